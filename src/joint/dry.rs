//! The dry clearance joint of docs/model.md §2.10: Hertz-type normal force with the
//! bearing's damping laws, and modified Coulomb friction.

use crate::bearing::{latched_rate, LawSetup};

use super::{JointForce, JointMotion, JournalGeometry};

/// An isotropic elastic material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Young's modulus `E` (Pa), > 0.
    pub youngs_modulus: f64,
    /// Poisson's ratio `ν`, in (−1, 0.5).
    pub poisson_ratio: f64,
}

impl Material {
    /// The material's compliance `σ = (1 − ν²)/E` (1/Pa).
    fn compliance(&self) -> f64 {
        (1.0 - self.poisson_ratio * self.poisson_ratio) / self.youngs_modulus
    }
}

/// The contact stiffness `K = (4/3) E* √R` (N/m^1.5) of the journal in its bushing,
/// as Flores, Ambrósio, Claro & Lankarani (2007) apply Hertz's law to the revolute
/// clearance joint: `1/E* = σ_j + σ_b` with `σ = (1 − ν²)/E` of journal and bushing,
/// and the equivalent radius of the conforming pair `R = R_b R_j / (R_b − R_j)`
/// (m; `R_b − R_j = c`).
pub fn cylinder_stiffness(geometry: &JournalGeometry, journal: Material, bushing: Material) -> f64 {
    let radius = geometry.bushing_radius() * geometry.radius / geometry.clearance;
    let modulus = 1.0 / (journal.compliance() + bushing.compliance());
    4.0 / 3.0 * modulus * radius.sqrt()
}

/// Modified Coulomb friction with Ambrósio's dynamic correction (Ambrósio 2003):
/// `F_t = −μ c_d F_n v_t/|v_t|`, with `c_d` 0 up to the stick speed, 1 from the slip
/// speed on, linear between.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Friction {
    /// Coefficient of friction `μ` (–), ≥ 0.
    pub coefficient: f64,
    /// `v_0` (m/s), ≥ 0: no friction at slip speeds up to it.
    pub stick_speed: f64,
    /// `v_1` (m/s), ≥ `v_0`: full friction from it on.
    pub slip_speed: f64,
}

impl Friction {
    /// Ambrósio's correction `c_d` (–) at slip speed `slip` (m/s):
    /// 0 for `|v_t| ≤ v_0`, `(|v_t| − v_0)/(v_1 − v_0)` between, 1 for `|v_t| ≥ v_1`.
    pub fn correction(&self, slip: f64) -> f64 {
        let speed = slip.abs();
        if speed <= self.stick_speed {
            0.0
        } else if speed >= self.slip_speed {
            1.0
        } else {
            (speed - self.stick_speed) / (self.slip_speed - self.stick_speed)
        }
    }

    /// Friction force `F_t = −μ c_d F_n sign(v_t)` (N) on the journal along `t`, for
    /// the normal force `normal` (N) and slip speed `slip` (m/s).
    pub fn force(&self, normal: f64, slip: f64) -> f64 {
        -self.coefficient * self.correction(slip) * normal * slip.signum()
    }
}

/// The dry clearance joint: its geometry, stiffness, contact law with the latched
/// onset speed, and friction.
#[derive(Debug, Clone, PartialEq)]
pub struct DryContact {
    geometry: JournalGeometry,
    stiffness: f64,
    law: LawSetup,
    /// The hysteresis laws' rate coefficient `c` (s/m) of the current contact.
    rate: f64,
    /// Whether the journal was in contact at the last [`DryContact::latch`].
    in_contact: bool,
    friction: Friction,
}

impl DryContact {
    /// A joint of `geometry` with contact stiffness `stiffness` (N/m^1.5; e.g.
    /// [`cylinder_stiffness`], or one given), the contact law `law` (the bearing's
    /// [`LawSetup`]) and `friction`.
    pub fn new(
        geometry: JournalGeometry,
        stiffness: f64,
        law: LawSetup,
        friction: Friction,
    ) -> Self {
        Self {
            geometry,
            stiffness,
            law,
            rate: law.rate,
            in_contact: false,
            friction,
        }
    }

    /// Latches the approach speed at a contact onset, as [`crate::bearing::BallSet::latch`]
    /// does for a ball: a restitution-based law takes `c = χ/max(δ̇, v_floor)` when
    /// the journal is in contact at `motion` and was not at the previous call. To be
    /// called at every accepted step end and regime hold (docs/model.md §2.5).
    pub fn latch(&mut self, motion: &JointMotion) {
        let Some(chi) = self.law.chi else {
            return;
        };
        let k = self.geometry.contact(motion);
        if k.penetration > 0.0 {
            if !self.in_contact {
                self.rate = latched_rate(chi, k.approach);
                self.in_contact = true;
            }
        } else {
            self.in_contact = false;
        }
    }

    /// The joint's force at `motion`: zero while `δ ≤ 0`; in contact the normal force
    /// `F_n` of the contact law on `K δ^{3/2}` and `δ̇`, along `−n` on the journal,
    /// and the friction force `F_t` along `t` at the contact point.
    pub fn force(&self, motion: &JointMotion) -> JointForce {
        self.force_in(motion, None)
    }

    /// Whether the journal touches the bushing at `motion` (`δ > 0`).
    pub fn touches(&self, motion: &JointMotion) -> bool {
        self.geometry.contact(motion).penetration > 0.0
    }

    /// The penetration `δ` (m) at `motion`: the switching surface of the contact.
    pub fn penetration(&self, motion: &JointMotion) -> f64 {
        self.geometry.contact(motion).penetration
    }

    /// [`DryContact::force`] with the contact held (docs/model.md §8.4): `None`
    /// picks it from the sign of `δ`; `Some(false)` applies no force; `Some(true)`
    /// continues the contact's law smoothly past `δ = 0` with the elastic part
    /// `K δ |δ|^{1/2}`, so that an integrator can locate the exit.
    pub fn force_in(&self, motion: &JointMotion, held: Option<bool>) -> JointForce {
        let k = self.geometry.contact(motion);
        let delta = k.penetration;
        if !held.unwrap_or(delta > 0.0) {
            return JointForce::default();
        }
        let elastic = self.stiffness * delta * delta.abs().sqrt();
        let normal = self.law.law.force(elastic, k.approach, self.rate);
        let friction = self.friction.force(normal, k.slip);
        let [n, t] = [k.normal, k.tangent];
        JointForce {
            force: [
                -normal * n[0] + friction * t[0],
                -normal * n[1] + friction * t[1],
            ],
            journal_moment: self.geometry.radius * friction,
            bushing_moment: -self.geometry.bushing_radius() * friction,
            normal,
            elastic,
            friction,
            damping_dissipation: (normal - elastic) * k.approach,
            friction_dissipation: -friction * k.slip,
            film_power: 0.0,
        }
    }
}
