//! Event location by the explicit pairs, on a system whose switches are known in
//! closed form: a unit mass dropped onto a damped linear spring (a bouncing ball
//! with a Kelvin–Voigt contact). In contact (`x < 0`) `ẍ = −g − k x − c ẋ`, in
//! flight `ẍ = −g`; the damping force jumps by `c ẋ` at every touch-down and
//! lift-off, as the bearing's compression-only damping does at a contact onset.
//!
//! The reference is exact: a parabola in flight (next touch-down at `2 v/g`), a
//! damped oscillation in contact (lift-off found by bisection on its closed form to
//! 1e-15 s).

use studyrun::error::ModelError;
use studyrun::solve::{integrate, Method, OdeSystem, SolverSettings, Stats};

const G: f64 = 9.81;
const K: f64 = 1e4;
const C: f64 = 20.0;
const DROP: f64 = 0.05;
const DURATION: f64 = 0.6;

/// The bouncer; `held` is the contact regime an integrator holds.
struct Bouncer {
    held: Option<bool>,
    margin: f64,
}

impl OdeSystem for Bouncer {
    fn dim(&self) -> usize {
        2
    }

    fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        let contact = self.held.unwrap_or(y[0] < 0.0);
        self.margin = match self.held {
            Some(true) => -y[0],
            Some(false) => y[0],
            None => f64::INFINITY,
        };
        dydt[0] = y[1];
        dydt[1] = -G + if contact { -K * y[0] - C * y[1] } else { 0.0 };
        Ok(())
    }

    fn hold_regime(&mut self, _t: f64, y: &[f64]) -> Result<bool, ModelError> {
        self.held = Some(y[0] < 0.0);
        Ok(true)
    }

    fn release_regime(&mut self) {
        self.held = None;
    }

    fn margin(&self) -> f64 {
        self.margin
    }
}

/// One phase of the exact motion, starting at `t0` with `x = 0` and speed `v0`
/// (the first one at `x = DROP`, at rest).
#[derive(Clone, Copy)]
struct Phase {
    t0: f64,
    x0: f64,
    v0: f64,
    contact: bool,
}

const OMEGA: f64 = 100.0; // √K
const ZETA: f64 = C / (2.0 * OMEGA);

fn omega_d() -> f64 {
    OMEGA * (1.0 - ZETA * ZETA).sqrt()
}

impl Phase {
    /// Position (m) `tau` s into the phase.
    fn x(&self, tau: f64) -> f64 {
        if !self.contact {
            return self.x0 + self.v0 * tau - 0.5 * G * tau * tau;
        }
        let a = G / K;
        let b = (self.v0 + ZETA * OMEGA * a) / omega_d();
        -G / K
            + (-ZETA * OMEGA * tau).exp()
                * (a * (omega_d() * tau).cos() + b * (omega_d() * tau).sin())
    }

    /// Its length (s) and the speed (m/s) at its end.
    fn end(&self) -> (f64, f64) {
        if !self.contact {
            let tau = (self.v0 + (self.v0 * self.v0 + 2.0 * G * self.x0).sqrt()) / G;
            return (tau, self.v0 - G * tau);
        }
        // x < 0 from just after touch-down until lift-off, inside one damped period.
        let mut step = std::f64::consts::PI / omega_d() / 1000.0;
        let mut tau = step;
        while self.x(tau) < 0.0 {
            tau += step;
        }
        let (mut lo, mut hi) = (tau - step, tau);
        while hi - lo > 1e-16 {
            let mid = 0.5 * (lo + hi);
            if self.x(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        step = 1e-7;
        let v = (self.x(hi + step) - self.x(hi - step)) / (2.0 * step);
        (hi, v)
    }
}

/// The exact phases up to `DURATION`.
fn phases() -> Vec<Phase> {
    let mut out = vec![Phase {
        t0: 0.0,
        x0: DROP,
        v0: 0.0,
        contact: false,
    }];
    loop {
        let p = *out.last().unwrap();
        let (len, v) = p.end();
        if p.t0 + len > DURATION {
            return out;
        }
        out.push(Phase {
            t0: p.t0 + len,
            x0: 0.0,
            v0: v,
            contact: !p.contact,
        });
    }
}

fn exact(phases: &[Phase], t: f64) -> f64 {
    let p = phases.iter().rev().find(|p| p.t0 <= t).unwrap();
    p.x(t - p.t0)
}

/// Largest error in `x` relative to the drop height, and the work.
fn run(method: Method, locate_events: bool) -> (f64, Stats) {
    let ph = phases();
    let times: Vec<f64> = (0..=600).map(|k| k as f64 * 1e-3).collect();
    let mut worst: f64 = 0.0;
    let settings = SolverSettings {
        locate_events,
        ..SolverSettings::new(method)
    };
    let mut sys = Bouncer {
        held: None,
        margin: f64::INFINITY,
    };
    let stats = integrate(&mut sys, &settings, 0.0, &[DROP, 0.0], &times, |_, t, y| {
        worst = worst.max((y[0] - exact(&ph, t)).abs() / DROP);
        Ok(())
    })
    .unwrap();
    (worst, stats)
}

fn pairs(rtol: f64) -> [(&'static str, Method); 3] {
    let atol = rtol * 1e-3;
    [
        ("dopri5", Method::DormandPrince { rtol, atol }),
        ("tsit5", Method::Tsit5 { rtol, atol }),
        ("dop853", Method::Dop853 { rtol, atol }),
    ]
}

#[test]
fn the_reference_has_the_expected_bounces() {
    let ph = phases();
    // Touch-down after √(2h/g); a contact lasts about π/ω_d.
    assert!((ph[1].t0 - (2.0 * DROP / G).sqrt()).abs() < 1e-15);
    let contact = ph[2].t0 - ph[1].t0;
    assert!((contact - std::f64::consts::PI / omega_d()).abs() < 0.1 * contact);
    assert!(ph.len() >= 6, "{} phases", ph.len());
}

/// Every switch is found (one event per phase change), the error falls with the
/// tolerance like the pairs' order allows on a smooth problem, and stepping across
/// the switches instead costs more evaluations for a larger error.
#[test]
fn switches_are_located_and_the_error_converges() {
    let switches = phases().len() as u64 - 1;
    for rtol in [1e-6, 1e-8, 1e-10] {
        for (name, method) in pairs(rtol) {
            let (err, stats) = run(method, true);
            let (err_across, stats_across) = run(method, false);
            eprintln!(
                "{name} rtol {rtol:e}: located {err:.2e} ({} RHS, {} events), across {err_across:.2e} ({} RHS)",
                stats.rhs_evals, stats.events, stats_across.rhs_evals
            );
            assert_eq!(stats.events, switches, "{name} rtol {rtol:e}");
            assert_eq!(stats_across.events, 0);
            assert!(err < 100.0 * rtol, "{name} rtol {rtol:e}: error {err:e}");
            assert!(
                stats.rhs_evals < stats_across.rhs_evals,
                "{name} rtol {rtol:e}: {} vs {} RHS",
                stats.rhs_evals,
                stats_across.rhs_evals
            );
        }
    }
}
