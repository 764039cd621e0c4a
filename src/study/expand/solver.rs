//! The `solver:` section: integrator, tolerances, steps and budget, checked.

use super::*;
use crate::study::config::SolverSection;

pub(super) fn solver(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
) -> Result<SolverSettings, StudyError> {
    let s = match &file.solver {
        Some(s) => s,
        None => return Ok(SolverSettings::new(Method::DEFAULT)),
    };
    let method = method(ctx, s, sampling)?;
    refuse_ignored(ctx, s, &method)?;
    let mut settings = SolverSettings::new(method);
    if let Some(l) = &s.locate_events {
        settings.locate_events = l.value;
    }
    if let Some(l) = &s.stiffness_switch {
        settings.stiffness_switch = l.value;
    }
    if let Some(m) = &s.max_steps {
        if m.value == 0 {
            return Err(ctx.err(
                Some(at(&m.referenced)),
                "solver.max_steps",
                "0 is not allowed: a budget of at least 1 step per case",
            ));
        }
        settings.max_steps = m.value;
    }
    let duration = sampling.duration;
    let max_step = positive(
        ctx,
        &s.max_step,
        (Dimension::Time, "solver.max_step"),
        f64::INFINITY,
    )?;
    settings.max_step = within(
        ctx,
        &s.max_step,
        (max_step, "solver.max_step"),
        max_step <= duration,
        format!("a largest step > 0 and at most the duration {duration} s"),
    )?;
    Ok(settings)
}

/// The value of the optional setting `v` (of dimension `dim`, at `field`), which
/// must be > 0; `default` when it is not given.
fn positive(
    ctx: &Ctx<'_>,
    v: &Option<S<Scalar>>,
    (dim, field): (Dimension, &str),
    default: f64,
) -> Result<f64, StudyError> {
    match v {
        None => Ok(default),
        Some(v) => {
            let x = ctx.quantity(v, dim, field)?;
            if x > 0.0 {
                Ok(x)
            } else {
                Err(ctx.err(
                    Some(at(&v.referenced)),
                    field,
                    format!("{x} is not allowed: > 0"),
                ))
            }
        }
    }
}

/// `x`, the value of the setting `v` at `field`, unless it is given and not `ok` by
/// `rule`. A tolerance or step outside its range is a typo or a misunderstanding: a
/// relative tolerance of 10 % or more integrates nothing, one below 1e-14 asks for
/// more than float64 holds; no step can be longer than the run.
fn within(
    ctx: &Ctx<'_>,
    v: &Option<S<Scalar>>,
    (x, field): (f64, &str),
    ok: bool,
    rule: String,
) -> Result<f64, StudyError> {
    match v {
        Some(v) if !ok => Err(ctx.err(
            Some(at(&v.referenced)),
            field,
            format!("{x} is not allowed: {rule}"),
        )),
        _ => Ok(x),
    }
}

/// The integrator of `solver.method` (dop853 when not given) with its tolerances
/// (`rtol`, `atol`, dimensionless) or RK4's fixed step (s), which must fit the
/// sample spacing of `sampling`.
fn method(ctx: &Ctx<'_>, s: &SolverSection, sampling: &Sampling) -> Result<Method, StudyError> {
    let rtol = positive(
        ctx,
        &s.rtol,
        (Dimension::Dimensionless, "solver.rtol"),
        DEFAULT_RTOL,
    )?;
    let rtol = within(
        ctx,
        &s.rtol,
        (rtol, "solver.rtol"),
        (MIN_RTOL..MAX_RTOL).contains(&rtol),
        format!(
            "a relative tolerance > 0, from {MIN_RTOL:e} up to (not including) {MAX_RTOL}; \
             1e-6 to 1e-10 are usual"
        ),
    )?;
    let atol = positive(
        ctx,
        &s.atol,
        (Dimension::Dimensionless, "solver.atol"),
        DEFAULT_ATOL,
    )?;
    let duration = sampling.duration;
    let spacing = 1.0 / sampling.sample_rate;
    Ok(match s.method.as_ref().map(|m| m.value.as_str()) {
        Some("dopri5") => Method::DormandPrince { rtol, atol },
        Some("tsit5") => Method::Tsit5 { rtol, atol },
        None | Some("dop853") => Method::Dop853 { rtol, atol },
        Some("sdirk4") => Method::Sdirk4 { rtol, atol },
        Some("rk4") => {
            let step = positive(ctx, &s.step, (Dimension::Time, "solver.step"), 20e-6)?;
            let rule = format!(
                "RK4's fixed step must be at most the sample spacing 1/sample_rate = {spacing} s \
                 (and the duration {duration} s): with longer steps the samples between \
                 them are only interpolated"
            );
            if s.step.is_none() && !rk4_step_fits(step, spacing) {
                return Err(ctx.err(
                    s.method.as_ref().map(|m| at(&m.referenced)),
                    "solver.step",
                    format!("the default step {step} s is too long: {rule}; give `step`"),
                ));
            }
            let ok = rk4_step_fits(step, spacing) && step <= duration;
            Method::Rk4 {
                step: within(ctx, &s.step, (step, "solver.step"), ok, rule)?,
            }
        }
        Some(other) => {
            let m = s.method.as_ref().map(|m| at(&m.referenced));
            return Err(ctx.err(
                m,
                "solver.method",
                format!("`{other}` is not allowed: dopri5, tsit5, dop853, rk4 or sdirk4"),
            ));
        }
    })
}

/// Refuses a setting the chosen `method` would ignore, rather than dropping it
/// silently.
fn refuse_ignored(ctx: &Ctx<'_>, s: &SolverSection, method: &Method) -> Result<(), StudyError> {
    let method_name = s.method.as_ref().map_or("dop853", |m| m.value.as_str());
    let given =
        |v: &Option<S<Scalar>>| v.as_ref().map(|v| (at(&v.referenced), v.value.to_string()));
    let flag = |v: &Option<S<bool>>| v.as_ref().map(|v| (at(&v.referenced), v.value.to_string()));
    let (events, switch) = (flag(&s.locate_events), flag(&s.stiffness_switch));
    let (ignored, takes) = match method {
        Method::Rk4 { .. } => (
            vec![
                ("rtol", given(&s.rtol)),
                ("atol", given(&s.atol)),
                ("max_step", given(&s.max_step)),
                ("locate_events", events),
                ("stiffness_switch", switch),
            ],
            "a fixed `step` (s)",
        ),
        Method::Sdirk4 { .. } => (
            vec![("step", given(&s.step)), ("stiffness_switch", switch)],
            "`rtol`, `atol`, `max_step` and `locate_events`",
        ),
        _ => (
            vec![("step", given(&s.step))],
            "`rtol`, `atol`, `max_step`, `locate_events` and `stiffness_switch`",
        ),
    };
    match ignored.into_iter().find(|(_, v)| v.is_some()) {
        Some((field, Some((place, value)))) => Err(ctx.err(
            Some(place),
            &format!("solver.{field}"),
            format!("{value} is not allowed with method {method_name}, which takes {takes}"),
        )),
        _ => Ok(()),
    }
}
