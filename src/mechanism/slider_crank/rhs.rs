//! The right-hand side: the crank's motion, the contact state of the bearing, the
//! 2×2 (or housed 4×4) d'Alembert solve for the accelerations, and the regime
//! machinery the event-locating integrators use.

use super::*;

/// The housing's acceleration `ḧ = (F − k_h h − c_h ḣ)/m_h` (m/s²) under bearing
/// force `f` (N) at displacement `h` (m) and velocity `hd` (m/s) (§3.9).
#[inline(always)]
pub(super) fn housing_acceleration(
    housing: &Housing,
    f: [f64; 2],
    h: [f64; 2],
    hd: [f64; 2],
) -> [f64; 2] {
    let Housing {
        mass,
        stiffness,
        damping,
    } = *housing;
    [
        (f[0] - stiffness * h[0] - damping * hd[0]) / mass,
        (f[1] - stiffness * h[1] - damping * hd[1]) / mass,
    ]
}

/// The journal centre's displacement `p = e + h` (m) and velocity (m/s) at state `y`
/// of a bearing case with `housing`, which the crank pivot follows: `e` and `ė`
/// without a housing (§3.9).
#[inline(always)]
pub(super) fn journal(housing: &Option<Housing>, y: &[f64]) -> ([f64; 2], [f64; 2]) {
    match housing {
        None => ([y[0], y[1]], [y[2], y[3]]),
        Some(_) => ([y[0] + y[4], y[1] + y[5]], [y[2] + y[6], y[3] + y[7]]),
    }
}

impl SliderCrank {
    /// Writes the rates of `(ex, ey, ėx, ėy)` and, with a housing, of
    /// `(hx, hy, ḣx, ḣy)` into `dydt` for the journal's acceleration `pdd` (m/s²)
    /// under bearing force `f` (N): `ë = p̈` without a housing, else `p̈ − ḧ` (§3.9).
    /// Returns how many rates it wrote.
    #[inline(always)]
    pub(super) fn mechanism_rates(
        &self,
        y: &[f64],
        pdd: [f64; 2],
        f: [f64; 2],
        dydt: &mut [f64],
    ) -> usize {
        match &self.housing {
            None => {
                dydt[..4].copy_from_slice(&[y[2], y[3], pdd[0], pdd[1]]);
                4
            }
            Some(h) => {
                let hdd = housing_acceleration(h, f, [y[4], y[5]], [y[6], y[7]]);
                dydt[..4 + HOUSING_LEN].copy_from_slice(&[
                    y[2],
                    y[3],
                    pdd[0] - hdd[0],
                    pdd[1] - hdd[1],
                    y[6],
                    y[7],
                    hdd[0],
                    hdd[1],
                ]);
                4 + HOUSING_LEN
            }
        }
    }

    /// The bearing's contact state at time `t` (s) and state `y` of a bearing case,
    /// and the crank angle (rad) then.
    pub(super) fn bearing_state(
        &self,
        t: f64,
        y: &[f64],
    ) -> Result<(ContactState, f64), ModelError> {
        let motion = self.drive.motion(t);
        let crank = motion.angle;
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let (p, pd) = journal(&self.housing, y);
        let kin = self.k.kinematics::<true>(crank.sin_cos(), &motion, p, pd)?;
        Ok((self.contact_state(crank, &kin, e, ed), crank))
    }

    /// The bearing's contact state at crank angle `crank` (rad) with kinematics `kin`.
    pub(super) fn contact_state(
        &self,
        crank: f64,
        kin: &Kinematics,
        e: [f64; 2],
        ed: [f64; 2],
    ) -> ContactState {
        let (journal, housing) = race_turns(self.location, crank, kin);
        let weights = self.bearing.as_ref().map_or(
            CageWeights {
                journal: 0.0,
                housing: 0.0,
            },
            |w| w.weights,
        );
        weights.contact_state(e, ed, journal, housing)
    }

    /// The crank's motion at `t` (s): `θ2 = ω t` at constant speed, else the drive's.
    #[inline(always)]
    pub(super) fn motion<const VARYING: bool>(&self, t: f64) -> CrankMotion {
        if VARYING {
            self.drive.motion(t)
        } else {
            CrankMotion {
                angle: self.k.omega * t,
                rate: self.k.omega,
                accel: 0.0,
            }
        }
    }

    /// Crank motion, kinematics, bearing force and the journal's acceleration `p̈`
    /// (`ë` without a housing, §3.9) at `(t, y)`, with the balls loaded as the held
    /// regime says if `held` (else by the sign of `δ`); no force and `p̈ = 0` for the
    /// ideal mechanism. Runs on lanes `V`, with the crank's
    /// acceleration terms when `VARYING`; with `RIGID` the caller has checked that
    /// the case has no housing, and the journal is `e` without looking. Inlined into
    /// each instruction set's version of its callers.
    #[inline(always)]
    pub(super) fn solve<V: Lanes, const VARYING: bool, const RIGID: bool>(
        &mut self,
        t: f64,
        y: &[f64],
        held: bool,
    ) -> Result<(CrankMotion, Kinematics, BallSum, [f64; 2]), ModelError> {
        let motion = self.motion::<VARYING>(t);
        let k = &self.k;
        let crank = motion.angle;
        let Some(w) = self.bearing.as_mut() else {
            return Ok((
                motion,
                k.kinematics::<VARYING>(crank.sin_cos(), &motion, [0.0; 2], [0.0; 2])?,
                BallSum::default(),
                [0.0; 2],
            ));
        };
        let &[ex, ey, vx, vy] = &y[..4] else {
            unreachable!("a bearing case has 4 state variables")
        };
        let (e, ed) = ([ex, ey], [vx, vy]);
        let (p, pd) = if RIGID {
            (e, ed)
        } else {
            journal(&self.housing, y)
        };
        let regime = held.then_some(&w.regime);
        let (kin, sum) = match self.location {
            // The bearing's angles follow the crank alone: one SIMD sin_cos for all.
            Location::CrankGround => {
                let state = w.weights.contact_state(e, ed, crank, 0.0);
                let (sum, trig) = w.balls.evaluate::<V>(&state, regime, Some(crank));
                (k.kinematics::<VARYING>(trig, &motion, p, pd)?, sum)
            }
            // The journal turns with the rod, whose angle needs the crank's first.
            _ => {
                let kin = k.kinematics::<VARYING>(crank.sin_cos(), &motion, p, pd)?;
                let (journal, housing) = race_turns(self.location, crank, &kin);
                let state = w.weights.contact_state(e, ed, journal, housing);
                (kin, w.balls.evaluate::<V>(&state, regime, None).0)
            }
        };
        w.margin = sum.margin;
        Ok((
            motion,
            kin,
            sum,
            k.eccentricity_acceleration(&kin, sum.force),
        ))
    }
}

impl OdeSystem for SliderCrank {
    fn dim(&self) -> usize {
        match (self.has_joint(), self.ledger) {
            (false, _) => 0,
            (true, false) => self.ledger_index(),
            (true, true) => self.ledger_index() + LEDGER_LEN,
        }
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        if self.bearing.is_none() {
            if self.journal.is_some() {
                return self.journal_rhs(t, y, dydt);
            }
            return Ok(());
        }
        let held = self.bearing.as_ref().is_some_and(|w| w.held);
        let (isa, varies) = (self.isa, self.drive.varies());
        // The common case first: no ledger, no housing.
        if !self.ledger && self.housing.is_none() {
            let (edd, _) = if varies {
                dispatch(isa, RhsTask::<true, true>::new(self, t, y, held))
            } else {
                dispatch(isa, RhsTask::<false, true>::new(self, t, y, held))
            }?;
            dydt.copy_from_slice(&[y[2], y[3], edd[0], edd[1]]);
            return Ok(());
        }
        if self.ledger {
            let (pdd, f, rates) = if varies {
                dispatch(
                    isa,
                    LedgerTask::<true> {
                        sys: self,
                        t,
                        y,
                        held,
                    },
                )
            } else {
                dispatch(
                    isa,
                    LedgerTask::<false> {
                        sys: self,
                        t,
                        y,
                        held,
                    },
                )
            }?;
            let at = self.mechanism_rates(y, pdd, f, dydt);
            dydt[at..at + LEDGER_LEN].copy_from_slice(&rates);
            return Ok(());
        }
        let (pdd, f) = if varies {
            dispatch(isa, RhsTask::<true, false>::new(self, t, y, held))
        } else {
            dispatch(isa, RhsTask::<false, false>::new(self, t, y, held))
        }?;
        self.mechanism_rates(y, pdd, f, dydt);
        Ok(())
    }

    /// Latches the approach speeds of balls, or of the plain journal, whose contact
    /// began (restitution-based damping laws only, docs/model.md §2.5); nothing else.
    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        self.journal_regime(y, false);
        if self.bearing.as_ref().is_some_and(|w| w.balls.latches()) {
            let (state, _) = self.bearing_state(t, y)?;
            if let Some(w) = self.bearing.as_mut() {
                w.balls.latch(&state);
            }
        }
        Ok(())
    }

    fn hold_regime(&mut self, t: f64, y: &[f64]) -> Result<bool, ModelError> {
        if self.bearing.is_none() {
            self.journal_regime(y, true);
            return Ok(self.journal.is_some());
        }
        let (state, crank) = self.bearing_state(t, y)?;
        let angle = (self.location == Location::CrankGround).then_some(crank);
        let Some(w) = self.bearing.as_mut() else {
            return Ok(false);
        };
        // A located onset latches its approach speed before the regime's
        // damping branches are recorded from it.
        w.balls.latch(&state);
        w.balls.freeze(&state, angle, &mut w.regime);
        w.held = true;
        Ok(true)
    }

    fn release_regime(&mut self) {
        if let Some(w) = self.bearing.as_mut() {
            w.held = false;
        }
        self.journal_release();
    }

    fn margin(&self) -> f64 {
        match &self.bearing {
            Some(w) => w.margin,
            None => self.journal_margin().unwrap_or(f64::INFINITY),
        }
    }

    /// When at least [`CHATTER_SWITCHES`] of the last 64 regimes recorded changed
    /// the loaded set (the chatter is of contact onsets and exits, not of damping or
    /// defect-zone switches), gives the contacts the band
    /// `ε = atol + rtol·max(|e_x|, |e_y|)` (m) at `y`: the error the integrator lets
    /// the eccentricity make in a step, a length it cannot resolve. A loaded ball
    /// then leaves contact at `δ_r = −ε` instead of 0 (docs/model.md §8.8).
    fn settle_chatter(&mut self, y: &[f64], rtol: f64, atol: f64) -> bool {
        let Some(w) = self.bearing.as_mut() else {
            return false;
        };
        if w.regime.recent_contact_changes() < CHATTER_SWITCHES {
            return false;
        }
        w.regime
            .set_band((atol + rtol * y[0].abs().max(y[1].abs())).min(MAX_BAND));
        true
    }
}

/// The journal's `p̈` (m/s², [`SliderCrank::solve`]) and the bearing force (N) of
/// [`OdeSystem::rhs`] as a [`LaneTask`], with the crank's acceleration terms when
/// `VARYING`, for a case without a housing when `RIGID`.
pub(super) struct RhsTask<'a, const VARYING: bool, const RIGID: bool> {
    pub(super) sys: &'a mut SliderCrank,
    pub(super) t: f64,
    pub(super) y: &'a [f64],
    pub(super) held: bool,
}

impl<'a, const VARYING: bool, const RIGID: bool> RhsTask<'a, VARYING, RIGID> {
    /// The task at `(t, y)` with the regime held when `held`.
    pub(super) fn new(sys: &'a mut SliderCrank, t: f64, y: &'a [f64], held: bool) -> Self {
        Self { sys, t, y, held }
    }
}

impl<const VARYING: bool, const RIGID: bool> LaneTask for RhsTask<'_, VARYING, RIGID> {
    type Output = Result<([f64; 2], [f64; 2]), ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        let (_, _, sum, pdd) = self
            .sys
            .solve::<V, VARYING, RIGID>(self.t, self.y, self.held)?;
        Ok((pdd, sum.force))
    }
}
