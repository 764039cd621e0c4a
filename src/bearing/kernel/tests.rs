//! The kernel against its scalar twin, and its regimes and margins.

use super::*;
use crate::bearing::RestitutionLaw;

/// Three balls with 10 mm clearance: along +x only ball 0 can be loaded.
pub(super) fn three_balls(model: DampingModel) -> BallSet {
    BallSet::new(&BearingParams {
        ball_count: 3,
        clearance: 10e-3,
        damping_model: model,
        ..BearingParams::default()
    })
}

/// Ball 0's deflection `d` (m) and approach speed `v` (m/s).
pub(super) fn at(d: f64, v: f64) -> ContactState {
    ContactState {
        e: [5e-3 + d, 0.0],
        v: [v, 0.0],
        ..ContactState::default()
    }
}

/// The latch takes the approach speed at the first loaded state of a contact,
/// keeps it while the ball stays loaded, and takes a new one (at least the
/// floor) at the next onset; the force is `K δ^{3/2} (1 + χ v / v₀)`.
#[test]
pub(super) fn latch_holds_the_onset_speed_for_the_whole_contact() {
    let law = RestitutionLaw::HuntCrossley;
    let chi = law.chi(0.8);
    let mut set = three_balls(DampingModel::Restitution {
        law,
        restitution: 0.8,
    });
    assert!(set.latches());
    let force = |set: &BallSet, d: f64, v: f64| set.ball(0, &at(d, v)).force;
    let hertz = |d: f64| 9.57e9 * d * d.sqrt();
    // Before any contact the coefficient is 0: pure Hertz. (The deflection is
    // rounded at the 5 mm offset, ~1e-12 relative: tolerances 1e-9.)
    assert!((force(&set, 1e-6, 0.3) - hertz(1e-6)).abs() <= 1e-9 * hertz(1e-6));
    set.latch(&at(1e-9, 0.05));
    let expected = hertz(2e-6) * (1.0 + chi * 0.2 / 0.05);
    assert!((force(&set, 2e-6, 0.2) - expected).abs() <= 1e-9 * expected);
    // Still in contact: a faster state does not re-latch.
    set.latch(&at(3e-6, 0.2));
    assert!((force(&set, 2e-6, 0.2) - expected).abs() <= 1e-9 * expected);
    // Out of contact, then a slow onset: the floor.
    set.latch(&at(-1e-9, -0.05));
    set.latch(&at(1e-9, 1e-5));
    let slow = hertz(2e-6) * (1.0 + chi * 0.2 / ONSET_SPEED_FLOOR);
    assert!((force(&set, 2e-6, 0.2) - slow).abs() <= 1e-9 * slow);
    // Continuous at onset, and never pulling: 0 at δ = 0 and when opening fast.
    assert_eq!(force(&set, 0.0, 5.0), 0.0);
    assert_eq!(force(&set, 2e-6, -1.0), 0.0);
}

/// The other laws do not latch, and latching leaves their forces alone.
#[test]
pub(super) fn laws_without_onset_speed_do_not_latch() {
    for model in [
        DampingModel::CompressionOnly,
        DampingModel::TwoSided,
        DampingModel::HuntCrossleyAlpha { alpha: 0.4 },
    ] {
        let mut set = three_balls(model);
        assert!(!set.latches());
        let before = set.ball(0, &at(2e-6, 0.1));
        set.latch(&at(1e-9, 0.05));
        assert_eq!(set.ball(0, &at(2e-6, 0.1)), before);
    }
    let set = three_balls(DampingModel::HuntCrossleyAlpha { alpha: 0.4 });
    let f = set.ball(0, &at(2e-6, 0.1)).force;
    let expected = 9.57e9 * 2e-6 * 2e-6f64.sqrt() * (1.0 + 0.4 * 0.1);
    assert!((f - expected).abs() <= 1e-9 * expected);
}

/// The SIMD kernel equals the scalar twin for a latched law with different
/// coefficients on different balls, under the natural law and a held regime.
#[test]
pub(super) fn hysteresis_kernel_matches_its_scalar_twin() {
    let params = BearingParams {
        ball_count: 11,
        damping_model: DampingModel::Restitution {
            law: RestitutionLaw::Flores,
            restitution: 0.7,
        },
        ..BearingParams::default()
    };
    let mut set = BallSet::new(&params);
    let state = |k: f64| ContactState {
        e: [30e-6 * (0.7 * k).cos(), 30e-6 * (0.7 * k).sin()],
        v: [0.02 * (1.3 * k).sin(), -0.03 * (0.4 * k).cos()],
        cage: 0.37 * k,
        psi_in: -0.2 * k,
        psi_out: 0.37 * k,
    };
    for k in 0..40 {
        set.latch(&state(f64::from(k)));
    }
    let s = state(40.5);
    let mut regime = set.no_regime();
    set.freeze(&s, None, &mut regime);
    let moved = state(40.55);
    for held in [None, Some(&regime)] {
        let sum = match held {
            None => set.force(&moved),
            Some(r) => set.force_in(&moved, r),
        };
        let (mut fx, mut fy, mut largest) = (0.0, 0.0, 0.0f64);
        for r in 0..set.len() {
            let b = set.ball_in(r, &moved, held);
            fx += b.force * b.normal[0];
            fy += b.force * b.normal[1];
            largest = largest.max(b.force.abs());
        }
        assert!(largest > 0.0);
        assert!((sum.force[0] - fx).abs() <= 1e-12 * largest, "{held:?}");
        assert!((sum.force[1] - fy).abs() <= 1e-12 * largest, "{held:?}");
    }
}

/// With a band `ε` a loaded ball stays loaded down to `δ = −ε`: the margin of the
/// held regime counts its exit from `−ε`, and a regime recorded inside the band
/// keeps it (and records no contact change); without the band it leaves at 0.
#[test]
pub(super) fn a_band_holds_a_loaded_ball_down_to_minus_epsilon() {
    let mut set = BallSet::new(&BearingParams::default());
    let state = |e: [f64; 2]| ContactState {
        e,
        v: [0.0, 0.0],
        cage: 0.0,
        psi_in: 0.0,
        psi_out: 0.0,
    };
    let n = set.ball(0, &state([0.0, 0.0])).normal;
    let origin = set.ball(0, &state([0.0, 0.0])).delta;
    // Ball 0's deflection is `origin + ρ` along its normal; the others stay open.
    let along = |delta: f64| state([(delta - origin) * n[0], (delta - origin) * n[1]]);
    let (band, inside) = (1e-10, -5e-11);
    assert!((set.ball(0, &along(inside)).delta - inside).abs() < 1e-13);
    for with_band in [false, true] {
        let mut regime = set.no_regime();
        if with_band {
            regime.set_band(band);
        }
        set.freeze(&along(1e-9), None, &mut regime);
        assert!(regime.loaded(0));
        assert_eq!(regime.recent_contact_changes(), 1);
        let margin = set.force_in(&along(inside), &regime).margin;
        assert_eq!(margin >= 0.0, with_band, "margin {margin:e}");
        assert!(set.force_in(&along(-2.0 * band), &regime).margin < 0.0);
        set.freeze(&along(inside), None, &mut regime);
        assert_eq!(regime.loaded(0), with_band);
        assert_eq!(
            regime.recent_contact_changes(),
            if with_band { 1 } else { 2 }
        );
    }
}
