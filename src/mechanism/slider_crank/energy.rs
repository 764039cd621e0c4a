//! The energy ledger (docs/model.md §3.8, §4.4): the mechanism's energies, and the
//! driver's work, the explicit time dependence and the dissipation as quadratures
//! riding along in the state.

use super::*;

impl SliderCrank {
    /// Reads the ledger from a state vector (zeros when the ledger is off).
    pub fn ledger(&self, y: &[f64]) -> Ledger {
        if !self.ledger {
            return Ledger::default();
        }
        let at = self.ledger_index();
        Ledger {
            driver_work: y[at],
            explicit_potential_work: y[at + 1],
            dissipated: y[at + 2],
        }
    }

    /// Where the ledger's quadratures start in the state: after `(ex, ey, ėx, ėy)`
    /// and the housing's `(hx, hy, ḣx, ḣy)` when there is one.
    pub(super) fn ledger_index(&self) -> usize {
        4 + self.housing.map_or(0, |_| HOUSING_LEN)
    }

    /// Kinetic and potential energy at time `t` (s) and state `y` (§3.8, with the
    /// housing's of §3.9); the potential uses the natural law (a ball is loaded when
    /// `δ > 0`).
    pub fn energy(&mut self, t: f64, y: &[f64]) -> Result<Energy, ModelError> {
        let k = &self.k;
        let motion = self.drive.motion(t);
        let crank = motion.angle;
        let (e, ed, p, pd) = if self.has_joint() {
            let (p, pd) = journal(&self.housing, y);
            ([y[0], y[1]], [y[2], y[3]], p, pd)
        } else {
            ([0.0; 2], [0.0; 2], [0.0; 2], [0.0; 2])
        };
        let kin = k.kinematics::<true>(crank.sin_cos(), &motion, p, pd)?;
        let (mut kinetic, gravity) = k.body_energies(&kin, motion.rate, p, pd);
        // The housing's displacement is measured from its rest position, where the
        // springs carry its weight: gravity's work on it and the springs' preload's
        // cancel (§3.9).
        let spring = match &self.housing {
            Some(h) => {
                kinetic += 0.5 * h.mass * (y[6] * y[6] + y[7] * y[7]);
                0.5 * h.stiffness * (y[4] * y[4] + y[5] * y[5])
            }
            None => 0.0,
        };
        let contact_potential = match &self.bearing {
            Some(w) => {
                let state = self.contact_state(crank, &kin, e, ed);
                (0..w.balls.len())
                    .map(|r| w.balls.ball(r, &state))
                    .filter(|b| b.delta > 0.0)
                    .map(|b| 0.4 * b.elastic * b.delta)
                    .sum()
            }
            None => self.journal_potential(y),
        };
        Ok(Energy {
            kinetic,
            potential: gravity + spring + contact_potential,
            contact_potential,
        })
    }

    /// The ledger's rates at `y` after [`SliderCrank::solve`] gave `motion`, `kin`
    /// and the journal's `pdd`: the driver's power `T θ̇2` (W), the bearing's
    /// `∂V/∂t` at fixed `e` (W) and its dissipation with the housing's `c_h |ḣ|²`
    /// (W), for the ball forces the right-hand side applied (the held regime's when
    /// `held`), ball by ball from the kernel's scalar twin.
    pub(super) fn ledger_rates<const VARYING: bool>(
        &self,
        motion: &CrankMotion,
        y: &[f64],
        kin: &Kinematics,
        pdd: [f64; 2],
        held: bool,
    ) -> [f64; 3] {
        let k = &self.k;
        let torque = k.driver_torque::<VARYING>(kin, &k.accelerations(kin, pdd), motion.accel);
        let omega = motion.rate;
        let Some(w) = self.bearing.as_ref() else {
            return [torque * omega, 0.0, 0.0];
        };
        let crank = motion.angle;
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let state = self.contact_state(crank, kin, e, ed);
        // Race rates: the journal turns with the crank (crank_ground), the rod
        // (crank_rod, θ̇3 = k_θ Ȧ_y) or the slider (rod_slider: not at all), the
        // housing with the ground, the crank or the rod.
        let rod_rate = || kin.k_theta * (ed[1] + k.l2 * omega * kin.u[0]);
        let (journal_rate, housing_rate) = match self.location {
            Location::CrankRod => (rod_rate(), omega),
            Location::RodSlider => (0.0, rod_rate()),
            _ => (omega, 0.0),
        };
        let cage_rate = w.weights.journal * journal_rate + w.weights.housing * housing_rate;
        let (psi_in_rate, psi_out_rate) = (cage_rate - journal_rate, cage_rate - housing_rate);
        let regime = held.then_some(&w.regime);
        let mut dissipation = self
            .housing
            .map_or(0.0, |h| h.damping * (y[6] * y[6] + y[7] * y[7]));
        let mut rate = 0.0;
        for r in 0..w.balls.len() {
            let b = w.balls.ball_in(r, &state, regime);
            let n = b.normal;
            // ∂δ_r/∂t at fixed e: the ball's direction turns with the cage, the
            // waviness under it with the ball's angle on each race.
            let delta_rate = cage_rate * (-e[0] * n[1] + e[1] * n[0])
                + b.slope_in * psi_in_rate
                + b.slope_out * psi_out_rate;
            rate += b.elastic * delta_rate;
            dissipation += (b.force - b.elastic) * b.approach;
        }
        [torque * omega, rate, dissipation]
    }
}

/// The journal's `p̈` (m/s²), the bearing force (N) and the ledger's rates of
/// [`OdeSystem::rhs`] with the ledger on, as a [`LaneTask`], with the crank's
/// acceleration terms when `VARYING`.
pub(super) struct LedgerTask<'a, const VARYING: bool> {
    pub(super) sys: &'a mut SliderCrank,
    pub(super) t: f64,
    pub(super) y: &'a [f64],
    pub(super) held: bool,
}

impl<const VARYING: bool> LaneTask for LedgerTask<'_, VARYING> {
    type Output = Result<([f64; 2], [f64; 2], [f64; LEDGER_LEN]), ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        let (motion, kin, sum, pdd) = self
            .sys
            .solve::<V, VARYING, false>(self.t, self.y, self.held)?;
        let rates = self
            .sys
            .ledger_rates::<VARYING>(&motion, self.y, &kin, pdd, self.held);
        Ok((pdd, sum.force, rates))
    }
}
