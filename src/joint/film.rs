//! The lubricated clearance joint of docs/model.md §2.10: the short-bearing (Ocvirk)
//! film force of a dynamically loaded journal, with half-Sommerfeld cavitation, and
//! the dry contact beyond the film limit.

use std::f64::consts::{PI, TAU};

use super::{DryContact, JointForce, JointMotion, JournalGeometry};

/// The default film limit: the eccentricity ratio `ε_f` above which the film force
/// is held at its value for `ε_f` (docs/model.md §2.10).
pub const FILM_LIMIT: f64 = 0.95;

/// The short-bearing film of a plain journal bearing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Film {
    geometry: JournalGeometry,
    viscosity: f64,
    limit: f64,
}

impl Film {
    /// A film of dynamic viscosity `viscosity` (Pa s) in a bearing of `geometry`,
    /// whose eccentricity ratio enters the film force capped at `limit` (–, in
    /// (0, 1); [`FILM_LIMIT`] by default).
    pub fn new(geometry: JournalGeometry, viscosity: f64, limit: f64) -> Self {
        Self {
            geometry,
            viscosity,
            limit,
        }
    }

    /// The film's force on the journal at `motion` (N, global, through the journal
    /// centre), and its power `F·ė` (W):
    /// `F = −(μ_v R L³/c²) ∫ G(θ)/(1 + ε cos θ)³ (cos θ n + sin θ t) dθ` over the
    /// half film `θ₁ < θ < θ₁ + π` where `G = −ε(ω̄ − φ̇) sin θ + ε̇ cos θ < 0`
    /// (the pressure positive), `θ` measured from the widest gap (`−n`)
    /// counter-clockwise, `ω̄ = (ω_j + ω_b)/2`, `ε` capped at the film limit.
    pub fn force(&self, motion: &JointMotion) -> JointForce {
        let g = &self.geometry;
        let k = g.contact(motion);
        let c = g.clearance;
        let eps = (k.eccentricity / c).min(self.limit);
        // ε_f/ε: the orbit speed ε φ̇ c enters as ε_f φ̇ c.
        let held = if k.eccentricity > 0.0 {
            eps * c / k.eccentricity
        } else {
            1.0
        };
        let mean = 0.5 * (motion.journal_rate + motion.bushing_rate);
        let wedge = eps * mean - held * k.orbit_speed / c;
        let squeeze = k.approach / c;
        if wedge == 0.0 && squeeze == 0.0 {
            return JointForce::default();
        }
        let [ss, sc, cc] = half_film_integrals(eps, squeeze.atan2(wedge));
        let scale = self.viscosity * g.radius * g.length.powi(3) / (c * c);
        let radial = -scale * (squeeze * cc - wedge * sc);
        let tangential = -scale * (squeeze * sc - wedge * ss);
        let [n, t] = [k.normal, k.tangent];
        let force = [
            radial * n[0] + tangential * t[0],
            radial * n[1] + tangential * t[1],
        ];
        JointForce {
            force,
            film_power: force[0] * motion.v[0] + force[1] * motion.v[1],
            ..JointForce::default()
        }
    }
}

/// `[∫ sin²θ, ∫ sin θ cos θ, ∫ cos²θ] / (1 + ε cos θ)³ dθ` over `θ₁ < θ < θ₁ + π`,
/// in closed form through Sommerfeld's substitution
/// `cos γ = (ε + cos θ)/(1 + ε cos θ)`, `sin γ = √(1−ε²) sin θ/(1 + ε cos θ)`,
/// under which the integrands become `sin²γ (1−ε²)^{−3/2}`,
/// `sin γ (cos γ − ε) (1−ε²)^{−2}` and `(cos γ − ε)² (1−ε²)^{−5/2}`.
fn half_film_integrals(eps: f64, theta1: f64) -> [f64; 3] {
    let root = (1.0 - eps * eps).sqrt();
    // Antiderivatives in γ of sin²γ, sin γ (cos γ − ε), (cos γ − ε)².
    let primitives = |theta: f64| {
        let (s, c) = theta.sin_cos();
        let d = 1.0 + eps * c;
        let (sin_g, cos_g) = (root * s / d, (eps + c) / d);
        // γ − θ is 2π-periodic and within (−π, π): unwrap γ to follow θ.
        let offset = sin_g.atan2(cos_g) - theta;
        let gamma = theta + offset - TAU * (offset / TAU).round();
        let half_sc = 0.5 * sin_g * cos_g;
        [
            0.5 * gamma - half_sc,
            0.5 * sin_g * sin_g + eps * cos_g,
            (0.5 + eps * eps) * gamma + half_sc - 2.0 * eps * sin_g,
        ]
    };
    let (a, b) = (primitives(theta1), primitives(theta1 + PI));
    let w = 1.0 - eps * eps;
    [
        (b[0] - a[0]) / (w * root),
        (b[1] - a[1]) / (w * w),
        (b[2] - a[2]) / (w * w * root),
    ]
}

/// A lubricated clearance joint: the [`Film`]'s force, plus the [`DryContact`]'s
/// once the journal reaches the bushing (`δ > 0`).
#[derive(Debug, Clone, PartialEq)]
pub struct LubricatedJoint {
    film: Film,
    dry: DryContact,
}

impl LubricatedJoint {
    /// The joint of `film` with the dry contact `dry` of the same geometry.
    pub fn new(film: Film, dry: DryContact) -> Self {
        Self { film, dry }
    }

    /// Latches the dry contact's onset speed ([`DryContact::latch`]).
    pub fn latch(&mut self, motion: &JointMotion) {
        self.dry.latch(motion);
    }

    /// The film's force plus the dry contact's at `motion`: the force, moments and
    /// dissipation rates of [`DryContact::force`] with the film force added to
    /// `force` and its power in `film_power`.
    pub fn force(&self, motion: &JointMotion) -> JointForce {
        self.force_in(motion, None)
    }

    /// The dry contact of the joint.
    pub fn dry(&self) -> &DryContact {
        &self.dry
    }

    /// [`LubricatedJoint::force`] with the dry contact held as
    /// [`DryContact::force_in`] holds it.
    pub fn force_in(&self, motion: &JointMotion, held: Option<bool>) -> JointForce {
        let film = self.film.force(motion);
        let mut total = self.dry.force_in(motion, held);
        total.force[0] += film.force[0];
        total.force[1] += film.force[1];
        total.film_power = film.film_power;
        total
    }
}
