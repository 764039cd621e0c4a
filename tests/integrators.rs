//! The time integrators of `studyrun::solve` against problems with known answers:
//! convergence orders, tolerance ladders, stiffness, agreement between methods,
//! observer semantics, failures and work counters.
//!
//! Run with `cargo test --release --test integrators -- --nocapture` to see the
//! measured numbers each test prints.

use crate::common::VanDerPol;
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

/// `y' = y cos t`, `y(0) = 1`: `y = e^{sin t}`. Non-autonomous, so as a system in
/// `(y, t)` it is nonlinear and every elementary differential contributes to the
/// error (on a linear autonomous problem some pairs' leading error terms nearly
/// cancel, e.g. Tsit5's).
struct ExpSin;

impl ExpSin {
    fn exact(t: f64) -> f64 {
        t.sin().exp()
    }
}

impl OdeSystem for ExpSin {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        dydt[0] = y[0] * t.cos();
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

/// `y' = −y` whose evaluation number `fail_at` (counting from 1) fails; records
/// the times of all evaluations.
struct FailsOnce {
    fail_at: usize,
    times: Vec<f64>,
}

impl OdeSystem for FailsOnce {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        self.times.push(t);
        if self.times.len() == self.fail_at {
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

/// The adaptive explicit pairs: name, method at `(rtol, atol)`, order of the
/// solution and of the continuous extension.
type Pair = (&'static str, fn(f64, f64) -> Method, u32, u32);

const PAIRS: [Pair; 3] = [
    (
        "DOPRI5",
        |rtol, atol| Method::DormandPrince { rtol, atol },
        5,
        4,
    ),
    ("Tsit5", |rtol, atol| Method::Tsit5 { rtol, atol }, 5, 4),
    ("DOP853", |rtol, atol| Method::Dop853 { rtol, atol }, 8, 7),
];

fn tsit5(rtol: f64, atol: f64) -> SolverSettings {
    SolverSettings::new(Method::Tsit5 { rtol, atol })
}

fn dop853(rtol: f64, atol: f64) -> SolverSettings {
    SolverSettings::new(Method::Dop853 { rtol, atol })
}

/// Least-squares slope of `ln y` against `ln x`.
fn log_slope(x: &[f64], y: &[f64]) -> f64 {
    let (lx, ly): (Vec<f64>, Vec<f64>) = x.iter().zip(y).map(|(a, b)| (a.ln(), b.ln())).unzip();
    let n = lx.len() as f64;
    let (mx, my) = (lx.iter().sum::<f64>() / n, ly.iter().sum::<f64>() / n);
    let sxy: f64 = lx.iter().zip(&ly).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = lx.iter().map(|a| (a - mx) * (a - mx)).sum();
    sxy / sxx
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
fn explicit_pairs_error_falls_with_tolerance_on_steps_and_dense_output() {
    // Oscillator ω = 2π over [0, 5] (5 periods; x has scale 1, x' scale 2π);
    // 1000 samples at cell midpoints, which do not coincide with step ends.
    let mut osc = Oscillator {
        omega: 2.0 * std::f64::consts::PI,
    };
    let times = midpoints(5.0, 1000);
    for (name, method, _, _) in PAIRS {
        let (mut tols, mut finals, mut denses) = (vec![], vec![], vec![]);
        for e in 4..=10 {
            let tol = 10f64.powi(-e);
            let (stats, seen) = run(
                &mut osc,
                &SolverSettings::new(method(tol, tol)),
                &[1.0, 0.0],
                &times,
            );
            let (dense, last) = errors(&seen, |t| osc.exact(t).to_vec());
            eprintln!(
                "{name} rtol 1e-{e}: steps {}, rejected {}, final error {last:.3e}, dense error {dense:.3e}",
                stats.steps, stats.rejected
            );
            tols.push(tol);
            finals.push(last);
            denses.push(dense);
        }
        for errs in [&finals, &denses] {
            // Monotone over the ladder 1e-4, 1e-5, ..., 1e-10.
            for w in errs.windows(2) {
                assert!(w[1] < w[0], "{name}: error did not fall: {errs:?}");
            }
            // Overall by more than 1e4.
            assert!(errs[0] / errs[errs.len() - 1] > 1e4, "{name}: {errs:?}");
            // Proportional to the tolerance: error ∝ tol^s with s in [0.8, 1.3]
            // (measured 0.97 to 1.20 at step ends and between them).
            let slope = log_slope(&tols, errs);
            eprintln!("{name}: error ∝ tol^{slope:.2}");
            assert!((0.8..=1.3).contains(&slope), "{name}: error ∝ tol^{slope}");
        }
        // Dense output at rtol 1e-10: below 1e-8 (absolute, i.e. 1e-8 of the smaller
        // solution scale 1, for both components).
        assert!(denses[denses.len() - 1] < 1e-8, "{name}: {denses:?}");
    }
}

#[test]
fn explicit_pairs_converge_with_their_order_at_fixed_steps() {
    // y' = y cos t on [0, 10] with N equal steps (max_step = 10/N and a tolerance
    // that never binds, so no step is rejected); samples at every step end and at
    // every step's midpoint. N from errors of ~1e-9 down to well above rounding.
    let t_end = 10.0;
    for (name, method, order, dense_order) in PAIRS {
        let ns: &[usize] = if order == 8 {
            &[20, 25, 35, 50, 70]
        } else {
            &[100, 141, 200, 283, 400]
        };
        let (mut hs, mut ends, mut mids) = (vec![], vec![], vec![]);
        for &n in ns {
            let h = t_end / n as f64;
            let times: Vec<f64> = (1..=2 * n).map(|k| k as f64 * h / 2.0).collect();
            let mut s = SolverSettings::new(method(1.0, 1.0));
            s.max_step = h;
            let (stats, seen) = run(&mut ExpSin, &s, &[1.0], &times);
            assert_eq!((stats.steps, stats.rejected), (n as u64, 0), "{name}");
            let err = |(t, y): &(f64, Vec<f64>)| (y[0] - ExpSin::exact(*t)).abs();
            let end = seen.iter().skip(1).step_by(2).map(err).fold(0.0, f64::max);
            let mid = seen.iter().step_by(2).map(err).fold(0.0, f64::max);
            eprintln!(
                "{name} h = {h:.4}: {} RHS, step-end error {end:.3e}, midpoint error {mid:.3e} ({:.1} times)",
                stats.rhs_evals,
                mid / end
            );
            hs.push(h);
            ends.push(end);
            mids.push(mid);
        }
        // Between step ends the error stays within a small factor of the step ends'
        // (measured 1.3 DOPRI5, 2.3 Tsit5, 8.3 DOP853, constant in h).
        let factor = if order == 8 { 20.0 } else { 5.0 };
        for (m, e) in mids.iter().zip(&ends) {
            assert!(
                *m < factor * e,
                "{name}: midpoint error {m:e} vs step ends {e:e}"
            );
        }
        let (p_end, p_mid) = (log_slope(&hs, &ends), log_slope(&hs, &mids));
        // The solution's global error has the pair's order; between step ends the
        // continuous extension adds a local error of order dense_order + 1, so the
        // midpoint error converges with min(order, dense_order + 1).
        let p_dense = order.min(dense_order + 1);
        eprintln!("{name}: observed order {p_end:.3} at step ends (theory {order}), {p_mid:.3} at midpoints (theory {p_dense})");
        assert!(
            (p_end - f64::from(order)).abs() < 0.3,
            "{name}: order {p_end}"
        );
        assert!(
            (p_mid - f64::from(p_dense)).abs() < 0.3,
            "{name}: dense order {p_mid}"
        );
    }
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
        (tsit5(1e-10, 1e-10), 1e-7),
        (dop853(1e-10, 1e-10), 1e-7),
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

fn all_methods() -> [SolverSettings; 5] {
    [
        dp(1e-9, 1e-9),
        tsit5(1e-9, 1e-9),
        dop853(1e-9, 1e-9),
        rk4(0.01),
        sdirk(1e-9, 1e-9),
    ]
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
    for settings in [
        dp(1e-6, 1e-6),
        tsit5(1e-6, 1e-6),
        dop853(1e-6, 1e-6),
        sdirk(1e-6, 1e-6),
    ] {
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
    for settings in [
        dp(1e-8, 1e-8),
        tsit5(1e-8, 1e-8),
        dop853(1e-8, 1e-8),
        sdirk(1e-8, 1e-8),
    ] {
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
        SolveError::StepBudgetTooSmall {
            step: 0.01,
            needed: 100,
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
fn dop853_rejects_a_step_whose_extra_dense_stage_fails() {
    // Evaluations 1 and 2 are f(t0) and the initial step's probe, 3 to 14 the 12
    // stages of the first step (the last at t0 + h); with samples inside that step
    // the 15th is the first extra stage of the continuous extension, at t0 + 0.1 h.
    // It fails: the step is rejected and retried with h/10, and the run ends well.
    let mut sys = FailsOnce {
        fail_at: 15,
        times: Vec::new(),
    };
    let times = midpoints(1.0, 100);
    let (s, seen) = run(&mut sys, &dop853(1e-8, 1e-8), &[1.0], &times);
    eprintln!("DOP853 with a failing extra stage: {s:?}");
    let (t14, t15) = (sys.times[13], sys.times[14]);
    // The failure hit the extra stage at 0.1 h of a first step ending at t14
    // (a retried stage would sit at c_2 h' = 0.0526 h' < 0.1 h).
    assert!(
        (t15 - 0.1 * t14).abs() < 1e-12 * t14,
        "t14 = {t14}, t15 = {t15}"
    );
    assert!(s.rejected >= 1, "{s:?}");
    // 12 per attempt, 2 at the start, 3 per accepted step with samples inside, and
    // the failed extra evaluation.
    assert_eq!(
        (s.rhs_evals - 2 - 12 * (s.steps + s.rejected)) % 3,
        1,
        "{s:?}"
    );
    // Values within 10 × tol of e^{−t} at every sample (measured 1.8e-8).
    let (err, _) = errors(&seen, |t| vec![(-t).exp()]);
    assert!(err < 1e-7, "{err:e}");
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
    check(tsit5(-1e-6, 1e-6), 0.0, &ok, &t, "rtol = -0.000001");
    check(dop853(1e-6, 0.0), 0.0, &ok, &t, "atol = 0");
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
    // The 5(4) pairs with FSAL: 6 evaluations per attempted step, plus f(t0) and the
    // one of the initial step-size selection (DOPRI5 at 1e-8 and Tsit5 at 1e-6, where
    // both reject some steps).
    for settings in [dp(1e-8, 1e-8), tsit5(1e-6, 1e-6)] {
        let (s, _) = run(&mut VanDerPol, &settings, &[2.0, 0.0], &midpoints(10.0, 50));
        eprintln!("{:?} on Van der Pol: {s:?}", settings.method);
        assert!(s.rejected > 0, "want a run with rejections: {s:?}");
        assert_eq!(s.rhs_evals, 6 * (s.steps + s.rejected) + 2);
        assert_eq!((s.jacobians, s.factorizations), (0, 0));
    }

    // DOP853: 12 per attempted step and 2 at the start, plus 3 for the continuous
    // extension of each accepted step with a sample strictly inside: none when the
    // only sample is the end, at most one per sample otherwise.
    let (s, _) = run(&mut VanDerPol, &dop853(1e-8, 1e-8), &[2.0, 0.0], &[10.0]);
    eprintln!("DOP853 on Van der Pol, one sample: {s:?}");
    assert!(s.rejected > 0, "want a run with rejections: {s:?}");
    assert_eq!(s.rhs_evals, 12 * (s.steps + s.rejected) + 2);
    let (s, _) = run(
        &mut VanDerPol,
        &dop853(1e-8, 1e-8),
        &[2.0, 0.0],
        &midpoints(10.0, 50),
    );
    eprintln!("DOP853 on Van der Pol, 51 samples: {s:?}");
    let dense = s.rhs_evals - 12 * (s.steps + s.rejected) - 2;
    assert!(dense % 3 == 0 && (3..=3 * 50).contains(&dense), "{s:?}");
    assert!(dense / 3 <= s.steps, "{s:?}");

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
