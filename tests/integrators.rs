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
        eprintln!("RK4 h = {h}: steps {}, final error {last:.3e}, dense error {dense:.3e}", stats.steps);
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
    // Oscillator ω = 2π over [0, 5] (5 periods, solution scale 1 in x, 2π in x');
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
        for w in errs.windows(2) {
            // Monotone over the ladder.
            assert!(w[1] < w[0], "error did not fall: {:?}", errs);
        }
        // Overall by more than 1e4 from rtol 1e-4 to 1e-10.
        assert!(errs[0] / errs[errs.len() - 1] > 1e4, "{errs:?}");
    }
    // Dense output at rtol 1e-10 within 1e-8 of the solution scale (ω = 2π for x').
    let scale = 2.0 * std::f64::consts::PI;
    assert!(denses[denses.len() - 1] < 1e-8 * scale, "{denses:?}");
}

#[test]
fn sdirk4_solves_stiff_problems_with_far_fewer_steps_than_dormand_prince() {
    let tol = 1e-6;
    // Prothero–Robinson, λ = −1e6, with an initial transient (y(0) = 1 ≠ sin 0).
    let mut pr = ProtheroRobinson { lambda: -1e6 };
    let times = midpoints(10.0, 100);
    let exact = |t: f64| vec![t.sin() + (-1e6 * t).exp()];
    let (s_stats, seen) = run(&mut pr, &sdirk(tol, tol), &[1.0], &times);
    let (s_dense, s_last) = errors(&seen, exact);
    let (d_stats, seen) = run(&mut pr, &dp(tol, tol), &[1.0], &times);
    let (d_dense, d_last) = errors(&seen, exact);
    eprintln!("Prothero–Robinson, tol 1e-6: SDIRK4 {s_stats:?}, final error {s_last:.2e}, dense {s_dense:.2e}");
    eprintln!("Prothero–Robinson, tol 1e-6: DP {d_stats:?}, final error {d_last:.2e}, dense {d_dense:.2e}");
    // Linear stiff 2×2 system, eigenvalues −1 and −1e6, on [0, 5].
    let mut lin = StiffLinear { lambda: -1e6 };
    let times = midpoints(5.0, 100);
    let (l_stats, seen) = run(&mut lin, &sdirk(tol, tol), &[1.0, 0.0], &times);
    let (l_dense, l_last) = errors(&seen, |t| lin.exact(t).to_vec());
    let (ld_stats, _) = run(&mut lin, &dp(tol, tol), &[1.0, 0.0], &times);
    eprintln!("Stiff linear, tol 1e-6: SDIRK4 {l_stats:?}, final error {l_last:.2e}, dense {l_dense:.2e}");
    eprintln!("Stiff linear, tol 1e-6: DP {ld_stats:?}");
}

#[test]
fn sdirk4_is_fourth_order_on_a_non_stiff_problem() {
    let mut osc = Oscillator { omega: 1.0 };
    let times = midpoints(10.0, 200);
    for e in 3..=10 {
        let tol = 10f64.powi(-e);
        let (stats, seen) = run(&mut osc, &sdirk(tol, tol), &[1.0, 0.0], &times);
        let (dense, last) = errors(&seen, |t| osc.exact(t).to_vec());
        eprintln!("SDIRK4 tol 1e-{e}: {stats:?}, final error {last:.3e}, dense {dense:.3e}");
    }
    for h in [0.2, 0.1, 0.05, 0.025] {
        let mut s = sdirk(1.0, 1.0);
        s.max_step = h;
        let (stats, seen) = run(&mut osc, &s, &[1.0, 0.0], &times);
        let (dense, last) = errors(&seen, |t| osc.exact(t).to_vec());
        eprintln!("SDIRK4 max_step {h}: {stats:?}, final error {last:.3e}, dense {dense:.3e}");
    }
}

#[test]
fn all_methods_agree_on_van_der_pol() {
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
    for settings in [dp(1e-10, 1e-10), rk4(1e-3), sdirk(1e-10, 1e-10)] {
        let (stats, seen) = run(&mut VanDerPol, &settings, &y0, &times);
        eprintln!("{:?}: {stats:?}, max difference {:.3e}", settings.method, diff(&seen));
    }
}
