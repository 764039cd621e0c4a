//! The instruction set does not change a single bit: the right-hand side, the margin
//! and every output sample of the production model on AVX (chosen at run time on
//! CPUs that have it) equal the baseline SSE2 ones bit for bit, in random scenes
//! (both locations, every damping law, waviness on either race, gravity, 3–40
//! balls) at random states, under the natural law and under a held regime. So a
//! whole run, which is a sequence of such evaluations, is the same on every x86-64
//! machine whatever the build machine was.

use proptest::prelude::*;
use studyrun::bearing::{DampingModel, RaceWaviness};
use studyrun::mechanism::{CaseParams, Location, SliderCrank};
use studyrun::numeric::simd::Isa;
use studyrun::solve::OdeSystem;

/// Everything one evaluation returns, as exact bit patterns (`{:?}` of an `f64` is
/// its shortest round-trip form, so equal text means equal bits).
fn evaluation(m: &mut SliderCrank, t: f64, y: &[f64; 4]) -> String {
    let mut dydt = [0.0; 4];
    let rhs = m.rhs(t, y, &mut dydt).map(|()| (dydt, m.margin()));
    format!("{rhs:?} {:?}", m.sample(t, y))
}

#[test]
fn this_machine_runs_the_avx_lanes_when_it_has_them() {
    let mut m = SliderCrank::new(&CaseParams::default()).unwrap();
    #[cfg(target_arch = "x86_64")]
    assert_eq!(
        m.set_isa(Isa::Avx) == Isa::Avx,
        std::arch::is_x86_feature_detected!("avx")
    );
    assert_eq!(m.set_isa(Isa::Baseline), Isa::Baseline);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn avx_and_baseline_give_the_same_bits(
        crank_rod in any::<bool>(),
        balls in 3usize..40,
        damping in prop_oneof![Just(0.0), 1.0f64..2e3],
        two_sided in any::<bool>(),
        inner in prop_oneof![Just(0.0), 1e-7f64..5e-6],
        outer in prop_oneof![Just(0.0), 1e-7f64..5e-6],
        gravity in any::<bool>(),
        rpm in 100.0f64..3000.0,
        t in 0.0f64..0.4,
        e in prop::array::uniform2(-3e-5f64..3e-5),
        v in prop::array::uniform2(-0.05f64..0.05),
        held in any::<bool>(),
        hold_shift in prop::array::uniform2(-2e-6f64..2e-6),
    ) {
        let mut c = CaseParams {
            location: if crank_rod { Location::CrankRod } else { Location::CrankGround },
            rpm,
            gravity,
            ..CaseParams::default()
        };
        c.bearing.ball_count = balls;
        c.bearing.damping = damping;
        c.bearing.damping_model =
            if two_sided { DampingModel::TwoSided } else { DampingModel::CompressionOnly };
        c.bearing.inner_waviness = RaceWaviness::single(35, inner);
        c.bearing.outer_waviness = RaceWaviness::single(12, outer);
        let y = [e[0], e[1], v[0], v[1]];
        let [baseline, avx] = [Isa::Baseline, Isa::Avx].map(|isa| {
            let mut m = SliderCrank::new(&c).unwrap();
            m.set_isa(isa);
            if held {
                // A regime frozen a little away from the state, so some balls are
                // held past their switch.
                let near = [e[0] + hold_shift[0], e[1] + hold_shift[1], v[0], v[1]];
                m.hold_regime(t, &near).unwrap();
            }
            evaluation(&mut m, t, &y)
        });
        prop_assert_eq!(baseline, avx);
    }
}
