//! Helpers shared by `tests/hard_cases.rs`, `tests/properties.rs` and
//! `tests/stiffness.rs`: one instrumented run of a slider-crank case with the energy
//! ledger on, on either model ([`Model`]: the Cartesian reference or the production
//! minimal-coordinate model), and the checks every hard case makes (finite outputs,
//! eccentricity within physical bounds, docs/model.md §4.4's energy balance,
//! constraint residuals).
#![allow(dead_code)]

use std::f64::consts::PI;
use std::fmt;
use std::time::Instant;

use studyrun::bearing::{BearingParams, DampingModel, RaceWaviness};
use studyrun::error::ModelError;
use studyrun::mechanism::{CartesianSliderCrank, CaseParams, Location, Sample, SliderCrank};
use studyrun::multibody::{ForceElement, Ledger};
use studyrun::solve::{integrate, Method, OdeSystem, SolveError, SolverSettings, Stats};

/// Which formulation of the slider-crank a hard case runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// `CartesianSliderCrank`: the general multibody core (docs/model.md §4), which
    /// steps across contact switches.
    Reference,
    /// `SliderCrank`: the minimal-coordinate model every study runs (§3), with the
    /// contact switches located (`locate_events`, on by default) and its own ledger
    /// (§3.8).
    Production,
}

/// Both models, reference first.
pub const MODELS: [Model; 2] = [Model::Reference, Model::Production];

impl fmt::Display for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Model::Reference => "reference",
            Model::Production => "production",
        })
    }
}

/// A model with its energy ledger on that can record a sample.
pub trait Instrumented: OdeSystem {
    /// The outputs, energies, ledger and constraint residuals at `(t, y)`.
    fn record(&mut self, t: f64, y: &[f64]) -> Result<Record, ModelError>;
}

impl Instrumented for CartesianSliderCrank {
    fn record(&mut self, t: f64, y: &[f64]) -> Result<Record, ModelError> {
        let sample = self.sample(t, y)?;
        let s = self.system_mut();
        let (kinetic, potential, ledger) = (s.kinetic_energy(), s.potential_energy(t), s.ledger(y));
        let contact_potential = s
            .elements()
            .iter()
            .map(|e| e.energy(t, s.q(), s.qd()).potential)
            .sum();
        let position_residual = s.position_residual(t);
        let velocity_residual = s.velocity_residual(t);
        Ok(Record {
            t,
            sample,
            kinetic,
            potential,
            contact_potential,
            ledger,
            position_residual,
            velocity_residual,
        })
    }
}

/// The constraints hold by construction: the residuals are 0.
impl Instrumented for SliderCrank {
    fn record(&mut self, t: f64, y: &[f64]) -> Result<Record, ModelError> {
        let sample = self.sample(t, y)?;
        let energy = self.energy(t, y)?;
        Ok(Record {
            t,
            sample,
            kinetic: energy.kinetic,
            potential: energy.potential,
            contact_potential: energy.contact_potential,
            ledger: self.ledger(y),
            position_residual: 0.0,
            velocity_residual: 0.0,
        })
    }
}

/// A model with a record of the integrator's accepted steps: their end times,
/// whether each ended at a located switch, and the longest run of right-hand-side
/// evaluations between two accepted steps (which counts the attempts of rejected
/// steps in between; on the production model also the evaluations that locate a
/// switch, and not the step that recomputes the state there).
pub struct Probe<M> {
    pub mech: M,
    pub accepted: Vec<f64>,
    /// Per accepted step: it ended at a located switch.
    pub at_switch: Vec<bool>,
    evals_since_accept: u64,
    pub max_evals_between_accepts: u64,
}

impl<M> Probe<M> {
    pub fn new(mech: M) -> Self {
        Self {
            mech,
            accepted: Vec::new(),
            at_switch: Vec::new(),
            evals_since_accept: 0,
            max_evals_between_accepts: 0,
        }
    }
}

impl<M: OdeSystem> OdeSystem for Probe<M> {
    fn dim(&self) -> usize {
        self.mech.dim()
    }
    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        self.evals_since_accept += 1;
        self.mech.rhs(t, y, dydt)
    }
    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        self.max_evals_between_accepts =
            self.max_evals_between_accepts.max(self.evals_since_accept);
        self.evals_since_accept = 0;
        self.accepted.push(t);
        self.at_switch.push(false);
        self.mech.accept_step(t, y)
    }
    fn hold_regime(&mut self, t: f64, y: &[f64]) -> Result<bool, ModelError> {
        // After the first, each new regime is a restart at a located switch, where
        // the step just accepted ended; the step that recomputes the state there
        // ran since.
        if let Some(last) = self.at_switch.last_mut() {
            *last = true;
        }
        self.evals_since_accept = 0;
        self.mech.hold_regime(t, y)
    }
    fn release_regime(&mut self) {
        self.mech.release_regime()
    }
    fn margin(&self) -> f64 {
        self.mech.margin()
    }
}

/// What the observer saw at one sample time.
#[derive(Debug, Clone, Copy)]
pub struct Record {
    /// Time (s).
    pub t: f64,
    /// The outputs of docs/model.md §5.2.
    pub sample: Sample,
    /// Kinetic energy (J).
    pub kinetic: f64,
    /// Potential energy: Hertz contacts plus gravity when on (J).
    pub potential: f64,
    /// Hertz potential of the bearing alone, `Σ 0.4 K δ_r^{5/2}` (J).
    pub contact_potential: f64,
    /// The energy ledger's quadratures.
    pub ledger: Ledger,
    /// Max-norm of `Φ(q, t)` (m or rad); 0 on the production model.
    pub position_residual: f64,
    /// Max-norm of `Φq q̇ + Φt` (m/s or rad/s); 0 on the production model.
    pub velocity_residual: f64,
}

/// One finished run.
pub struct Run {
    pub model: Model,
    pub records: Vec<Record>,
    pub stats: Stats,
    /// Wall-clock time of the integration (s).
    pub wall: f64,
    /// End times of the accepted steps (s).
    pub accepted: Vec<f64>,
    /// Per accepted step: it ended at a located switch (production model only).
    pub at_switch: Vec<bool>,
    /// Longest run of RHS evaluations between two accepted steps.
    pub max_evals_between_accepts: u64,
}

/// `n + 1` uniform sample times over `[0, duration]` (s).
pub fn uniform_times(duration: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| duration * k as f64 / n as f64).collect()
}

/// Integrates `mech` (ledger on) from its initial state `y0` and records every sample.
fn run_instrumented<M: Instrumented>(
    model: Model,
    mech: M,
    y0: Vec<f64>,
    settings: &SolverSettings,
    times: &[f64],
) -> Result<Run, SolveError> {
    let mut probe = Probe::new(mech);
    let mut records = Vec::with_capacity(times.len());
    let start = Instant::now();
    let stats = integrate(&mut probe, settings, 0.0, &y0, times, |p, t, y| {
        records.push(p.mech.record(t, y)?);
        Ok(())
    })?;
    Ok(Run {
        model,
        records,
        stats,
        wall: start.elapsed().as_secs_f64(),
        accepted: probe.accepted,
        at_switch: probe.at_switch,
        max_evals_between_accepts: probe.max_evals_between_accepts,
    })
}

/// Integrates `case` on `model` with the energy ledger on and records every sample.
pub fn run_model(
    model: Model,
    case: &CaseParams,
    settings: &SolverSettings,
    times: &[f64],
) -> Result<Run, SolveError> {
    match model {
        Model::Reference => {
            let mut mech = CartesianSliderCrank::new(case)
                .expect("valid case")
                .with_energy_ledger(true);
            let y0 = mech.initial_state();
            run_instrumented(model, mech, y0, settings, times)
        }
        Model::Production => {
            let mech = SliderCrank::new(case)
                .expect("valid case")
                .with_energy_ledger(true);
            let y0 = mech.initial_state();
            run_instrumented(model, mech, y0, settings, times)
        }
    }
}

/// Σ |offset| + Σ amplitudes of one race (m): the largest height its waviness reaches.
pub fn race_extent(w: &RaceWaviness) -> f64 {
    w.offset.abs() + w.harmonics.iter().map(|h| h.amplitude).sum::<f64>()
}

/// Both races' largest waviness height, `Σ` over races and harmonics (m).
pub fn waviness_extent(b: &BearingParams) -> f64 {
    race_extent(&b.inner_waviness) + race_extent(&b.outer_waviness)
}

/// The paper's bearing with waviness `number` / `amplitude` on both races.
pub fn wavy(number: u32, amplitude: f64) -> BearingParams {
    BearingParams {
        inner_waviness: RaceWaviness::single(number, amplitude),
        outer_waviness: RaceWaviness::single(number, amplitude),
        ..BearingParams::default()
    }
}

/// The paper's crank_ground case at `rpm` with 9 balls, `P_d` = 40 µm, K = 9.57e9,
/// C = 300 and waviness N = 35 / 4 µm on both races.
pub fn paper_case(location: Location, rpm: f64) -> CaseParams {
    CaseParams {
        location,
        rpm,
        bearing: wavy(35, 4e-6),
        ..CaseParams::default()
    }
}

/// DOPRI5 at `rtol`, `atol = 1e-4 rtol`.
pub fn dopri(rtol: f64) -> SolverSettings {
    SolverSettings::new(Method::DormandPrince {
        rtol,
        atol: rtol * 1e-4,
    })
}

/// Summary of the checks every hard case makes.
#[derive(Debug, Clone, Copy, Default)]
pub struct Checks {
    /// Largest |energy balance residual| over the run (J).
    pub energy_residual: f64,
    /// Largest |driver work| over the run (J): the balance's scale.
    pub driver_work_scale: f64,
    /// Energy dissipated by damping at the end (J).
    pub dissipated: f64,
    /// `energy_residual / max(driver_work_scale, floor)`.
    pub energy_relative: f64,
    /// Largest |e| (m).
    pub max_eccentricity: f64,
    /// Largest `|e| / bound` of the energy bound (see [`check_run`]).
    pub energy_bound_ratio: f64,
    /// Largest `|e| / bound` of the instantaneous force bound (NaN where it does not apply).
    pub force_bound_ratio: f64,
    /// Largest `|e| / bound` of the run-max force bound `(P_d/2 + ΣΠ + (max|F|/K)^{2/3}) / cos(π/N_b)`.
    pub run_bound_ratio: f64,
    /// Largest `|e| / (P_d/2 + ΣΠ + (max|F|/K)^{2/3})`: the run-max bound without the
    /// ball-spacing factor (recorded, never asserted).
    pub plain_bound_ratio: f64,
    /// Largest bearing force |F| (N).
    pub max_force: f64,
    /// Largest position / velocity residual over the run (m, m/s).
    pub max_position_residual: f64,
    pub max_velocity_residual: f64,
    /// Position / velocity residual at the last sample (m, m/s).
    pub end_position_residual: f64,
    pub end_velocity_residual: f64,
    /// Fewest / most loaded balls over the samples.
    pub min_loaded: usize,
    pub max_loaded: usize,
}

/// Position and velocity residual limits of every hard case (m, m/s).
pub const POSITION_RESIDUAL_LIMIT: f64 = 1e-9;
pub const VELOCITY_RESIDUAL_LIMIT: f64 = 1e-7;

/// What [`check_run`] asserts beyond finiteness, bounds and residuals.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    /// Largest allowed `max |energy residual| / max(max|W|, energy_floor)`.
    pub energy_tol: f64,
    /// Floor of the energy scale (J), for runs whose driver work is tiny.
    pub energy_floor: f64,
    /// Also assert the run-max force bound (a heuristic bound, see [`check_run`]).
    pub run_max_force_bound: bool,
}

/// The energy balance residual `W − (ΔKE + ΔV − ∫∂V/∂t dt + E_diss)` at each record (J).
pub fn energy_residuals(run: &Run) -> Vec<f64> {
    let first = run.records[0];
    run.records
        .iter()
        .map(|r| {
            let l = r.ledger;
            l.driver_work
                - (r.kinetic - first.kinetic + r.potential
                    - first.potential
                    - l.explicit_potential_work
                    + l.dissipated)
        })
        .collect()
}

/// Checks a finished run of `case` and returns what it measured; `name` labels
/// failures. Asserts:
///
/// * every output (with the force at the case's joint), energy and ledger entry is
///   finite at every sample;
/// * the eccentricity is physically possible at every sample. Ball `b`, the one
///   nearest the direction of `e`, is at most `π/N_b` away from it, so
///   `|e| cos(π/N_b) ≤ e·n_b = δ_b + P_d/2 − Π_b ≤ δ_b + P_d/2 + ΣΠ` (ΣΠ: every
///   waviness amplitude and offset of both races). The factor `1/cos(π/N_b)` is
///   geometry, not slack: with 3 balls a journal heading between two of them
///   travels `P_d` (not `P_d/2`) before it touches either. Bounds on `δ_b`:
///   - *energy* (always asserted, rigorous at every instant): the ball's Hertz
///     potential is part of the bearing's, `0.4 K δ_b^{5/2} ≤ V_contact` at the
///     same sample;
///   - *instantaneous force* (asserted where it is rigorous: `P_d/2 ≥ ΣΠ` and ball
///     forces `≥ K δ^{3/2}`, i.e. compression-only damping or C = 0): then every
///     loaded ball has `n_r·e > 0`, so `|F| ≥ F·ê ≥ K δ_b^{3/2} cos(π/N_b)` and
///     `δ_b ≤ (|F(t)| / (K cos(π/N_b)))^{2/3}`;
///   - *run-max force* (the single-ball bound, with the spacing
///     factor; asserted when `limits.run_max_force_bound`): `δ_b ≤ (max|F|/K)^{2/3}`
///     with the largest |F| of the run. Not rigorous under preload or waviness
///     beyond `P_d/2`, where balls on opposite sides push against each other and |F|
///     underestimates a ball's force (a preloaded journal at rest has |F| ≈ 0).
/// * the energy balance closes: `max |residual| ≤ energy_tol · max(max|W|, energy_floor)`,
///   and the dissipated energy is not negative;
/// * constraint residuals stay below [`POSITION_RESIDUAL_LIMIT`] and
///   [`VELOCITY_RESIDUAL_LIMIT`] at every sample.
pub fn check_run(name: &str, case: &CaseParams, run: &Run, limits: Limits) -> Checks {
    let mut c = check_common(name, case, run, limits);
    let b = &case.bearing;
    // Eccentricity bounds; a relative slack of 1e-12 (plus 1e-15 m) covers round-off.
    let within = |e: f64, bound: f64| e <= bound * (1.0 + 1e-12) + 1e-15;
    let spacing = (PI / b.ball_count as f64).cos();
    let geometric = 0.5 * b.clearance + waviness_extent(b);
    let single_ball = (c.max_force / b.stiffness).powf(2.0 / 3.0);
    let run_bound = (geometric + single_ball) / spacing;
    let plain_bound = geometric + single_ball;
    let force_applies = 0.5 * b.clearance >= waviness_extent(b)
        && (b.damping_model == DampingModel::CompressionOnly || b.damping == 0.0);
    for r in &run.records {
        let e = r.sample.eccentricity[0].hypot(r.sample.eccentricity[1]);
        c.max_eccentricity = c.max_eccentricity.max(e);
        let energy_bound =
            (geometric + (r.contact_potential / (0.4 * b.stiffness)).powf(0.4)) / spacing;
        assert!(
            within(e, energy_bound),
            "{name}: |e| = {e:e} m above the energy bound {energy_bound:e} m at t = {}",
            r.t
        );
        c.energy_bound_ratio = c.energy_bound_ratio.max(e / energy_bound);
        if force_applies {
            let f = r.sample.joint_force(case.location).unwrap();
            let force_bound = (geometric
                + (f[0].hypot(f[1]) / (b.stiffness * spacing)).powf(2.0 / 3.0))
                / spacing;
            assert!(
                within(e, force_bound),
                "{name}: |e| = {e:e} m above the force bound {force_bound:e} m at t = {}",
                r.t
            );
            c.force_bound_ratio = (e / force_bound).max(if c.force_bound_ratio.is_nan() {
                0.0
            } else {
                c.force_bound_ratio
            });
        }
        if limits.run_max_force_bound {
            assert!(
                within(e, run_bound),
                "{name}: |e| = {e:e} m above the run-max force bound {run_bound:e} m at t = {}",
                r.t
            );
        }
        c.run_bound_ratio = c.run_bound_ratio.max(e / run_bound);
        c.plain_bound_ratio = c.plain_bound_ratio.max(e / plain_bound);
    }

    c
}

/// Checks a finished run of a plain-journal `case` (docs/model.md §2.10); `name`
/// labels failures. Asserts what [`check_run`] asserts of every output, the energy
/// balance and the residuals, and the journal's eccentricity bound: the journal
/// penetrates the bushing by `δ = |e| − c`, whose contact potential
/// `0.4 K δ^{5/2}` is the sample's contact potential (a journal has one contact),
/// so `|e| ≤ c + (V_contact / (0.4 K))^{2/5}` at every sample, rigorous for any
/// damping law and for the lubricated joint (whose film adds no potential).
pub fn check_plain_run(name: &str, case: &CaseParams, run: &Run, limits: Limits) -> Checks {
    assert!(case.joint.is_plain(), "{name}: not a plain journal");
    let mut c = check_common(name, case, run, limits);
    let k = case.journal.contact_stiffness();
    let clearance = case.journal.geometry.clearance;
    for r in &run.records {
        let e = r.sample.eccentricity[0].hypot(r.sample.eccentricity[1]);
        c.max_eccentricity = c.max_eccentricity.max(e);
        let bound = clearance + (r.contact_potential / (0.4 * k)).powf(0.4);
        assert!(
            e <= bound * (1.0 + 1e-9) + 1e-15,
            "{name}: |e| = {e:e} m above the journal's energy bound {bound:e} m at t = {}",
            r.t
        );
        c.energy_bound_ratio = c.energy_bound_ratio.max(e / bound);
    }
    c
}

/// The checks both kinds of joint share: every output, energy and ledger entry is
/// finite, the energy balance closes and the residuals stay below their limits.
fn check_common(name: &str, case: &CaseParams, run: &Run, limits: Limits) -> Checks {
    let mut c = Checks {
        min_loaded: usize::MAX,
        force_bound_ratio: f64::NAN,
        ..Checks::default()
    };
    for r in &run.records {
        let s = &r.sample;
        let f = s.joint_force(case.location).unwrap();
        let values = [
            s.slider_acceleration,
            s.crank_moment,
            s.crank_ground_force[0],
            s.crank_ground_force[1],
            s.crank_rod_force[0],
            s.crank_rod_force[1],
            f[0],
            f[1],
            s.eccentricity[0],
            s.eccentricity[1],
            r.kinetic,
            r.potential,
            r.contact_potential,
            r.ledger.driver_work,
            r.ledger.explicit_potential_work,
            r.ledger.dissipated,
        ];
        assert!(
            values.iter().all(|v| v.is_finite()),
            "{name}: non-finite output at t = {}: {values:?}",
            r.t
        );
        c.max_force = c.max_force.max(f[0].hypot(f[1]));
        c.min_loaded = c.min_loaded.min(s.loaded_balls);
        c.max_loaded = c.max_loaded.max(s.loaded_balls);
        c.max_position_residual = c.max_position_residual.max(r.position_residual);
        c.max_velocity_residual = c.max_velocity_residual.max(r.velocity_residual);
    }
    let last = run.records.last().unwrap();
    c.end_position_residual = last.position_residual;
    c.end_velocity_residual = last.velocity_residual;

    // Energy balance.
    c.energy_residual = energy_residuals(run)
        .iter()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    c.driver_work_scale = run
        .records
        .iter()
        .fold(0.0f64, |m, r| m.max(r.ledger.driver_work.abs()));
    c.dissipated = last.ledger.dissipated;
    let scale = c.driver_work_scale.max(limits.energy_floor);
    c.energy_relative = c.energy_residual / scale;
    assert!(
        c.energy_relative <= limits.energy_tol,
        "{name}: energy balance residual {:e} J = {:e} of max(max|W| = {:e} J, floor {:e} J), limit {:e}",
        c.energy_residual,
        c.energy_relative,
        c.driver_work_scale,
        limits.energy_floor,
        limits.energy_tol
    );
    assert!(
        c.dissipated >= -limits.energy_tol * scale,
        "{name}: negative dissipation {:e} J",
        c.dissipated
    );

    // Constraint residuals.
    assert!(
        c.max_position_residual < POSITION_RESIDUAL_LIMIT,
        "{name}: position residual {:e} m",
        c.max_position_residual
    );
    assert!(
        c.max_velocity_residual < VELOCITY_RESIDUAL_LIMIT,
        "{name}: velocity residual {:e} m/s",
        c.max_velocity_residual
    );
    c
}

/// Prints one line of what a run measured.
pub fn report(name: &str, run: &Run, c: &Checks) {
    println!(
        "{name} [{}]: {} steps, {} rejected, {} RHS, {:.2} s | energy {:.2e} J / {:.3e} J = {:.2e} (dissipated {:.3e} J) | \
         |e|max {:.2} µm, |e|/bound energy {:.3} force {:.3} run-max {:.3} plain {:.3} | |F|max {:.1} N | balls {}..{} | \
         residuals max {:.1e} m {:.1e} m/s, end {:.1e} m {:.1e} m/s",
        run.model,
        run.stats.steps,
        run.stats.rejected,
        run.stats.rhs_evals,
        run.wall,
        c.energy_residual,
        c.driver_work_scale,
        c.energy_relative,
        c.dissipated,
        c.max_eccentricity * 1e6,
        c.energy_bound_ratio,
        c.force_bound_ratio,
        c.run_bound_ratio,
        c.plain_bound_ratio,
        c.max_force,
        c.min_loaded,
        c.max_loaded,
        c.max_position_residual,
        c.max_velocity_residual,
        c.end_position_residual,
        c.end_velocity_residual,
    );
}

/// A channel of the samples, by accessor.
pub fn series(run: &Run, f: impl Fn(&Sample) -> f64) -> Vec<f64> {
    run.records.iter().map(|r| f(&r.sample)).collect()
}

/// Slider acceleration series (m/s²).
pub fn slider_acceleration(run: &Run) -> Vec<f64> {
    series(run, |s| s.slider_acceleration)
}

/// Max |a − b| over the first `n` samples, relative to the range of `b` there.
pub fn max_relative_difference(a: &[f64], b: &[f64], n: usize) -> f64 {
    let (a, b) = (&a[..n], &b[..n]);
    let (lo, hi) = b
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max)
        / (hi - lo)
}

/// Root mean square of `x` (its units).
pub fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt()
}
