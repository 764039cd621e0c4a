//! The characteristic frequencies of the bearing (docs/model.md §7.3): cage, outer and
//! inner ball pass, ball spin, from the raceway diameters and the races' mean speeds
//! at the case's location.

use crate::mechanism::{CaseParams, Location};

/// A case's characteristic bearing frequencies (Hz, ≥ 0); NaN for the ideal
/// mechanism, which has no bearing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FaultFrequencies {
    /// Cage (fundamental train frequency) `|ω̄_m|/2π`.
    pub ftf: f64,
    /// Ball pass frequency of the outer race, `N_b |ω̄_m − ω̄_o|/2π`.
    pub bpfo: f64,
    /// Ball pass frequency of the inner race, `N_b |ω̄_i − ω̄_m|/2π`.
    pub bpfi: f64,
    /// Ball spin frequency relative to the cage, `(d_m/2D)(1 − (D/d_m)²) |ω̄_i − ω̄_o|/2π`.
    pub bsf: f64,
}

impl FaultFrequencies {
    /// The metric names, in [`FaultFrequencies::values`] order.
    pub const NAMES: [&'static str; 4] = ["ftf", "bpfo", "bpfi", "bsf"];

    /// The frequencies of `params` (docs/model.md §7.3): the mean race speeds are
    /// `ω̄_i = ω`, `ω̄_o = 0` at crank_ground and `ω̄_i = 0` (the rod's mean),
    /// `ω̄_o = ω` at crank_rod, `ω = 2π rpm/60`; the cage turns at
    /// `ω̄_m = (ω̄_i d_i + ω̄_o d_o)/(d_i + d_o)`; `D = (d_o − d_i)/2` and
    /// `d_m = (d_i + d_o)/2`; with a contact angle `φ`, `γ = (D/d_m) cos φ` and
    /// `ω̄_m = (ω̄_i (1 − γ) + ω̄_o (1 + γ))/2` (at `φ = 0` the form above), the ball
    /// spin `(d_m/2D)(1 − γ²) |ω̄_i − ω̄_o|/2π`. A varying crank speed gives NaN: its lines move with
    /// the speed (a profile that stays at one speed counts as that speed).
    pub fn of(params: &CaseParams) -> Self {
        Self::at_rpm(params, params.constant_rpm().unwrap_or(f64::NAN))
    }

    /// The metric names of [`FaultFrequencies::orders`], in
    /// [`FaultFrequencies::values`] order.
    pub const ORDER_NAMES: [&'static str; 4] =
        ["ftf_order", "bpfo_order", "bpfi_order", "bsf_order"];

    /// The same quantities as orders (cycles per crank revolution, docs/model.md
    /// §7.3): the frequencies at one revolution per second, 60 rev/min. Every one
    /// is proportional to the crank speed, so they hold at any speed, varying or not.
    pub fn orders(params: &CaseParams) -> Self {
        Self::at_rpm(params, 60.0)
    }

    /// The frequencies of `params` with the crank at `rpm` (rev/min).
    fn at_rpm(params: &CaseParams, rpm: f64) -> Self {
        let omega = std::f64::consts::TAU * rpm / 60.0;
        // The rod turns back and forth against the slider: no steady race speed at
        // rod_slider; a plain journal has no balls.
        let (wi, wo) = match params.location {
            _ if params.joint.is_plain() => (f64::NAN, f64::NAN),
            Location::CrankGround => (omega, 0.0),
            Location::CrankRod => (0.0, omega),
            Location::RodSlider | Location::Ideal => (f64::NAN, f64::NAN),
        };
        let b = &params.bearing;
        let (di, d_o) = (b.inner_race_diameter, b.outer_race_diameter);
        let ratio = (d_o - di) / (d_o + di);
        // γ = (D/d_m) cos φ: the contact points' radii are d_m(1 ∓ γ)/2.
        let gamma = ratio * b.contact_angle.cos();
        let wm = 0.5 * (wi * (1.0 - gamma) + wo * (1.0 + gamma));
        let nb = b.ball_count as f64;
        let hz = 1.0 / std::f64::consts::TAU;
        Self {
            ftf: wm.abs() * hz,
            bpfo: nb * (wm - wo).abs() * hz,
            bpfi: nb * (wi - wm).abs() * hz,
            bsf: (1.0 - gamma * gamma) / (2.0 * ratio) * (wi - wo).abs() * hz,
        }
    }

    /// `[ftf, bpfo, bpfi, bsf]`.
    pub fn values(&self) -> [f64; 4] {
        [self.ftf, self.bpfo, self.bpfi, self.bsf]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paper_bearing_at_300_rpm() {
        // docs/model.md §7.3: f = 5 Hz, d_i = 29.2 mm, d_o = 46.6 mm, 9 balls.
        let mut p = CaseParams {
            rpm: 300.0,
            location: Location::CrankGround,
            ..CaseParams::default()
        };
        p.bearing.ball_count = 9;
        let f = FaultFrequencies::of(&p);
        let (di, d_o) = (p.bearing.inner_race_diameter, p.bearing.outer_race_diameter);
        let cage = 5.0 * di / (di + d_o);
        assert!((f.ftf - cage).abs() < 1e-12 && (f.ftf - 1.926).abs() < 1e-3);
        assert!((f.bpfo - 9.0 * cage).abs() < 1e-12);
        assert!((f.bpfi - 9.0 * (5.0 - cage)).abs() < 1e-12);
        // The textbook forms with D = 8.7 mm, d_m = 37.9 mm, contact angle 0.
        let (big_d, dm) = (0.5 * (d_o - di), 0.5 * (d_o + di));
        assert!((f.bpfo - 9.0 / 2.0 * 5.0 * (1.0 - big_d / dm)).abs() < 1e-12);
        assert!((f.bpfi - 9.0 / 2.0 * 5.0 * (1.0 + big_d / dm)).abs() < 1e-12);
        let bsf = dm / (2.0 * big_d) * 5.0 * (1.0 - (big_d / dm).powi(2));
        assert!((f.bsf - bsf).abs() < 1e-12, "{} vs {bsf}", f.bsf);
        // At crank_rod the outer race turns: cage at the outer race's share, the
        // pass frequencies unchanged.
        p.location = Location::CrankRod;
        let g = FaultFrequencies::of(&p);
        assert!((g.ftf - 5.0 * d_o / (di + d_o)).abs() < 1e-12);
        assert!((g.bpfo - f.bpfo).abs() < 1e-12 && (g.bpfi - f.bpfi).abs() < 1e-12);
        assert!((g.bsf - f.bsf).abs() < 1e-12);
        // Orders are the frequencies over the crank's 5 rev/s, and hold for a
        // run-up too.
        let o = FaultFrequencies::orders(&p);
        for (order, hz) in o.values().iter().zip(g.values()) {
            assert!((order - hz / 5.0).abs() < 1e-12, "{order} vs {hz} Hz");
        }
        p.speed = Some(crate::mechanism::SpeedProfile::Ramp {
            from: 300.0,
            to: 900.0,
            over: 1.0,
        });
        assert!(FaultFrequencies::of(&p).values().iter().all(|v| v.is_nan()));
        assert_eq!(FaultFrequencies::orders(&p), o);
        p.location = Location::Ideal;
        assert!(FaultFrequencies::of(&p).values().iter().all(|v| v.is_nan()));
        assert!(FaultFrequencies::orders(&p)
            .values()
            .iter()
            .all(|v| v.is_nan()));
    }
}
