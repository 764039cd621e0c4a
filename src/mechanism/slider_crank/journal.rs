//! The plain journal at the location (docs/model.md §2.10, §3.10): the dry or
//! lubricated joint's force and moments in the reduced equations, its energy terms,
//! its samples and its contact regime.
//!
//! The state's `e` is the location's eccentricity (crank_ground: crank pivot minus
//! ground; crank_rod: rod eye minus crank pin; rod_slider: slider pin minus rod
//! eye). The journal is the crank's pin at crank_ground and crank_rod and the
//! slider's pin at rod_slider; the bushing is the ground (or the housing), the rod's
//! big-end eye, the rod's small-end eye. The joint's eccentricity (journal minus
//! bushing centre) is `σ e`, `σ = −1` at crank_rod and `+1` elsewhere.

use crate::bearing::LawSetup;
use crate::joint::{DryContact, Film, JointForce, JointMotion, LubricatedJoint, FILM_LIMIT};
use crate::mechanism::{JointKind, JournalParams};

use super::*;

/// The joint's force law.
#[derive(Debug, Clone)]
enum Law {
    Dry(DryContact),
    Lubricated(LubricatedJoint),
}

impl Law {
    fn dry(&self) -> &DryContact {
        match self {
            Law::Dry(d) => d,
            Law::Lubricated(l) => l.dry(),
        }
    }
}

/// A plain journal at its location, with its contact regime.
#[derive(Debug, Clone)]
pub(super) struct Journal {
    law: Law,
    /// `σ` (–): the joint's eccentricity is `σ e`.
    sign: f64,
    /// Whether the journal touches the bushing while an integrator holds the
    /// regime ([`OdeSystem::hold_regime`]); `None` under the natural law.
    held: Option<bool>,
    /// Switching margin of the latest right-hand side (m): `δ` held in contact,
    /// `−δ` held out of it, `+∞` under the natural law.
    margin: f64,
}

impl Journal {
    /// The journal of `kind` with `params` at `location`, with the contact law `law`.
    pub(super) fn new(
        kind: JointKind,
        params: &JournalParams,
        law: LawSetup,
        location: Location,
    ) -> Self {
        let dry = DryContact::new(
            params.geometry,
            params.contact_stiffness(),
            law,
            params.friction,
        );
        let law = match kind {
            JointKind::Lubricated => {
                let film = Film::new(params.geometry, params.viscosity, FILM_LIMIT);
                Law::Lubricated(LubricatedJoint::new(film, dry))
            }
            _ => Law::Dry(dry),
        };
        Self {
            law,
            sign: if location == Location::CrankRod {
                -1.0
            } else {
                1.0
            },
            held: None,
            margin: f64::INFINITY,
        }
    }

    /// The joint's relative motion at `e` (m) and `ė` (m/s) with the journal's and
    /// the bushing's angular velocities `rates` (rad/s).
    fn motion(&self, e: [f64; 2], ed: [f64; 2], rates: [f64; 2]) -> JointMotion {
        let s = self.sign;
        JointMotion {
            e: [s * e[0], s * e[1]],
            v: [s * ed[0], s * ed[1]],
            journal_rate: rates[0],
            bushing_rate: rates[1],
        }
    }

    /// The force under the held regime (or the natural law).
    fn force(&self, motion: &JointMotion) -> JointForce {
        match &self.law {
            Law::Dry(d) => d.force_in(motion, self.held),
            Law::Lubricated(l) => l.force_in(motion, self.held),
        }
    }
}

/// What the journal's solve gives at one `(t, y)`.
pub(super) struct JournalSolve {
    motion: CrankMotion,
    kin: Kinematics,
    /// The joint's force and moments.
    joint: JointForce,
    /// The force on the body `e` is measured from (N, global): the bushing's at
    /// crank_ground and rod_slider, the journal's at crank_rod.
    housing_force: [f64; 2],
    /// The journal's `p̈` (m/s²).
    pdd: [f64; 2],
    /// The joint's moments on the crank and on the rod (N m).
    crank_moment: f64,
    rod_moment: f64,
}

impl SliderCrank {
    /// The plain journal of `case` at its location, `None` for a ball bearing or the
    /// ideal mechanism.
    pub(super) fn plain_journal(case: &CaseParams) -> Option<Journal> {
        (case.location != Location::Ideal && case.joint.is_plain()).then(|| {
            let law = LawSetup::of(case.bearing.damping_model, case.bearing.damping);
            Journal::new(case.joint, &case.journal, law, case.location)
        })
    }

    /// The journal's and the bushing's angular velocities (rad/s) at crank rate
    /// `omega` with the rod's `θ̇3 = rod_rate`.
    fn body_rates(&self, omega: f64, rod_rate: f64) -> [f64; 2] {
        match self.location {
            Location::CrankGround => [omega, 0.0],
            Location::CrankRod => [omega, rod_rate],
            _ => [0.0, rod_rate],
        }
    }

    /// Crank motion, kinematics, the joint's force and the journal's acceleration at
    /// `(t, y)` of a case with a plain journal (docs/model.md §3.10): the joint's
    /// virtual work `σ F·δe + M_j δθ_j + M_b δθ_b` adds `−σF` to the bearing force of
    /// the reduced equations and the rod's moment `k_θ M_rod` to the `e_y` equation.
    pub(super) fn journal_solve(&mut self, t: f64, y: &[f64]) -> Result<JournalSolve, ModelError> {
        let motion = self.drive.motion(t);
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let (p, pd) = journal(&self.housing, y);
        let kin = self
            .k
            .kinematics::<true>(motion.angle.sin_cos(), &motion, p, pd)?;
        let rod_rate = kin.k_theta * (pd[1] + self.k.l2 * motion.rate * kin.u[0]);
        let rates = self.body_rates(motion.rate, rod_rate);
        let location = self.location;
        let Some(j) = self.journal.as_mut() else {
            unreachable!("journal_solve runs for a plain journal")
        };
        let jm = j.motion(e, ed, rates);
        let joint = j.force(&jm);
        if let Some(held) = j.held {
            let delta = j.law.dry().penetration(&jm);
            j.margin = if held { delta } else { -delta };
        }
        let s = j.sign;
        let housing_force = [-s * joint.force[0], -s * joint.force[1]];
        let (crank_moment, rod_moment) = match location {
            Location::CrankGround => (joint.journal_moment, 0.0),
            Location::CrankRod => (joint.journal_moment, joint.bushing_moment),
            _ => (0.0, joint.bushing_moment),
        };
        let generalised = [
            housing_force[0],
            housing_force[1] - kin.k_theta * rod_moment,
        ];
        let pdd = self.k.eccentricity_acceleration(&kin, generalised);
        Ok(JournalSolve {
            motion,
            kin,
            joint,
            housing_force,
            pdd,
            crank_moment,
            rod_moment,
        })
    }

    /// [`OdeSystem::rhs`] of a case with a plain journal, with the ledger's rates
    /// when it is on.
    pub(super) fn journal_rhs(
        &mut self,
        t: f64,
        y: &[f64],
        dydt: &mut [f64],
    ) -> Result<(), ModelError> {
        let s = self.journal_solve(t, y)?;
        let at = self.mechanism_rates(y, s.pdd, s.housing_force, dydt);
        if self.ledger {
            let torque = self.journal_torque(&s);
            let damping = self
                .housing
                .map_or(0.0, |h| h.damping * (y[6] * y[6] + y[7] * y[7]));
            let j = &s.joint;
            let dissipated =
                j.damping_dissipation + j.friction_dissipation - j.film_power + damping;
            dydt[at..at + LEDGER_LEN].copy_from_slice(&[torque * s.motion.rate, 0.0, dissipated]);
        }
        Ok(())
    }

    /// The driver torque (N m) with the joint's moments: d'Alembert over `δθ2` at
    /// fixed `e`, under which the crank turns by `δθ2` and the rod by
    /// `k_θ L2 cos θ2 δθ2`.
    fn journal_torque(&self, s: &JournalSolve) -> f64 {
        let k = &self.k;
        let acc = k.accelerations(&s.kin, s.pdd);
        k.driver_torque::<true>(&s.kin, &acc, s.motion.accel)
            - s.crank_moment
            - s.rod_moment * s.kin.k_theta * k.l2 * s.kin.u[0]
    }

    /// The samples of a case with a plain journal ([`SliderCrank::sample`]).
    pub(super) fn journal_sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        let saved = self.journal.as_mut().and_then(|j| j.held.take());
        let solved = self.journal_solve(t, y);
        if let Some(j) = self.journal.as_mut() {
            j.held = saved;
        }
        let s = solved?;
        let parts = SampleParts {
            kin: s.kin,
            pdd: s.pdd,
            force: s.housing_force,
            loaded: usize::from(s.joint.normal > 0.0),
        };
        let mut sample = self.outputs(parts, y, s.rod_moment);
        sample.crank_moment = self.journal_torque(&s);
        Ok(sample)
    }

    /// The journal's latching and regime at `(t, y)`: latches the contact law's onset
    /// speed, and with `hold` holds the contact as it is there.
    pub(super) fn journal_regime(&mut self, y: &[f64], hold: bool) {
        let (e, ed) = ([y[0], y[1]], [y[2], y[3]]);
        let Some(j) = self.journal.as_mut() else {
            return;
        };
        let jm = j.motion(e, ed, [0.0; 2]);
        match &mut j.law {
            Law::Dry(d) => d.latch(&jm),
            Law::Lubricated(l) => l.latch(&jm),
        }
        if hold {
            j.held = Some(j.law.dry().touches(&jm));
            j.margin = f64::INFINITY;
        }
    }

    /// Back to the natural law.
    pub(super) fn journal_release(&mut self) {
        if let Some(j) = self.journal.as_mut() {
            j.held = None;
            j.margin = f64::INFINITY;
        }
    }

    /// The switching margin of the latest right-hand side (m).
    pub(super) fn journal_margin(&self) -> Option<f64> {
        self.journal.as_ref().map(|j| j.margin)
    }

    /// The joint's elastic potential `0.4 K δ^{5/2}` (J) at state `y` (natural law).
    pub(super) fn journal_potential(&self, y: &[f64]) -> f64 {
        let Some(j) = self.journal.as_ref() else {
            return 0.0;
        };
        let jm = j.motion([y[0], y[1]], [0.0; 2], [0.0; 2]);
        let delta = j.law.dry().penetration(&jm);
        if delta > 0.0 {
            0.4 * j.law.dry().force(&jm).elastic * delta
        } else {
            0.0
        }
    }
}
