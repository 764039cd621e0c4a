//! The `sensors:` section resolved into [`Sensor`]s (docs/model.md §7.8), each value
//! checked where it is written.

use std::collections::HashSet;

use super::{at, channel_named, Ctx, Effects};
use crate::signal::sensor::{Noise, Sensor, Transducer, CLEAN_SUFFIX};
use crate::simulate::Sampling;
use crate::study::config::{NoiseSection, SensorSection, S};
use crate::study::units::Dimension;
use crate::study::StudyError;

/// Refuses a case of another noise realisation than 0 (`noise_realization`, set by an
/// axis, a design or a case; `first` is the first such case's id and realisation)
/// when no sensor of the study has `noise:`: the realisation would change nothing.
pub(super) fn check_realizations(
    ctx: &Ctx<'_>,
    sensors: &[Sensor],
    first: Option<(u64, u64)>,
) -> Result<(), StudyError> {
    if sensors.iter().any(|s| s.noise.is_some()) {
        return Ok(());
    }
    match first {
        Some((id, realization)) => Err(ctx.err(
            None,
            "noise_realization",
            format!(
                "{} (case {}) draws another realisation of the sensors' noise, and no sensor \
                 has `noise:`; give a sensor `noise: {{snr_db: ..., seed: ...}}` or leave \
                 noise_realization out",
                realization, id
            ),
        )),
        None => Ok(()),
    }
}

/// The signal-to-noise ratios (dB) a sensor's noise may have: above 300 dB the noise's
/// amplitude, 10^(−SNR/20) of the signal's, is below 10^−15, the float64 rounding of the
/// series; below −100 dB it is more than 10^5 times the signal's, whose fourth power
/// (kurtosis) leaves float64's range for signals above 10^72 and which no metric can
/// tell from noise anyway (docs/grid-file.md).
pub(crate) const SNR_DB: std::ops::RangeInclusive<f64> = -100.0..=300.0;

/// Longest sensor name in bytes: its longest derived variable,
/// `<name>_clean_envelope_order_spectrum` (30 more bytes), fits netCDF's 256-byte names.
pub(crate) const MAX_SENSOR_NAME: usize = 226;

/// Refuses a sensor of `list` (resolved into `sensors`) whose series `<name>` or
/// `<name>_clean` is another sensor's or one of `taken`, the names of every other
/// variable of the study file.
pub(super) fn check_names(
    ctx: &Ctx<'_>,
    list: &S<Vec<S<SensorSection>>>,
    sensors: &[Sensor],
    taken: &HashSet<String>,
) -> Result<(), StudyError> {
    let mut own: HashSet<String> = HashSet::new();
    for (k, (entry, sensor)) in list.value.iter().zip(sensors).enumerate() {
        let name = &sensor.name;
        let name_at = Some(at(&entry.value.name.referenced));
        let field = format!("sensors[{k}].name");
        if name.len() > MAX_SENSOR_NAME {
            return Err(ctx.err(
                name_at,
                &field,
                format!(
                    "`{name}` is {} bytes long; at most {MAX_SENSOR_NAME}, so that its longest \
                     variable, `<name>_clean_envelope_order_spectrum`, fits netCDF's 256-byte names",
                    name.len()
                ),
            ));
        }
        for series in [name.clone(), format!("{name}{CLEAN_SUFFIX}")] {
            if taken.contains(&series) {
                return Err(ctx.err(
                    name_at,
                    &field,
                    format!(
                        "`{name}` would store the series `{series}`, which is already a \
                         variable of the study file; choose another name"
                    ),
                ));
            }
            if !own.insert(series.clone()) {
                return Err(ctx.err(
                    name_at,
                    &field,
                    format!("`{name}`: the series `{series}` is another sensor's; names must be distinct"),
                ));
            }
        }
    }
    Ok(())
}

/// A sensor's `noise`, its SNR within [`SNR_DB`] (`field` names it).
fn noise(ctx: &Ctx<'_>, n: &NoiseSection, field: &str) -> Result<Noise, StudyError> {
    let snr = &n.snr_db;
    if !(SNR_DB.contains(&snr.value)) {
        return Err(ctx.err(
            Some(at(&snr.referenced)),
            field,
            format!(
                "{} is not allowed: a signal-to-noise ratio from {} to {} dB (below, the \
                 noise's fourth powers in the metrics overflow; above, the noise is under \
                 the series' rounding)",
                snr.value,
                SNR_DB.start(),
                SNR_DB.end()
            ),
        ));
    }
    Ok(Noise {
        snr_db: snr.value,
        seed: n.seed.as_ref().map_or(0, |s| s.value),
    })
}

/// The sensors of `list` for a study sampled as `sampling`; their names are checked
/// against the study's other variables by [`check_names`].
pub(super) fn sensors(
    ctx: &Ctx<'_>,
    list: &S<Vec<S<SensorSection>>>,
    sampling: &Sampling,
    effects: &Effects,
) -> Result<Vec<Sensor>, StudyError> {
    let nyquist = 0.5 * sampling.sample_rate;
    let mut sensors: Vec<Sensor> = Vec::with_capacity(list.value.len());
    for (k, entry) in list.value.iter().enumerate() {
        let s = &entry.value;
        let field = |key: &str| format!("sensors[{k}].{key}");
        let name = &s.name.value;
        let name_at = Some(at(&s.name.referenced));
        let valid = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic())
            && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid {
            return Err(ctx.err(
                name_at,
                &field("name"),
                format!(
                    "`{name}` is not a sensor name; expected a letter followed by letters, \
                     digits or `_`"
                ),
            ));
        }
        let channel = channel_named(ctx, &s.channel, &field("channel"), effects)?;
        let f_n = ctx.quantity(
            &s.natural_frequency,
            Dimension::Frequency,
            &field("natural_frequency"),
        )?;
        if !(f_n > 0.0 && f_n < nyquist) {
            return Err(ctx.err(
                Some(at(&s.natural_frequency.referenced)),
                &field("natural_frequency"),
                format!(
                    "{f_n} Hz; expected 0 < natural_frequency < sample_rate/2 = {nyquist} Hz \
                     (the Nyquist frequency)"
                ),
            ));
        }
        let zeta = s.damping_ratio.value;
        if !(zeta.is_finite() && zeta > 0.0) {
            return Err(ctx.err(
                Some(at(&s.damping_ratio.referenced)),
                &field("damping_ratio"),
                format!("{zeta}; expected a finite damping ratio > 0"),
            ));
        }
        let noise = s
            .noise
            .as_ref()
            .map(|n| noise(ctx, &n.value, &field("noise.snr_db")))
            .transpose()?;
        sensors.push(Sensor {
            name: name.clone(),
            channel,
            transducer: Transducer {
                natural_frequency: f_n,
                damping_ratio: zeta,
            },
            noise,
        });
    }
    Ok(sensors)
}
