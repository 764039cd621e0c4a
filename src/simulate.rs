//! Running one case: integrate a [`SliderCrank`] and sample the outputs of
//! docs/model.md §5.2 at exact, uniformly spaced sample times. The ideal mechanism has no
//! state and is sampled in closed form, without an integrator.

use std::ops::Range;
use std::time::Instant;

use crate::error::ParamError;
use crate::mechanism::{CaseModel, CaseParams, Location, Sample, SliderCrank};
use crate::solve::{integrate, SolveError, SolverSettings, Stats};

/// Uniform output sampling: times `k / sample_rate` for `k = 0..=n` with
/// `n = round(duration × sample_rate)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    /// Simulated time (s, > 0).
    pub duration: f64,
    /// Output samples per second (Hz, > 0).
    pub sample_rate: f64,
}

impl Sampling {
    /// Checks both fields, that the number of samples is sane (≤ 1e9) and that the
    /// duration is a whole number of sample intervals (to 1e-6 of one), so that the
    /// last sample is at `t = duration`.
    pub fn validate(&self) -> Result<(), ParamError> {
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(ParamError::new(
                "duration",
                self.duration,
                "finite and > 0 s",
            ));
        }
        if !(self.sample_rate.is_finite() && self.sample_rate > 0.0) {
            return Err(ParamError::new(
                "sample_rate",
                self.sample_rate,
                "finite and > 0 Hz",
            ));
        }
        if self.duration * self.sample_rate > 1e9 {
            return Err(ParamError::new(
                "sample_rate",
                self.sample_rate,
                "at most 1e9 samples per case (duration x sample_rate)",
            ));
        }
        // The last sample is at t = duration: a whole number of sample intervals.
        let intervals = self.duration * self.sample_rate;
        if (intervals - intervals.round()).abs() > 1e-6 {
            let n = intervals.floor().max(1.0);
            // Twelve significant digits: enough to land on a sample, few enough to read.
            let nearby =
                |x: f64| crate::error::number(format!("{x:.11e}").parse::<f64>().unwrap_or(x));
            return Err(ParamError::new(
                "duration",
                self.duration,
                format!(
                    "a whole number of sample intervals: duration x sample_rate = {} is not \
                     one, so no sample would fall at t = duration; {} s or {} s would be, at {} Hz",
                    nearby(intervals),
                    nearby(n / self.sample_rate),
                    nearby((n + 1.0) / self.sample_rate),
                    crate::error::number(self.sample_rate),
                ),
            ));
        }
        Ok(())
    }

    /// Number of samples, both ends included.
    pub fn len(&self) -> usize {
        (self.duration * self.sample_rate).round() as usize + 1
    }

    /// Always false: a sampling has at least the sample at t = 0.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The analysed window after `transient` (s): the indices of the samples at
    /// `transient ≤ t < duration`, from `ceil(transient × sample_rate)` (to within
    /// 1e-9 of a sample) up to but excluding the last sample. The window is
    /// half-open so that a window of whole crank revolutions holds each crank phase
    /// once: its periodic Hann spectrum then puts the crank harmonics on bins, and
    /// its mean square is the revolution's, with no end sample counted twice.
    pub fn analysis_window(&self, transient: f64) -> Range<usize> {
        let last = self.len() - 1;
        let start = (transient * self.sample_rate - 1e-9).ceil().max(0.0) as usize;
        start.min(last)..last
    }

    /// The sample times (s), computed as `k / sample_rate`, never accumulated.
    pub fn times(&self) -> Vec<f64> {
        (0..self.len())
            .map(|k| sample_time(k, self.sample_rate))
            .collect()
    }
}

/// The time (s) of sample `k` at `sample_rate` (Hz): `k / sample_rate`, the bits every
/// series, spectrum window and study file's `time` use.
pub fn sample_time(k: usize, sample_rate: f64) -> f64 {
    k as f64 / sample_rate
}

/// One output channel: a named scalar time series of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Channel {
    /// Variable name in files.
    pub name: &'static str,
    /// CF-style units.
    pub units: &'static str,
    /// Human-readable description.
    pub long_name: &'static str,
    /// The effect (its name in `effects:`) without which the channel is not simulated; `None` for every case.
    pub effect: Option<&'static str>,
}

/// The output channels, in file order. For the ideal mechanism the `bearing_*`,
/// `eccentricity_*` and `loaded_balls` channels are NaN, 0 and 0; compare with its
/// `crank_ground_force_*` or `crank_rod_force_*` instead. The `housing_*` channels
/// exist with the housing effect only, NaN for a case without a housing (the ideal
/// mechanism).
pub const CHANNELS: [Channel; 14] = [
    Channel {
        name: "slider_acceleration",
        units: "m s-2",
        long_name: "slider acceleration",
        effect: None,
    },
    Channel {
        name: "crank_moment",
        units: "N m",
        long_name: "driving moment on the crank (counter-clockwise positive)",
        effect: None,
    },
    Channel {
        name: "bearing_force",
        units: "N",
        long_name: "bearing equivalent reaction force |F|",
        effect: None,
    },
    Channel {
        name: "bearing_force_x",
        units: "N",
        long_name: "bearing force on the housing, x",
        effect: None,
    },
    Channel {
        name: "bearing_force_y",
        units: "N",
        long_name: "bearing force on the housing, y",
        effect: None,
    },
    Channel {
        name: "eccentricity_x",
        units: "m",
        long_name: "bearing eccentricity (journal minus housing centre), x",
        effect: None,
    },
    Channel {
        name: "eccentricity_y",
        units: "m",
        long_name: "bearing eccentricity (journal minus housing centre), y",
        effect: None,
    },
    Channel {
        name: "loaded_balls",
        units: "1",
        long_name: "number of loaded balls",
        effect: None,
    },
    Channel {
        name: "crank_ground_force_x",
        units: "N",
        long_name: "force on the ground from the crank at the crank-ground joint, x",
        effect: None,
    },
    Channel {
        name: "crank_ground_force_y",
        units: "N",
        long_name: "force on the ground from the crank at the crank-ground joint, y",
        effect: None,
    },
    Channel {
        name: "crank_rod_force_x",
        units: "N",
        long_name: "force on the crank from the rod at the crank-rod joint, x",
        effect: None,
    },
    Channel {
        name: "crank_rod_force_y",
        units: "N",
        long_name: "force on the crank from the rod at the crank-rod joint, y",
        effect: None,
    },
    Channel {
        name: "housing_acceleration_x",
        units: "m s-2",
        long_name: "acceleration of the housing carrying the outer race, x",
        effect: Some("housing"),
    },
    Channel {
        name: "housing_acceleration_y",
        units: "m s-2",
        long_name: "acceleration of the housing carrying the outer race, y",
        effect: Some("housing"),
    },
];

/// Index of a channel in [`CHANNELS`] by name.
pub fn channel_index(name: &str) -> Option<usize> {
    CHANNELS.iter().position(|c| c.name == name)
}

/// The values of every channel in [`CHANNELS`] order for one sample.
pub fn channel_values(s: &Sample, location: Location) -> [f64; CHANNELS.len()] {
    let f = s.joint_force(location).unwrap_or([f64::NAN; 2]);
    [
        s.slider_acceleration,
        s.crank_moment,
        // Forces are far from overflow: no need for `hypot`'s scaling.
        (f[0] * f[0] + f[1] * f[1]).sqrt(),
        f[0],
        f[1],
        s.eccentricity[0],
        s.eccentricity[1],
        s.loaded_balls as f64,
        s.crank_ground_force[0],
        s.crank_ground_force[1],
        s.crank_rod_force[0],
        s.crank_rod_force[1],
        s.housing_acceleration[0],
        s.housing_acceleration[1],
    ]
}

/// The sampled outputs of one case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseOutput {
    /// Where the bearing sat.
    pub location: Location,
    /// Sample times (s).
    pub times: Vec<f64>,
    /// `channels[c][k]`: channel `c` of [`CHANNELS`] at `times[k]`.
    pub channels: Vec<Vec<f64>>,
    /// Integrator work.
    pub stats: Stats,
    /// Wall-clock time of the integration and sampling (s).
    pub wall_time: f64,
}

impl CaseOutput {
    /// The series of the channel called `name`, if there is one.
    pub fn channel(&self, name: &str) -> Option<&[f64]> {
        channel_index(name).map(|c| self.channels[c].as_slice())
    }
}

/// Why a case could not be simulated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CaseError {
    /// A parameter is out of range.
    #[error(transparent)]
    Param(#[from] ParamError),
    /// The integration stopped early.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// The model a case runs, chosen once per case: the production [`SliderCrank`]
/// (minimal coordinates). The one place a new mechanism or formulation plugs in.
pub fn build_model(case: &CaseParams) -> Result<SliderCrank, ParamError> {
    SliderCrank::new(case)
}

/// Simulates one case with `solver`, sampled as `sampling` says.
pub fn simulate(
    case: &CaseParams,
    solver: &SolverSettings,
    sampling: &Sampling,
) -> Result<CaseOutput, CaseError> {
    sampling.validate()?;
    let start = Instant::now();
    let model = build_model(case)?;
    let mut out = simulate_model(model, solver, sampling)?;
    out.wall_time = start.elapsed().as_secs_f64();
    Ok(out)
}

/// [`simulate`] from the journal-centre eccentricity `e` (m) at `t = 0` instead of
/// the housing centre: one perturbed replicate of a case (docs/model.md §9.5).
pub fn simulate_perturbed(
    case: &CaseParams,
    solver: &SolverSettings,
    sampling: &Sampling,
    e: [f64; 2],
) -> Result<CaseOutput, CaseError> {
    sampling.validate()?;
    let start = Instant::now();
    let model = build_model(case)?.with_initial_eccentricity(e);
    let mut out = simulate_model(model, solver, sampling)?;
    out.wall_time = start.elapsed().as_secs_f64();
    Ok(out)
}

/// Integrates `model` with `solver` and samples its outputs at `sampling`'s times
/// (validated by the caller); a model without state is sampled in closed form.
pub fn simulate_model<M: CaseModel>(
    model: M,
    solver: &SolverSettings,
    sampling: &Sampling,
) -> Result<CaseOutput, SolveError> {
    integrate_model(model, solver, sampling)?.sample()
}

/// Integrates `case` with `solver` at `sampling`'s times, leaving the sampling of a
/// model whose outputs are pure to [`Integrated::sample`] (which may run on another
/// thread).
pub fn integrate_case(
    case: &CaseParams,
    solver: &SolverSettings,
    sampling: &Sampling,
) -> Result<Integrated<SliderCrank>, CaseError> {
    sampling.validate()?;
    Ok(integrate_model(build_model(case)?, solver, sampling)?)
}

/// A case integrated: sampled as it went, or, for a model whose outputs depend on
/// the state alone ([`CaseModel::outputs_are_pure`]), with its states at the sample
/// times kept for [`Integrated::sample`], which gives the same bits.
pub enum Integrated<M> {
    /// Sampled during the integration.
    Sampled(CaseOutput),
    /// The states at the sample times, to be sampled.
    States(States<M>),
}

/// A pure model's states at its sample times.
pub struct States<M> {
    model: M,
    times: Vec<f64>,
    /// The state at `times[k]`: `values[k * dim .. (k + 1) * dim]`.
    values: Vec<f64>,
    dim: usize,
    stats: Stats,
    /// Wall-clock time of the integration (s).
    wall_time: f64,
}

impl<M: CaseModel> Integrated<M> {
    /// The case's outputs at its sample times.
    pub fn sample(self) -> Result<CaseOutput, SolveError> {
        let states = match self {
            Integrated::Sampled(out) => return Ok(out),
            Integrated::States(states) => states,
        };
        let start = Instant::now();
        let States {
            mut model,
            times,
            values,
            dim,
            stats,
            wall_time,
        } = states;
        let location = model.location();
        let mut channels = empty_channels(times.len());
        let mut record = recorder(&mut channels, location);
        for (&t, y) in times.iter().zip(values.chunks_exact(dim)) {
            record(&mut model, t, y).map_err(|source| SolveError::Model { t, source })?;
        }
        drop(record);
        Ok(CaseOutput {
            location,
            times,
            channels,
            stats,
            wall_time: wall_time + start.elapsed().as_secs_f64(),
        })
    }
}

/// One series per [`CHANNELS`] entry, each with room for `n` samples up front
/// (`vec![v; n]` would clone `v` without its capacity).
fn empty_channels(n: usize) -> Vec<Vec<f64>> {
    CHANNELS.iter().map(|_| Vec::with_capacity(n)).collect()
}

/// The observer that samples a model's outputs into `channels`.
fn recorder<M: CaseModel>(
    channels: &mut [Vec<f64>],
    location: Location,
) -> impl FnMut(&mut M, f64, &[f64]) -> Result<(), crate::error::ModelError> + '_ {
    move |m: &mut M, t: f64, y: &[f64]| {
        let s = m.sample(t, y)?;
        for (c, v) in channels.iter_mut().zip(channel_values(&s, location)) {
            c.push(v);
        }
        Ok(())
    }
}

/// Integrates `model` at `sampling`'s times: sampled as it goes, or, when its outputs
/// are pure, keeping its states for [`Integrated::sample`]. A run that stops early
/// reports the first sample that fails before it, as sampling on the way would have.
pub fn integrate_model<M: CaseModel>(
    mut model: M,
    solver: &SolverSettings,
    sampling: &Sampling,
) -> Result<Integrated<M>, SolveError> {
    let start = Instant::now();
    let times = sampling.times();
    let location = model.location();
    if model.dim() == 0 {
        let mut channels = empty_channels(times.len());
        let mut record = recorder(&mut channels, location);
        for &t in &times {
            record(&mut model, t, &[]).map_err(|source| SolveError::Model { t, source })?;
        }
        drop(record);
        return Ok(Integrated::Sampled(CaseOutput {
            location,
            times,
            channels,
            stats: Stats::default(),
            wall_time: start.elapsed().as_secs_f64(),
        }));
    }
    let y0 = model.initial_state();
    if !model.outputs_are_pure() {
        let mut channels = empty_channels(times.len());
        let stats = integrate(
            &mut model,
            solver,
            0.0,
            &y0,
            &times,
            recorder(&mut channels, location),
        )?;
        return Ok(Integrated::Sampled(CaseOutput {
            location,
            times,
            channels,
            stats,
            wall_time: start.elapsed().as_secs_f64(),
        }));
    }
    let dim = y0.len();
    let mut values = Vec::with_capacity(times.len() * dim);
    let keep = |_: &mut M, _: f64, y: &[f64]| {
        values.extend_from_slice(y);
        Ok(())
    };
    let run = integrate(&mut model, solver, 0.0, &y0, &times, keep);
    let states = States {
        model,
        values,
        dim,
        stats: run.as_ref().copied().unwrap_or_default(),
        wall_time: start.elapsed().as_secs_f64(),
        times,
    };
    match run {
        Ok(_) => Ok(Integrated::States(states)),
        Err(e) => {
            // The samples served before the run stopped, as they would have been.
            let served = states.values.len() / dim;
            let times = states.times[..served].to_vec();
            let early = States { times, ..states };
            Integrated::States(early).sample().and(Err(e))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanism::CartesianSliderCrank;

    /// The largest |difference| of two runs' slider accelerations (m/s²) and the
    /// range of the second's.
    fn slider_difference(a: &CaseOutput, b: &CaseOutput) -> (f64, f64) {
        let (a, b) = (
            a.channel("slider_acceleration").unwrap(),
            b.channel("slider_acceleration").unwrap(),
        );
        let range = b.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x))
            - b.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let worst = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        (worst, range)
    }

    /// A pure model sampled after its integration, from the states it kept, gives the
    /// bits of sampling it on the way; a model with memory is sampled on the way.
    #[test]
    fn outputs_sampled_after_the_integration_are_the_same_bits() {
        let case = CaseParams {
            location: Location::CrankGround,
            rpm: 600.0,
            ..CaseParams::default()
        };
        let sampling = Sampling {
            duration: 0.05,
            sample_rate: 20_000.0,
        };
        let solver = SolverSettings::default();
        let model = SliderCrank::new(&case).unwrap();
        assert!(model.outputs_are_pure());
        let run = integrate_model(model, &solver, &sampling).unwrap();
        assert!(matches!(run, Integrated::States(_)));
        let after = run.sample().unwrap();
        let mut model = SliderCrank::new(&case).unwrap();
        let times = sampling.times();
        let mut channels = empty_channels(times.len());
        let y0 = model.initial_state();
        let observe = recorder(&mut channels, case.location);
        let stats = integrate(&mut model, &solver, 0.0, &y0, &times, observe).unwrap();
        assert_eq!(stats, after.stats);
        for (c, (a, b)) in after.channels.iter().zip(&channels).enumerate() {
            let same = a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
            assert!(same && a.len() == b.len(), "channel {c}");
        }
        let journal = CaseParams {
            joint: crate::mechanism::JointKind::DryClearance,
            ..case
        };
        let model = SliderCrank::new(&journal).unwrap();
        assert!(!model.outputs_are_pure());
        let run = integrate_model(model, &solver, &sampling).unwrap();
        assert!(matches!(run, Integrated::Sampled(_)));
    }

    /// Both formulations run through the one seam: at crank_rod over 30 ms (through
    /// the first contacts), tightly integrated, their slider accelerations agree to
    /// 1e-6 of the channel's range.
    #[test]
    fn both_models_run_through_the_seam_and_agree() {
        let case = CaseParams {
            location: Location::CrankRod,
            rpm: 600.0,
            ..CaseParams::default()
        };
        let sampling = Sampling {
            duration: 0.03,
            sample_rate: 10_000.0,
        };
        let solver = SolverSettings::new(crate::solve::Method::Dop853 {
            rtol: 1e-12,
            atol: 1e-16,
        });
        let minimal = simulate_model(SliderCrank::new(&case).unwrap(), &solver, &sampling).unwrap();
        let cartesian = simulate_model(
            CartesianSliderCrank::new(&case).unwrap(),
            &solver,
            &sampling,
        )
        .unwrap();
        let (worst, range) = slider_difference(&minimal, &cartesian);
        assert!(worst < 1e-6 * range, "worst {worst:e} of range {range:e}");
    }

    /// A perturbed start puts the journal at the given eccentricity at `t = 0` in both
    /// formulations (the Cartesian one to 1e-15 m); at crank_ground, where both also
    /// start the journal at rest relative to the housing, they then move alike: over
    /// 5 ms their slider accelerations agree to 1e-6 of its range, as unperturbed.
    #[test]
    fn perturbed_start_displaces_the_journal_in_both_models() {
        let e = [3e-7, -2e-7];
        let sampling = Sampling {
            duration: 0.005,
            sample_rate: 10_000.0,
        };
        let solver = SolverSettings::new(crate::solve::Method::Dop853 {
            rtol: 1e-12,
            atol: 1e-16,
        });
        for location in [Location::CrankGround, Location::CrankRod] {
            let case = CaseParams {
                location,
                rpm: 600.0,
                ..CaseParams::default()
            };
            let minimal = simulate_perturbed(&case, &solver, &sampling, e).unwrap();
            let model = CartesianSliderCrank::new(&case)
                .unwrap()
                .with_initial_eccentricity(e);
            let cartesian = simulate_model(model, &solver, &sampling).unwrap();
            for (k, ch) in ["eccentricity_x", "eccentricity_y"].iter().enumerate() {
                let (a, b) = (minimal.channel(ch).unwrap(), cartesian.channel(ch).unwrap());
                assert_eq!(a[0], e[k], "{location:?} {ch}");
                assert!((b[0] - e[k]).abs() < 1e-15, "{location:?} {ch}: {}", b[0]);
            }
            if location == Location::CrankRod {
                continue;
            }
            let (worst, range) = slider_difference(&minimal, &cartesian);
            assert!(worst < 1e-6 * range, "{location:?}: {worst:e} of {range:e}");
        }
    }

    #[test]
    fn analysis_window_is_half_open_from_the_transient() {
        let s = Sampling {
            duration: 0.4,
            sample_rate: 50_000.0,
        };
        assert_eq!(s.len(), 20_001);
        // One revolution at 300 rpm: 10 000 samples, the one at t = 0.4 s left out.
        assert_eq!(s.analysis_window(0.2), 10_000..20_000);
        assert_eq!(s.analysis_window(0.0), 0..20_000);
        // A transient between samples starts at the next one; one within 1e-9 of a
        // sample (here 0.2 s written as 0.1 + 0.1) starts on it.
        assert_eq!(s.analysis_window(0.200_01).start, 10_001);
        assert_eq!(s.analysis_window(0.1 + 0.1).start, 10_000);
        // Nothing left: an empty window, never one past the end.
        assert!(s.analysis_window(0.4).is_empty());
        assert!(s.analysis_window(1.0).is_empty());
    }
}
