//! The time integrators of `studyrun::solve` against problems with known answers:
//! convergence orders, tolerance ladders, stiffness, agreement between methods,
//! observer semantics, failures and work counters.
//!
//! Run with `cargo test --release --test integrators -- --nocapture` to see the
//! measured numbers each test prints.

use studyrun::error::ModelError;
use studyrun::solve::{integrate, Method, OdeSystem, SolveError, SolverSettings, Stats};

// ---------------------------------------------------------------------------
// Test problems
// ---------------------------------------------------------------------------

/// `y' = −y + sin t`, `y(0) = 1`: `y = 1.5 e^{−t} + (sin t − cos t)/2`.
struct Forced;

impl Forced {
    fn exact(t: f64) -> f64 {
        1.5 * (-t).exp() + 0.5 * (t.sin() - t.cos())
    }
}

impl OdeSystem for Forced {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = -y[0] + t.sin();
        Ok(())
    }
}

/// Harmonic oscillator `x'' = −ω² x`, `x(0) = 1`, `x'(0) = 0`: `x = cos ωt`.
struct Oscillator {
    omega: f64,
}

impl Oscillator {
    fn exact(&self, t: f64) -> [f64; 2] {
        let w = self.omega;
        [(w * t).cos(), -w * (w * t).sin()]
    }
}

impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = y[1];
        dydt[1] = -self.omega * self.omega * y[0];
        Ok(())
    }
}

/// Prothero–Robinson `y' = λ(y − sin t) + cos t`: `y = sin t + y(0) e^{λt}`.
struct ProtheroRobinson {
    lambda: f64,
}

impl OdeSystem for ProtheroRobinson {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = self.lambda * (y[0] - t.sin()) + t.cos();
        Ok(())
    }
}

/// Linear stiff system `y' = A y` with eigenvalues −1 and `lambda` and eigenvectors
/// (2, −1), (−1, 1); `y(0) = (1, 0)` gives `y = (2e^{−t} − e^{λt}, −e^{−t} + e^{λt})`.
struct StiffLinear {
    lambda: f64,
}

impl StiffLinear {
    fn exact(&self, t: f64) -> [f64; 2] {
        let (slow, fast) = ((-t).exp(), (self.lambda * t).exp());
        [2.0 * slow - fast, -slow + fast]
    }
}

impl OdeSystem for StiffLinear {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        // A = V diag(−1, λ) V⁻¹, V = [[2, −1], [−1, 1]], V⁻¹ = [[1, 1], [1, 2]].
        let l = self.lambda;
        dydt[0] = (-2.0 - l) * y[0] + (-2.0 - 2.0 * l) * y[1];
        dydt[1] = (1.0 + l) * y[0] + (1.0 + 2.0 * l) * y[1];
        Ok(())
    }
}

/// Van der Pol oscillator, `μ = 1`.
struct VanDerPol;

impl OdeSystem for VanDerPol {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = y[1];
        dydt[1] = (1.0 - y[0] * y[0]) * y[1] - y[0];
        Ok(())
    }
}

/// `y' = y²`, `y(0) = 1`: blows up at `t = 1`.
struct BlowUp;

impl OdeSystem for BlowUp {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = y[0] * y[0];
        Ok(())
    }
}

/// `y' = −y` whose model fails for `t > fail_after`.
struct FailsLater {
    fail_after: f64,
}

impl OdeSystem for FailsLater {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        if t > self.fail_after {
            return Err(ModelError::SingularConstraints);
        }
        dydt[0] = -y[0];
        Ok(())
    }
}

/// A system without state.
struct Empty;

impl OdeSystem for Empty {
    fn dim(&self) -> usize {
        0
    }
    fn rhs(&mut self, _t: f64, _y: &[f64], _dydt: &mut [f64]) -> Result<(), ModelError> {
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------

fn dp(rtol: f64, atol: f64) -> SolverSettings {
    SolverSettings::new(Method::DormandPrince { rtol, atol })
}

fn rk4(step: f64) -> SolverSettings {
    SolverSettings::new(Method::Rk4 { step })
}

fn sdirk(rtol: f64, atol: f64) -> SolverSettings {
    SolverSettings::new(Method::Sdirk4 { rtol, atol })
}

/// `count` sample times strictly inside `(0, t_end)` at the midpoints of `count`
/// equal cells, then `t_end` itself.
fn midpoints(t_end: f64, count: usize) -> Vec<f64> {
    let mut v: Vec<f64> = (0..count)
        .map(|k| t_end * (k as f64 + 0.5) / count as f64)
        .collect();
    v.push(t_end);
    v
}

/// Runs `sys` and returns the stats and every observed `(t, y)`.
fn run<S: OdeSystem>(
    sys: &mut S,
    settings: &SolverSettings,
    y0: &[f64],
    times: &[f64],
) -> (Stats, Vec<(f64, Vec<f64>)>) {
    let mut seen = Vec::with_capacity(times.len());
    let stats = integrate(sys, settings, 0.0, y0, times, |_, t, y| {
        seen.push((t, y.to_vec()));
        Ok(())
    })
    .unwrap_or_else(|e| panic!("{settings:?}: {e}"));
    assert_eq!(seen.len(), times.len());
    (stats, seen)
}

/// Largest error over the observed samples against `exact`, and the error at the
/// last sample.
fn errors(seen: &[(f64, Vec<f64>)], exact: impl Fn(f64) -> Vec<f64>) -> (f64, f64) {
    let err = |(t, y): &(f64, Vec<f64>)| {
        exact(*t)
            .iter()
            .zip(y)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let max = seen.iter().map(err).fold(0.0, f64::max);
    (max, err(seen.last().unwrap()))
}

// ---------------------------------------------------------------------------
// Orders and accuracy
// ---------------------------------------------------------------------------

#[test]
fn rk4_converges_with_order_four() {
    // y' = −y + sin t on [0, 5], h = 0.2, 0.1, 0.05; 1000 samples off the step grid.
    let times = midpoints(5.0, 1000);
    let exact = |t: f64| vec![Forced::exact(t)];
    let mut finals = Vec::new();
    let mut denses = Vec::new();
    for h in [0.2, 0.1, 0.05] {
        let (stats, seen) = run(&mut Forced, &rk4(h), &[1.0], &times);
        let (dense, last) = errors(&seen, exact);
        eprintln!(
            "RK4 h = {h}: steps {}, final error {last:.3e}, dense error {dense:.3e}",
            stats.steps
        );
        finals.push(last);
        denses.push(dense);
    }
    for w in finals.windows(2) {
        let order = (w[0] / w[1]).log2();
        eprintln!("RK4 observed order at t = 5: {order:.3}");
        // Observed order within 4 ± 0.2.
        assert!((order - 4.0).abs() < 0.2, "final-time order {order}");
    }
    for w in denses.windows(2) {
        let order = (w[0] / w[1]).log2();
        eprintln!("RK4 + Hermite observed order over 1000 samples: {order:.3}");
        // Cubic Hermite from order-4 end values is order 4 as well: 4 ± 0.2.
        assert!((order - 4.0).abs() < 0.2, "dense order {order}");
    }
}

#[test]
fn dormand_prince_error_falls_with_tolerance_on_steps_and_dense_output() {
    // Oscillator ω = 2π over [0, 5] (5 periods; x has scale 1, x' scale 2π);
    // 1000 samples at cell midpoints, which do not coincide with step ends.
    let mut osc = Oscillator {
        omega: 2.0 * std::f64::consts::PI,
    };
    let times = midpoints(5.0, 1000);
    let mut finals = Vec::new();
    let mut denses = Vec::new();
    for e in 4..=10 {
        let tol = 10f64.powi(-e);
        let (stats, seen) = run(&mut osc, &dp(tol, tol), &[1.0, 0.0], &times);
        let (dense, last) = errors(&seen, |t| osc.exact(t).to_vec());
        eprintln!(
            "DP rtol 1e-{e}: steps {}, rejected {}, final error {last:.3e}, dense error {dense:.3e}",
            stats.steps, stats.rejected
        );
        finals.push(last);
        denses.push(dense);
    }
    for errs in [&finals, &denses] {
        // Monotone over the ladder 1e-4, 1e-5, ..., 1e-10.
        for w in errs.windows(2) {
            assert!(w[1] < w[0], "error did not fall: {errs:?}");
        }
        // Overall by more than 1e4.
        assert!(errs[0] / errs[errs.len() - 1] > 1e4, "{errs:?}");
    }
    // Dense output at rtol 1e-10: below 1e-8 (absolute, i.e. 1e-8 of the smaller
    // solution scale 1, for both components).
    assert!(denses[denses.len() - 1] < 1e-8, "{denses:?}");
}

#[test]
fn sdirk4_solves_stiff_problems_with_far_fewer_steps_than_dormand_prince() {
    let tol = 1e-6;
    // Prothero–Robinson, λ = −1e6, on [0, 10] with an initial transient (y(0) = 1).
    let mut pr = ProtheroRobinson { lambda: -1e6 };
    let times = [10.0];
    let exact = |t: f64| vec![t.sin() + (-1e6 * t).exp()];
    let (s_stats, seen) = run(&mut pr, &sdirk(tol, tol), &[1.0], &times);
    let (_, s_last) = errors(&seen, exact);
    let (d_stats, seen) = run(&mut pr, &dp(tol, tol), &[1.0], &times);
    let (_, d_last) = errors(&seen, exact);
    eprintln!("Prothero–Robinson, tol 1e-6: SDIRK4 {s_stats:?}, error at t = 10: {s_last:.2e}");
    eprintln!("Prothero–Robinson, tol 1e-6: DP {d_stats:?}, error at t = 10: {d_last:.2e}");
    // Attempted steps below 1/10 of DP's (DP is held to |hλ| ≲ 3.3 by stability).
    assert!(10 * (s_stats.steps + s_stats.rejected) < d_stats.steps);
    // Error at t = 10 below 10 × tol.
    assert!(s_last < 1e-5, "{s_last:e}");

    // Linear stiff 2×2 system, eigenvalues −1 and −1e6, on [0, 5]; 100 samples.
    let mut lin = StiffLinear { lambda: -1e6 };
    let times = midpoints(5.0, 100);
    let (l_stats, seen) = run(&mut lin, &sdirk(tol, tol), &[1.0, 0.0], &times);
    let (l_dense, l_last) = errors(&seen, |t| lin.exact(t).to_vec());
    let (ld_stats, _) = run(&mut lin, &dp(tol, tol), &[1.0, 0.0], &times);
    eprintln!(
        "Stiff linear, tol 1e-6: SDIRK4 {l_stats:?}, final error {l_last:.2e}, dense error {l_dense:.2e}"
    );
    eprintln!("Stiff linear, tol 1e-6: DP {ld_stats:?}");
    assert!(10 * (l_stats.steps + l_stats.rejected) < ld_stats.steps);
    // Final error below tol; error at the 100 interior samples below 10 × tol
    // (solution scale 2).
    assert!(l_last < 1e-6, "{l_last:e}");
    assert!(l_dense < 1e-5, "{l_dense:e}");
}

#[test]
fn sdirk4_dense_output_on_a_stiff_problem_is_limited_by_the_step_length() {
    // Prothero–Robinson, λ = −1e6: the step-end values are accurate however long the
    // steps, so the controller takes steps of order 1 s, and between step ends the
    // interpolant is only as good as the step is short (stage order 1: the error of
    // the end slopes is O(h²)). `max_step` bounds it: the error over 2000 samples
    // must fall like h² (ratio > 3 per halving) and be below 2e-5 at max_step 0.02.
    let mut pr = ProtheroRobinson { lambda: -1e6 };
    let times = midpoints(10.0, 2000);
    let exact = |t: f64| vec![t.sin() + (-1e6 * t).exp()];
    let mut dense = Vec::new();
    for max_step in [f64::INFINITY, 0.08, 0.04, 0.02] {
        let mut s = sdirk(1e-6, 1e-6);
        s.max_step = max_step;
        let (stats, seen) = run(&mut pr, &s, &[1.0], &times);
        let (d, last) = errors(&seen, exact);
        eprintln!("PR max_step {max_step}: {stats:?}, dense error {d:.2e}, final {last:.2e}");
        dense.push(d);
    }
    for w in dense[1..].windows(2) {
        assert!(w[0] / w[1] > 3.0, "{dense:?}");
    }
    assert!(dense[3] < 2e-5, "{dense:?}");
}

#[test]
fn sdirk4_is_fourth_order_on_a_non_stiff_problem() {
    // Oscillator ω = 1 on [0, 10].
    let mut osc = Oscillator { omega: 1.0 };
    let times = midpoints(10.0, 200);
    let mut ladder = Vec::new();
    for e in 3..=10 {
        let tol = 10f64.powi(-e);
        let (stats, seen) = run(&mut osc, &sdirk(tol, tol), &[1.0, 0.0], &times);
        let (dense, last) = errors(&seen, |t| osc.exact(t).to_vec());
        eprintln!("SDIRK4 tol 1e-{e}: {stats:?}, final error {last:.3e}, dense error {dense:.3e}");
        ladder.push((stats.steps as f64, last, dense));
    }
    // The error falls monotonically as the tolerance is tightened...
    for w in ladder.windows(2) {
        assert!(w[1].1 < w[0].1 && w[1].2 < w[0].2, "{ladder:?}");
    }
    // ...like steps^(−4): slope between tol 1e-6 and 1e-10 within 4 ± 0.3.
    let (a, b) = (ladder[3], ladder[7]);
    let slope = (a.1 / b.1).ln() / (b.0 / a.0).ln();
    eprintln!("SDIRK4 error vs steps: order {slope:.3}");
    assert!((slope - 4.0).abs() < 0.3, "order {slope}");

    // Constant steps, forced by max_step with a tolerance that never binds.
    let mut finals = Vec::new();
    for h in [0.2, 0.1, 0.05] {
        let mut s = sdirk(1.0, 1.0);
        s.max_step = h;
        let (stats, seen) = run(&mut osc, &s, &[1.0, 0.0], &times);
        let (_, last) = errors(&seen, |t| osc.exact(t).to_vec());
        eprintln!("SDIRK4 max_step {h}: {stats:?}, final error {last:.3e}");
        finals.push(last);
    }
    for w in finals.windows(2) {
        let order = (w[0] / w[1]).log2();
        eprintln!("SDIRK4 observed order with halved steps: {order:.3}");
        // Within 4 ± 0.2.
        assert!((order - 4.0).abs() < 0.2, "order {order}");
    }
}

#[test]
fn all_methods_agree_on_van_der_pol() {
    // μ = 1, y(0) = (2, 0), on [0, 10], 100 samples; reference: DP at 1e-13.
    let times = midpoints(10.0, 100);
    let y0 = [2.0, 0.0];
    let (r_stats, reference) = run(&mut VanDerPol, &dp(1e-13, 1e-13), &y0, &times);
    eprintln!("reference DP 1e-13: {r_stats:?}");
    let diff = |seen: &[(f64, Vec<f64>)]| {
        seen.iter()
            .zip(&reference)
            .flat_map(|((_, a), (_, b))| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
            .fold(0.0, f64::max)
    };
    // Bounds on the largest difference over samples and components (scale ~2–3).
    for (settings, bound) in [
        (dp(1e-10, 1e-10), 1e-7),
        (rk4(1e-3), 1e-9),
        (sdirk(1e-10, 1e-10), 1e-6),
    ] {
        let (stats, seen) = run(&mut VanDerPol, &settings, &y0, &times);
        let d = diff(&seen);
        eprintln!("{:?}: {stats:?}, max difference {d:.3e}", settings.method);
        assert!(d < bound, "{:?}: {d:e} >= {bound:e}", settings.method);
    }
}

// ---------------------------------------------------------------------------
// Observer semantics
// ---------------------------------------------------------------------------

fn all_methods() -> [SolverSettings; 3] {
    [dp(1e-9, 1e-9), rk4(0.01), sdirk(1e-9, 1e-9)]
}

#[test]
fn observer_is_called_once_per_sample_in_order() {
    // Includes samples at t0, repeated times, and times on and off step ends.
    let times = [0.0, 0.0, 0.25, 0.25, 0.25, 0.7, 1.3, 2.0, 2.0];
    let osc = Oscillator { omega: 1.0 };
    for settings in all_methods() {
        let (_, seen) = run(
            &mut Oscillator { omega: 1.0 },
            &settings,
            &[1.0, 0.0],
            &times,
        );
        let observed: Vec<f64> = seen.iter().map(|(t, _)| *t).collect();
        assert_eq!(observed, times, "{settings:?}");
        // Samples at t0 get y0 itself.
        assert_eq!(seen[0].1, [1.0, 0.0]);
        assert_eq!(seen[1].1, [1.0, 0.0]);
        // Repeated times get the same state.
        assert_eq!(seen[2].1, seen[3].1);
        assert_eq!(seen[7].1, seen[8].1);
        // Values are the state at that time: within 1e-7 of the exact solution.
        let (err, _) = errors(&seen, |t| osc.exact(t).to_vec());
        assert!(err < 1e-7, "{settings:?}: {err:e}");
    }
}

#[test]
fn degenerate_sample_sets_call_nothing_or_only_the_observer() {
    for settings in all_methods() {
        // Empty sample set: Ok, zero stats, no call (even for a blow-up problem).
        let mut calls = 0;
        let stats = integrate(&mut BlowUp, &settings, 0.0, &[1.0], &[], |_, _, _| {
            calls += 1;
            Ok(())
        })
        .unwrap();
        assert_eq!((stats, calls), (Stats::default(), 0));
        // All samples at t0: the observer sees y0, f is never evaluated.
        let (stats, seen) = run(&mut BlowUp, &settings, &[1.0], &[0.0, 0.0]);
        assert_eq!(stats, Stats::default());
        assert_eq!(seen, [(0.0, vec![1.0]), (0.0, vec![1.0])]);
        // A system without state: observer calls only.
        let (stats, seen) = run(&mut Empty, &settings, &[], &[0.0, 0.5, 2.0]);
        assert_eq!(stats, Stats::default());
        assert_eq!(seen, [(0.0, vec![]), (0.5, vec![]), (2.0, vec![])]);
    }
}

// ---------------------------------------------------------------------------
// Failures
// ---------------------------------------------------------------------------

#[test]
fn blow_up_ends_with_an_error_not_a_panic_or_hang() {
    // y' = y², y(0) = 1, to t = 2 (pole at t = 1).
    for settings in [dp(1e-6, 1e-6), sdirk(1e-6, 1e-6)] {
        let err = integrate(
            &mut BlowUp,
            &settings,
            0.0,
            &[1.0],
            &[2.0],
            |_, _, _| Ok(()),
        )
        .unwrap_err();
        eprintln!("{:?}: {err}", settings.method);
        match err {
            SolveError::StepSizeTooSmall { t, .. } | SolveError::NonFinite { t, .. } => {
                // Stopped at the pole, to within 1e-3.
                assert!((t - 1.0).abs() < 1e-3, "{err}");
            }
            e => panic!("{:?}: unexpected {e}", settings.method),
        }
    }
    let err = integrate(&mut BlowUp, &rk4(0.01), 0.0, &[1.0], &[2.0], |_, _, _| {
        Ok(())
    })
    .unwrap_err();
    eprintln!("RK4: {err}");
    assert!(
        matches!(err, SolveError::NonFinite { index: 0, .. }),
        "{err}"
    );
}

#[test]
fn step_budget_counts_and_stops() {
    let times = [10.0];
    for settings in [dp(1e-8, 1e-8), sdirk(1e-8, 1e-8)] {
        let tiny = SolverSettings {
            max_steps: 5,
            ..settings
        };
        let err = integrate(
            &mut Oscillator { omega: 1.0 },
            &tiny,
            0.0,
            &[1.0, 0.0],
            &times,
            |_, _, _| Ok(()),
        )
        .unwrap_err();
        assert!(
            matches!(
                err,
                SolveError::StepBudgetExhausted {
                    steps: 5,
                    max_steps: 5,
                    ..
                }
            ),
            "{err}"
        );
    }
    // RK4 with h = 0.01 to t = 1 needs 100 steps: 99 fail before anything runs
    // (not even the sample at t0 is observed), 100 succeed.
    let mut calls = 0;
    let err = integrate(
        &mut Forced,
        &SolverSettings {
            max_steps: 99,
            ..rk4(0.01)
        },
        0.0,
        &[1.0],
        &[0.0, 1.0],
        |_, _, _| {
            calls += 1;
            Ok(())
        },
    )
    .unwrap_err();
    assert_eq!(
        err,
        SolveError::StepBudgetExhausted {
            t: 0.0,
            steps: 0,
            max_steps: 99
        }
    );
    assert_eq!(calls, 0);
    let ok = SolverSettings {
        max_steps: 100,
        ..rk4(0.01)
    };
    assert_eq!(run(&mut Forced, &ok, &[1.0], &[1.0]).0.steps, 100);
}

#[test]
fn model_and_observer_errors_propagate_with_their_time() {
    for settings in all_methods() {
        let err = integrate(
            &mut FailsLater { fail_after: 0.5 },
            &settings,
            0.0,
            &[1.0],
            &[1.0],
            |_, _, _| Ok(()),
        )
        .unwrap_err();
        match err {
            SolveError::Model { t, source } => {
                assert!(t > 0.5 && t <= 1.0, "{t}");
                assert_eq!(source, ModelError::SingularConstraints);
            }
            e => panic!("{settings:?}: {e}"),
        }
        let mut last = 0.0;
        let err = integrate(
            &mut Forced,
            &settings,
            0.0,
            &[1.0],
            &[0.2, 0.7, 0.9],
            |_, t, _| {
                last = t;
                if t > 0.5 {
                    Err(ModelError::NonFinite { what: "output" })
                } else {
                    Ok(())
                }
            },
        )
        .unwrap_err();
        assert_eq!(
            err,
            SolveError::Model {
                t: 0.7,
                source: ModelError::NonFinite { what: "output" }
            }
        );
        // Stopped at the failing sample.
        assert_eq!(last, 0.7);
    }
}

#[test]
fn invalid_settings_name_the_field() {
    let check = |settings: SolverSettings, t0: f64, y0: &[f64], times: &[f64], needle: &str| {
        match integrate(&mut Forced, &settings, t0, y0, times, |_, _, _| Ok(())) {
            Err(SolveError::InvalidSetting(msg)) => {
                assert!(msg.contains(needle), "{msg:?} should name {needle:?}")
            }
            other => panic!("expected InvalidSetting naming {needle}, got {other:?}"),
        }
    };
    let ok = [1.0];
    let t = [1.0];
    check(dp(0.0, 1e-6), 0.0, &ok, &t, "rtol = 0");
    check(dp(1e-6, -1.0), 0.0, &ok, &t, "atol = -1");
    check(sdirk(f64::NAN, 1e-6), 0.0, &ok, &t, "rtol = NaN");
    check(sdirk(1e-6, f64::INFINITY), 0.0, &ok, &t, "atol = inf");
    check(rk4(0.0), 0.0, &ok, &t, "step = 0");
    check(rk4(-0.1), 0.0, &ok, &t, "step = -0.1");
    let mut s = dp(1e-6, 1e-6);
    s.max_step = 0.0;
    check(s, 0.0, &ok, &t, "max_step = 0");
    check(rk4(0.1), f64::NAN, &ok, &t, "t0 = NaN");
    check(rk4(0.1), 0.0, &[1.0, 2.0], &t, "y0 has length 2");
    check(rk4(0.1), 0.0, &[f64::NAN], &t, "y0[0] = NaN");
    check(rk4(0.1), 0.0, &ok, &[0.5, 0.4], "sample_times[1] = 0.4");
    check(
        rk4(0.1),
        1.0,
        &ok,
        &[0.5],
        "sample_times[0] = 0.5 is before t0 = 1",
    );
    check(
        rk4(0.1),
        0.0,
        &ok,
        &[0.5, f64::INFINITY],
        "sample_times[1] = inf",
    );
}

// ---------------------------------------------------------------------------
// Work counters
// ---------------------------------------------------------------------------

#[test]
fn stats_match_the_methods_costs() {
    // Dormand–Prince with FSAL: 6 evaluations per attempted step, plus f(t0) and the
    // one of the initial step-size selection.
    let (s, _) = run(
        &mut VanDerPol,
        &dp(1e-8, 1e-8),
        &[2.0, 0.0],
        &midpoints(10.0, 50),
    );
    eprintln!("DP on Van der Pol: {s:?}");
    assert!(s.rejected > 0, "want a run with rejections: {s:?}");
    assert_eq!(s.rhs_evals, 6 * (s.steps + s.rejected) + 2);
    assert_eq!((s.jacobians, s.factorizations), (0, 0));

    // RK4: 4 per step; step count ceil((T − t0)/h) without a rounding sliver.
    for (t_end, steps) in [(1.0, 10), (0.3, 3), (1.05, 11)] {
        let (s, _) = run(&mut Forced, &rk4(0.1), &[1.0], &[t_end]);
        assert_eq!((s.steps, s.rhs_evals, s.rejected), (steps, 4 * steps, 0));
    }
    // Samples inside steps: the end slope is reused as the next first stage, so
    // only a sample inside the last step costs one more evaluation.
    let (s, _) = run(&mut Forced, &rk4(0.1), &[1.0], &[0.05, 0.45, 1.0]);
    assert_eq!((s.steps, s.rhs_evals), (10, 40));
    let (s, _) = run(&mut Forced, &rk4(0.1), &[1.0], &[0.05, 0.95, 1.0]);
    assert_eq!((s.steps, s.rhs_evals), (10, 41));

    // SDIRK4: each Jacobian costs n + 1 evaluations, each stage at least one Newton
    // iteration and at most 7; 2 evaluations at the start.
    let n = 2;
    let (s, _) = run(
        &mut VanDerPol,
        &sdirk(1e-8, 1e-8),
        &[2.0, 0.0],
        &midpoints(10.0, 50),
    );
    eprintln!("SDIRK4 on Van der Pol: {s:?}");
    let fixed = 2 + s.jacobians * (n + 1);
    assert!(s.jacobians >= 1 && s.factorizations >= s.jacobians, "{s:?}");
    assert!(s.rhs_evals >= fixed + 5 * s.steps, "{s:?}");
    assert!(
        s.rhs_evals <= fixed + 5 * 7 * (s.steps + s.rejected),
        "{s:?}"
    );
    // The Jacobian is reused across steps on this smooth problem.
    assert!(s.jacobians < s.steps, "{s:?}");
}
