//! `studyrun accuracy GRID`: the error and cost of every integrator setting.

use super::*;
use studyrun::accuracy::{
    self, describe, setting_label, CaseReference, Measurement, ERROR_CHANNELS,
};
use studyrun::solve::Method;

/// One value of `accuracy --rtols`: a number the accuracy study can judge
/// ([`studyrun::accuracy::check_rtol`]).
pub(super) fn parse_rtol(text: &str) -> Result<f64, String> {
    let rtol: f64 = text
        .trim()
        .parse()
        .map_err(|_| format!("'{text}' is not a number"))?;
    studyrun::accuracy::check_rtol(rtol)?;
    Ok(rtol)
}

pub(super) fn accuracy_command(
    grid: &Path,
    output: Option<PathBuf>,
    limits: Limits,
    force: bool,
    (methods, rtols): (&[String], &[f64]),
) -> Result<u8> {
    if let Some(twice) = rtols
        .iter()
        .enumerate()
        .find_map(|(k, r)| rtols[..k].contains(r).then_some(r))
    {
        clap::Error::raw(
            clap::error::ErrorKind::ValueValidation,
            format!("--rtols: {twice:e} is given twice; give each rtol once\n"),
        )
        .exit();
    }
    let study = load(grid, &limits, None)?;
    if study.recordings.is_some() {
        return Err(StudyError {
            path: grid.to_path_buf(),
            location: None,
            field: "recordings".into(),
            message: "a study of measured recordings has nothing to integrate: `accuracy` \
                      measures integrators on simulated cases"
                .into(),
        }
        .into());
    }
    check_memory(grid, &study, &limits)?;
    let output = output.unwrap_or_else(|| PathBuf::from(format!("{}_accuracy.h5", study.name)));
    // The output first, before all the work: nothing there that is not ours, no
    // replacing without --force, only a study file with it, and the lock held to the end.
    output::overwrite::check_output(&output, force, &[grid])?;
    let _lock = output::OutputLock::acquire(&output)?;
    output::overwrite::check_output(&output, force, &[grid])?;
    let jobs = limits.jobs;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(jobs).build()?;
    let ladder = ladder(&study, methods, rtols);
    say!(
        "studyrun: accuracy of {} settings on {} cases (+2 reference runs each)",
        ladder.len(),
        study.cases.len()
    );
    let (refs, ms) = pool.install(|| accuracy::run(&study, &ladder))?;
    print_cases(&study, &refs, &ms)?;
    print_summary(&study, &refs, &ms, &ladder)?;
    accuracy::write_file(&output, &study, &refs, &ms)?;
    say!("studyrun: wrote {}", output.display());
    Ok(EXIT_OK)
}

/// Refuses a grid whose accuracy study would not fit `limits`: it keeps the reference
/// run (all channels) of every case to the end, and each worker two more runs.
fn check_memory(grid: &Path, study: &Study, limits: &Limits) -> Result<()> {
    let run_bytes = (CHANNELS.len() + 1) as f64 * 8.0 * study.sampling.len() as f64;
    let need = (study.cases.len() + study.references.len() + 3 * limits.jobs) as f64 * run_bytes
        + 64.0 * 1024.0 * 1024.0;
    if need > limits.memory as f64 {
        return Err(StudyError {
            path: grid.to_path_buf(),
            location: None,
            field: "grid".into(),
            message: format!(
                "the accuracy study keeps the reference run of each of its {} cases ({} each): \
                 about {} of memory, more than the limit of {}; fewer cases, a lower \
                 sample_rate or a shorter duration",
                study.cases.len(),
                memory::bytes(run_bytes),
                memory::bytes(need),
                limits.describe()
            ),
        }
        .into());
    }
    Ok(())
}

/// The settings measured: the default ladder or the adaptive methods at `rtols`, only
/// the `methods` named (all when none), and only settings a grid file could run (RK4
/// steps up to the sample spacing).
fn ladder(study: &Study, methods: &[String], rtols: &[f64]) -> Vec<Method> {
    let mut ladder = if rtols.is_empty() {
        accuracy::default_ladder()
    } else {
        accuracy::ladder_at(rtols)
    };
    if !methods.is_empty() {
        ladder.retain(|m| methods.iter().any(|name| name == describe(m).0));
    }
    // Only settings a grid file could run: RK4 steps up to the sample spacing.
    let spacing = 1.0 / study.sampling.sample_rate;
    ladder.retain(|m| accuracy::runnable(m, spacing));
    ladder
}

/// Per case: its horizon and reference uncertainty, then one table row per setting.
fn print_cases(study: &Study, refs: &[CaseReference], ms: &[Measurement]) -> Result<()> {
    for r in refs {
        let c = &study.cases[r.case];
        let labels: Vec<String> = study
            .varied()
            .iter()
            .map(|a| format!("{a}={}", axis_value(a, &c.params)))
            .collect();
        out!(
            "\ncase {} ({}): horizon {:.3} s of {} s{}; reference metric uncertainty {:.1e} / {:.1e} / {:.1e}",
            c.id,
            labels.join(", "),
            r.horizon,
            study.sampling.duration,
            if r.horizon < study.sampling.duration { " (chaotic: pointwise errors up to the horizon only)" } else { "" },
            r.metric_uncertainty[0],
            r.metric_uncertainty[1],
            r.metric_uncertainty[2]
        )?;
        out!("| method | setting | max err {0} | rms err {0} | metric err {0} | metric err {1} | metric err {2} | wall (s) | steps | rejected | RHS |", ERROR_CHANNELS[0], ERROR_CHANNELS[1], ERROR_CHANNELS[2])?;
        out!("|---|---|---|---|---|---|---|---|---|---|---|")?;
        for m in ms.iter().filter(|m| m.case == r.case) {
            let (name, setting) = describe(&m.method);
            match &m.error {
                Some(e) => out!("| {name} | {} | failed: {e} |", setting_label(setting))?,
                None => out!(
                    "| {name} | {} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.1e} | {:.3} | {} | {} | {} |",
                    setting_label(setting),
                    m.max_error[0], m.rms_error[0], m.metric_error[0], m.metric_error[1], m.metric_error[2], m.wall_time, m.steps, m.rejected, m.rhs_evals
                )?,
            }
        }
    }
    Ok(())
}

/// Over all cases: the worst and median metric error and the cost of each setting,
/// the chaotic cases and the cheapest setting within 1 %.
fn print_summary(
    study: &Study,
    refs: &[CaseReference],
    ms: &[Measurement],
    ladder: &[Method],
) -> Result<()> {
    out!("\nover all cases (metric error: worst channel, worst case):")?;
    out!("| method | setting | worst metric error | median metric error | total wall (s) | total RHS |")?;
    out!("|---|---|---|---|---|---|")?;
    for method in ladder {
        let rows: Vec<_> = ms.iter().filter(|m| m.method == *method).collect();
        let mut errs: Vec<f64> = rows
            .iter()
            .map(|m| m.metric_error.iter().copied().fold(0.0, f64::max))
            .collect();
        errs.sort_by(f64::total_cmp);
        let (name, setting) = describe(method);
        out!(
            "| {name} | {} | {:.1e} | {:.1e} | {:.2} | {} |",
            setting_label(setting),
            errs.last().copied().unwrap_or(f64::NAN),
            errs.get(errs.len() / 2).copied().unwrap_or(f64::NAN),
            rows.iter().map(|m| m.wall_time).sum::<f64>(),
            rows.iter().map(|m| m.rhs_evals).sum::<u64>()
        )?;
    }
    let chaotic: Vec<String> = refs
        .iter()
        .filter(|r| r.horizon < study.sampling.duration)
        .map(|r| study.cases[r.case].id.to_string())
        .collect();
    out!(
        "\nchaotic cases (the two references part before the end; horizon < {} s): {} of {}: {}",
        study.sampling.duration,
        chaotic.len(),
        refs.len(),
        chaotic.join(", ")
    )?;
    match accuracy::cheapest_within(ms, refs, ladder, 0.01, study.sampling.duration) {
        Some((m, judged)) => {
            out!("cheapest setting with metric error < 1 % on the {judged} non-chaotic cases: {m}")?
        }
        None => out!("no setting keeps the metric error below 1 % on every non-chaotic case")?,
    }
    Ok(())
}
