//! Regime switches of a piecewise-smooth system (docs/model.md §8.4, §8.8): locating
//! one on an accepted step's continuous extension, and noticing when located
//! switches chatter.

use super::eval::{accept, eval};
use super::output::Samples;
use super::{OdeSystem, SolveError, Stats};
use crate::error::ModelError;

/// Of the last 64 accepted steps, how many ending at a located switch make a run's
/// switches chatter (docs/model.md §8.8). A run that resolves its contacts has long
/// stretches of ordinary steps between switches; a journal held against a ball by
/// compression-only damping has every step or every other step end at one.
pub const CHATTER_SWITCHES: u32 = 32;

/// Remembers which of the last 64 accepted steps ended at a located switch.
#[derive(Debug, Clone, Default)]
pub(crate) struct ChatterWatch {
    /// Bit `i` set: the `i`-th latest accepted step ended at a switch.
    history: u64,
}

impl ChatterWatch {
    /// Counts an accepted step, `at_switch` when it ended at a located switch; true
    /// while at least [`CHATTER_SWITCHES`] of the last 64 did.
    pub fn step(&mut self, at_switch: bool) -> bool {
        self.history = (self.history << 1) | u64::from(at_switch);
        self.history.count_ones() >= CHATTER_SWITCHES
    }
}

/// Tells `sys` its switches chatter at `(t, y)` ([`OdeSystem::settle_chatter`]) unless
/// it was told before in this run, and records the time in `stats` if it settled.
pub(crate) fn settle<S: OdeSystem>(
    sys: &mut S,
    (t, y): (f64, &[f64]),
    (rtol, atol): (f64, f64),
    stats: &mut Stats,
) {
    if stats.chatter_at.is_none() && sys.settle_chatter(y, rtol, atol) {
        stats.chatter_at = Some(t);
    }
}

/// Relative width (of the step) to which [`locate`] narrows a switch: far below
/// any step's error, e.g. `1e-14 s` on a `100 µs` step.
const EVENT_RESOLUTION: f64 = 1e-10;

/// Closest (fraction of the step) a trial point of [`locate`] comes to an end of
/// its bracket: half of [`EVENT_RESOLUTION`].
const NUDGE: f64 = 0.5 * EVENT_RESOLUTION;

/// Locates the first regime switch of an accepted step from `t0` of size `h` (s)
/// on its continuous extension (`extension(θ, y)` writes the state at fraction
/// `θ`), given the switching margin at its start (`≥ 0`) and each
/// stage's node and margin in `stages`: the switching margin `g(θ)` of the held
/// regime is evaluated along the extension, at the earliest stage node where it is
/// negative (the step's end included), to bracket a sign change, which the
/// Illinois variant of regula falsi then narrows to [`EVENT_RESOLUTION`] (keeping
/// trial points [`NUDGE`] inside the bracket, bisecting when the secant point is
/// not strictly inside it, stopping when no time between the ends is left).
/// Returns the fraction `θ` of the step just past the switch (`g(θ) < 0`) with the
/// state there in `y_event`, or `None` when the extension does not cross (a stage
/// state strayed, the trajectory did not). `f_end` is scratch for the slopes; each
/// `g` costs one evaluation of `f`.
pub(crate) fn locate<S: OdeSystem>(
    sys: &mut S,
    (t0, h): (f64, f64),
    extension: impl Fn(f64, &mut [f64]),
    (g0, stages): (f64, impl Iterator<Item = (f64, f64)>),
    (y_event, f_end): (&mut [f64], &mut [f64]),
    stats: &mut Stats,
) -> Result<Option<f64>, SolveError> {
    let mut g = |theta: f64, y: &mut [f64]| -> Result<f64, SolveError> {
        extension(theta, y);
        eval(sys, t0 + theta * h, y, f_end, stats)?;
        Ok(sys.margin())
    };
    let mut nodes: Vec<f64> = stages.filter(|&(_, m)| m < 0.0).map(|(c, _)| c).collect();
    nodes.sort_by(f64::total_cmp);
    nodes.dedup();
    let mut bracket = None;
    for c in nodes {
        let gc = g(c, y_event)?;
        if gc < 0.0 {
            bracket = Some((c, gc));
            break;
        }
    }
    let Some((mut b, mut gb)) = bracket else {
        return Ok(None);
    };
    let (mut a, mut ga) = (0.0, g0.max(0.0));
    let mut side = 0;
    let time = |theta: f64| t0 + theta * h;
    while b - a > EVENT_RESOLUTION {
        let resolved = |m: f64| m > a && m < b && time(m) != time(a) && time(m) != time(b);
        let mut m = (a * gb - b * ga) / (gb - ga);
        if !(m > a && m < b) {
            m = 0.5 * (a + b);
        }
        // A secant point within the resolution of an end is moved to half the
        // resolution from it. Once an end sits on the switch, the secant points
        // crowd it and the other end would only creep in by Illinois halvings (up
        // to ~30 evaluations); this way the next point either closes the bracket
        // or moves the far end.
        m = m.clamp(a + NUDGE, b - NUDGE);
        if !resolved(m) {
            // The point is not strictly inside in time: bisect instead.
            m = 0.5 * (a + b);
            if !resolved(m) {
                break;
            }
        }
        let gm = g(m, y_event)?;
        if gm < 0.0 {
            (b, gb) = (m, gm);
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        } else {
            (a, ga) = (m, gm);
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        }
    }
    extension(b, y_event);
    Ok(Some(b))
}

/// Ends an accepted step from `t` of size `h` (s) that reached `y_new` at `t_end`:
/// with `crossed` (the switching margin at the step's start and each stage's node
/// and margin, when a stage crossed a switching surface) the first switch is
/// located on the step's continuous extension ([`locate`]; its state goes to
/// `y_event`, `scratch` takes slopes). The system is then told the step ended, at
/// the switch if one was found, and the samples up to there are served from
/// `extension` (`out` holds each). Returns the switch's fraction `θ` of the step.
pub(crate) fn end_step<S, O>(
    sys: &mut S,
    samples: &mut Samples<'_, O>,
    (t, h, t_end): (f64, f64, f64),
    extension: impl Fn(f64, &mut [f64]),
    crossed: Option<(f64, impl Iterator<Item = (f64, f64)>)>,
    (y_new, y_event, scratch, out): (&[f64], &mut [f64], &mut [f64], &mut [f64]),
    stats: &mut Stats,
) -> Result<Option<f64>, SolveError>
where
    S: OdeSystem,
    O: FnMut(&mut S, f64, &[f64]) -> Result<(), ModelError>,
{
    let event = match crossed {
        Some(margins) => locate(sys, (t, h), &extension, margins, (y_event, scratch), stats)?,
        None => None,
    };
    let (t_serve, y_serve): (f64, &[f64]) = match event {
        Some(theta) => (t + theta * h, y_event),
        None => (t_end, y_new),
    };
    accept(sys, t_serve, y_serve)?;
    samples.serve(sys, t_serve, y_serve, out, |ts, o| {
        extension((ts - t) / h, o)
    })?;
    Ok(event)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::ModelError;
    use crate::solve::output::StepEnds;

    /// Switches chatter once [`CHATTER_SWITCHES`] of the last 64 accepted steps
    /// ended at one, in a row or every other step, and not while fewer did.
    #[test]
    fn chatter_is_half_the_steps_ending_at_switches() {
        let mut watch = ChatterWatch::default();
        let fired = |watch: &mut ChatterWatch, pattern: &dyn Fn(u32) -> bool, steps: u32| {
            (0..steps).position(|i| watch.step(pattern(i)))
        };
        assert_eq!(
            fired(&mut watch, &|_| true, 100),
            Some(CHATTER_SWITCHES as usize - 1)
        );
        let mut watch = ChatterWatch::default();
        assert_eq!(fired(&mut watch, &|i| i % 2 == 1, 100), Some(63));
        let mut watch = ChatterWatch::default();
        assert_eq!(fired(&mut watch, &|i| i % 3 == 0, 1000), None);
    }

    /// A system whose switching margin is `SWITCH − y` (m); [`locate`] takes the
    /// state from the continuous extension and only the margin from the system.
    struct Ramp {
        margin: f64,
    }

    const SWITCH: f64 = 0.3;

    impl OdeSystem for Ramp {
        fn dim(&self) -> usize {
            1
        }

        fn rhs(&mut self, _t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
            self.margin = SWITCH - y[0];
            dydt[0] = 0.0;
            Ok(())
        }

        fn margin(&self) -> f64 {
            self.margin
        }
    }

    /// Once an end of the bracket sits on the switch (here the first, from a stage
    /// node), the bracket must close at once instead of the far end creeping in by
    /// bisection (33 evaluations here without [`NUDGE`]).
    #[test]
    fn a_switch_is_located_in_few_evaluations() {
        // The cubic Hermite extension is exact for `y = θ + θ²`. Late in a run
        // (`t0` = 1000 s) time resolves only ~1e-13 of the step: the secant points
        // next to an end on the switch are not distinct times.
        let ends = StepEnds {
            t0: 1000.0,
            h: 1.0,
            y0: &[0.0],
            y1: &[2.0],
            f0: &[1.0],
            f1: &[3.0],
        };
        let mut sys = Ramp { margin: 0.0 };
        let mut stats = Stats::default();
        let (mut y_event, mut f_end) = ([0.0], [0.0]);
        let switch = ((1.0 + 4.0 * SWITCH).sqrt() - 1.0) / 2.0;
        // A stage node on the switch (the first float past it on the extension)
        // brackets it at once, from far below.
        let mut node = switch;
        let mut y = [0.0];
        loop {
            ends.continuous(node, &[], &mut y);
            if SWITCH - y[0] < 0.0 {
                break;
            }
            node = f64::from_bits(node.to_bits() + 1);
        }
        let stages = [(node, SWITCH - y[0]), (1.0, SWITCH - 2.0)];
        let theta = locate(
            &mut sys,
            (ends.t0, ends.h),
            |theta, y| ends.continuous(theta, &[], y),
            (SWITCH, stages.into_iter()),
            (&mut y_event, &mut f_end),
            &mut stats,
        )
        .unwrap()
        .unwrap();
        assert!(
            (theta - switch).abs() <= EVENT_RESOLUTION,
            "θ = {theta}, switch at {switch}"
        );
        assert!(SWITCH - y_event[0] < 0.0, "the state is past the switch");
        assert!(stats.rhs_evals <= 3, "{} evaluations", stats.rhs_evals);
    }
}
