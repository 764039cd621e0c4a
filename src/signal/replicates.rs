//! What a case's replicates add to the file (docs/model.md §9.5): each replicated
//! metric per replicate, its mean, standard deviation and 95 % interval over the
//! replicates, and the predictability horizon where the replicates part.

use crate::signal::metric_specs;
use crate::signal::VarSpec;

/// Relative separation (of the base run's slider-acceleration range) that ends the
/// predictability horizon.
pub const HORIZON_THRESHOLD: f64 = 1e-3;

/// Indices into [`metric_specs`] of the metrics stored per replicate: all but the
/// ideal mechanism's own `*_reference_rms` (the same for every replicate) and
/// `wall_time` (of the whole case).
pub fn replicated_metrics() -> Vec<usize> {
    metric_specs(None, true)
        .iter()
        .enumerate()
        .filter(|(_, s)| !s.name.ends_with("_reference_rms") && s.name != "wall_time")
        .map(|(k, _)| k)
        .collect()
}

/// The `[case, replicate]` variables: `<metric>_replicates` per
/// [`replicated_metrics`] entry.
pub fn replicate_metric_specs() -> Vec<VarSpec> {
    let specs = metric_specs(None, true);
    replicated_metrics()
        .into_iter()
        .map(|k| {
            let s = &specs[k];
            VarSpec::new(
                format!("{}_replicates", s.name),
                s.units.clone(),
                format!(
                    "{} of each replicate (replicate 0: the case unperturbed)",
                    s.long_name
                ),
            )
        })
        .collect()
}

/// The `[case]` statistics over the replicates, per [`replicated_metrics`] entry:
/// `<metric>_mean`, `<metric>_std` and `<metric>_ci95` (see [`Summary`]).
pub fn summary_specs() -> Vec<VarSpec> {
    let specs = metric_specs(None, true);
    replicated_metrics()
        .into_iter()
        .flat_map(|k| {
            let s = &specs[k];
            [
                VarSpec::new(
                    format!("{}_mean", s.name),
                    s.units.clone(),
                    format!("mean over the replicates of {}", s.long_name),
                ),
                VarSpec::new(
                    format!("{}_std", s.name),
                    s.units.clone(),
                    format!(
                        "sample standard deviation over the replicates of {}",
                        s.long_name
                    ),
                ),
                VarSpec::new(
                    format!("{}_ci95", s.name),
                    s.units.clone(),
                    format!(
                        "half-width of the 95 % Student t interval of the replicates' mean of {}",
                        s.long_name
                    ),
                ),
            ]
        })
        .collect()
}

/// The `[case]` chaos check variables: `predictability_horizon` and `chaotic`.
pub fn chaos_specs() -> Vec<VarSpec> {
    vec![
        VarSpec::new(
            "predictability_horizon",
            "s",
            "first time after the transient at which a perturbed replicate's slider \
             acceleration departs from replicate 0's by more than 1e-3 of its range after \
             the transient (the duration if none does)",
        ),
        VarSpec::new(
            "chaotic",
            "1",
            "1 if the predictability horizon lies before the end of the run, else 0",
        ),
    ]
}

/// Mean, sample standard deviation and the half-width of the 95 % interval of the
/// mean, `t_{0.975, n−1} s / √n`, over the `n` replicate values that are numbers
/// (NaN ones, e.g. of failed replicates, left out); `std` and `ci95` are NaN for
/// `n < 2`, all three for `n = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Summary {
    /// Mean (the metric's units).
    pub mean: f64,
    /// Sample standard deviation, `n − 1` in the denominator.
    pub std: f64,
    /// Half-width of the 95 % Student t interval of the mean.
    pub ci95: f64,
}

impl Summary {
    /// The summary of `values`.
    pub fn of(values: &[f64]) -> Self {
        let numbers = || values.iter().copied().filter(|v| !v.is_nan());
        let n = numbers().count();
        if n == 0 {
            return Self {
                mean: f64::NAN,
                std: f64::NAN,
                ci95: f64::NAN,
            };
        }
        let mean = numbers().sum::<f64>() / n as f64;
        if n < 2 {
            return Self {
                mean,
                std: f64::NAN,
                ci95: f64::NAN,
            };
        }
        let var = numbers().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
        let std = var.sqrt();
        Self {
            mean,
            std,
            ci95: student_t_975(n - 1) * std / (n as f64).sqrt(),
        }
    }
}

/// The 97.5 % quantile of Student's t distribution with `df ≥ 1` degrees of
/// freedom: the `t` with `P(|T| < t) = 0.95`, by bisection on the closed-form
/// distribution function for whole `df` (Abramowitz & Stegun 26.7.3–4) to 1e-13.
pub fn student_t_975(df: usize) -> f64 {
    let (mut lo, mut hi) = (0.0f64, 1e3);
    while hi - lo > 1e-13 * hi {
        let mid = 0.5 * (lo + hi);
        if central_probability(mid, df) < 0.95 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// `P(|T| < t)` for Student's t with `df ≥ 1` degrees of freedom (A&S 26.7.3–4).
fn central_probability(t: f64, df: usize) -> f64 {
    let theta = (t / (df as f64).sqrt()).atan();
    let (s, c) = theta.sin_cos();
    let c2 = c * c;
    if df % 2 == 1 {
        // 2/π [θ + sin θ cos θ (1 + 2/3 cos²θ + … + (2·4…(df−3))/(1·3…(df−2)) cos^(df−3) θ)]
        let (mut term, mut sum) = (1.0, 0.0);
        if df > 1 {
            sum = 1.0;
            for j in 1..(df - 1) / 2 {
                term *= (2 * j) as f64 / (2 * j + 1) as f64 * c2;
                sum += term;
            }
        }
        std::f64::consts::FRAC_2_PI * (theta + s * c * sum)
    } else {
        // sin θ [1 + 1/2 cos²θ + … + (1·3…(df−3))/(2·4…(df−2)) cos^(df−2) θ]
        let (mut term, mut sum) = (1.0, 1.0);
        for j in 1..df / 2 {
            term *= (2 * j - 1) as f64 / (2 * j) as f64 * c2;
            sum += term;
        }
        s * sum
    }
}

/// The first of `times` at which `other` departs from `base` by more than
/// [`HORIZON_THRESHOLD`] of `base`'s range (max − min over the whole series), or
/// `duration` if it never does; NaN samples in `other` count as departed.
pub fn predictability_horizon(base: &[f64], other: &[f64], times: &[f64], duration: f64) -> f64 {
    let max = base.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let min = base.iter().copied().fold(f64::INFINITY, f64::min);
    let limit = HORIZON_THRESHOLD * (max - min);
    base.iter()
        .zip(other)
        .zip(times)
        .find(|((a, b), _)| (*a - *b).abs() > limit || (*a - *b).is_nan())
        .map_or(duration, |(_, t)| *t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Student t quantiles against tabulated values (R's `qt(0.975, df)`).
    #[test]
    fn student_t_matches_tables() {
        for (df, t) in [
            (1, 12.706_204_736_174_7),
            (2, 4.302_652_729_749_46),
            (3, 3.182_446_305_284_26),
            (4, 2.776_445_105_197_8),
            (15, 2.131_449_545_559_77),
            (30, 2.042_272_456_301_24),
            (100, 1.983_971_518_523_55),
        ] {
            let got = student_t_975(df);
            assert!((got - t).abs() < 1e-9 * t, "df {df}: {got} vs {t}");
        }
    }

    #[test]
    fn summary_of_known_values() {
        let s = Summary::of(&[1.0, 2.0, 3.0, f64::NAN]);
        assert_eq!(s.mean, 2.0);
        assert_eq!(s.std, 1.0);
        assert!((s.ci95 - 4.302_652_729_749_46 / 3f64.sqrt()).abs() < 1e-12);
        let one = Summary::of(&[5.0]);
        assert_eq!(one.mean, 5.0);
        assert!(one.std.is_nan() && one.ci95.is_nan());
        assert!(Summary::of(&[]).mean.is_nan());
    }

    #[test]
    fn horizon_is_the_first_departure_beyond_the_threshold() {
        let times: Vec<f64> = (0..5).map(|k| k as f64 * 0.1).collect();
        let base = [0.0, 1.0, 2.0, 3.0, 4.0];
        // Range 4: the threshold is 4e-3.
        let near = [0.0, 1.0 + 3e-3, 2.0, 3.0 - 3e-3, 4.0];
        assert_eq!(predictability_horizon(&base, &near, &times, 0.5), 0.5);
        let apart = [0.0, 1.0, 2.0 + 5e-3, 3.0, 4.0];
        assert_eq!(predictability_horizon(&base, &apart, &times, 0.5), 0.2);
        let failed = [0.0, f64::NAN, 2.0, 3.0, 4.0];
        assert_eq!(predictability_horizon(&base, &failed, &times, 0.5), 0.1);
    }
}
