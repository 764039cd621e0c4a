//! What a study analyses and stores: the sampling, the analysed window, spectra,
//! envelope and order settings, and the series the file keeps.

use super::*;

/// The highest frequency the file stores of every spectrum (`spectra.max_frequency`,
/// Hz), if given: above 0 and at most the Nyquist frequency.
pub(super) fn max_frequency(
    ctx: &Ctx<'_>,
    spectra: Option<&SpectraSection>,
    sampling: &Sampling,
) -> Result<Option<f64>, StudyError> {
    let Some(given) = spectra.and_then(|s| s.max_frequency.as_ref()) else {
        return Ok(None);
    };
    let field = "spectra.max_frequency";
    let f = ctx.quantity(given, Dimension::Frequency, field)?;
    let nyquist = 0.5 * sampling.sample_rate;
    if !(f > 0.0 && f <= nyquist) {
        return Err(ctx.err(
            Some(at(&given.referenced)),
            field,
            format!(
                "{} is not allowed: a frequency above 0 and at most sample_rate/2 = {} Hz \
                 (the Nyquist frequency)",
                given.value,
                number(nyquist)
            ),
        ));
    }
    Ok(Some(f))
}

/// The order analysis the file asks for (`spectra: {orders: true}`,
/// `envelope: {orders: true}`), or `None`: `R` is the fewest whole revolutions any
/// case turns between the analysed window's first and last samples (at least one),
/// `M` the window's sample count (docs/model.md §7.9); `fewest` gives the fewest whole
/// revolutions of any case between two times (s) and the first case that turns so
/// few.
pub(super) fn order_settings(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    transient: f64,
    fewest: impl FnOnce(f64, f64) -> Option<(usize, u64)>,
) -> Result<Option<OrderSettings>, StudyError> {
    let spectra = file.spectra.as_ref().and_then(|s| s.orders.as_ref());
    let envelope = file.envelope.as_ref().and_then(|e| e.value.orders.as_ref());
    let asked = |o: Option<&S<bool>>| o.is_some_and(|o| o.value);
    if !asked(spectra) && !asked(envelope) {
        return Ok(None);
    }
    let (key, field) = match spectra.filter(|o| o.value) {
        Some(o) => (o, "spectra.orders"),
        None => (envelope.expect("asked"), "envelope.orders"),
    };
    let window = sampling.analysis_window(transient);
    let (first, last) = (
        window.start as f64 / sampling.sample_rate,
        (window.end.max(1) - 1) as f64 / sampling.sample_rate,
    );
    let (revolutions, id) = fewest(first, last).unwrap_or((0, 0));
    if revolutions == 0 || window.len() < 2 {
        return Err(ctx.err(
            Some(at(&key.referenced)),
            field,
            format!(
                "order spectra need at least one whole crank revolution in every case's \
                 analysed window ({first} s to {last} s); case {id} turns less: lengthen \
                 `duration` or shorten `transient`"
            ),
        ));
    }
    Ok(Some(OrderSettings {
        revolutions,
        samples: window.len(),
        spectra: asked(spectra),
        envelope: asked(envelope),
    }))
}

/// `duration` and `sample_rate`, checked; both required, and `window` refused (a
/// study without `recordings:`).
pub(super) fn sampling_of(ctx: &Ctx<'_>, file: &GridFile) -> Result<Sampling, StudyError> {
    super::refuse_recording_keys(ctx, file)?;
    let required = |v: &Option<S<Scalar>>, field: &str| {
        v.clone().ok_or_else(|| {
            ctx.err(
                None,
                field,
                format!(
                    "the required field `{field}` is missing (a study listing `recordings:` \
                     takes it from them)"
                ),
            )
        })
    };
    let (duration, sample_rate) = (
        required(&file.duration, "duration")?,
        required(&file.sample_rate, "sample_rate")?,
    );
    let sampling = Sampling {
        duration: ctx.quantity(&duration, Dimension::Time, "duration")?,
        sample_rate: ctx.quantity(&sample_rate, Dimension::Frequency, "sample_rate")?,
    };
    sampling.validate().map_err(|e| {
        ctx.err(
            Some(at(if e.field == "duration" {
                &duration.referenced
            } else {
                &sample_rate.referenced
            })),
            &e.field,
            e.refusal(),
        )
    })?;
    Ok(sampling)
}

/// The start of the analysed window (s): the grid's `transient`, or `auto` (the
/// longest first crank `revolution` of any case (s), at most half the duration); it
/// must leave two samples for the spectra and metrics.
pub(super) fn transient_of(
    ctx: &Ctx<'_>,
    file: &GridFile,
    sampling: &Sampling,
    revolution: f64,
) -> Result<f64, StudyError> {
    let transient = match &file.transient {
        None => revolution.min(0.5 * sampling.duration),
        Some(S {
            value: Scalar::Text(t),
            ..
        }) if t == "auto" => revolution.min(0.5 * sampling.duration),
        Some(v) => {
            let x = ctx.quantity(v, Dimension::Time, "transient")?;
            if !(0.0..sampling.duration).contains(&x) {
                return Err(ctx.err(
                    Some(at(&v.referenced)),
                    "transient",
                    format!(
                        "{} s is not allowed: >= 0 and below duration = {} s",
                        number(x),
                        number(sampling.duration)
                    ),
                ));
            }
            x
        }
    };
    // Spectra (Hann) and metrics need two samples in `transient ≤ t < duration`.
    let analysed = sampling.analysis_window(transient).len();
    if analysed < 2 {
        let last_sample = sampling.len() - 1;
        return Err(ctx.err(
            file.transient.as_ref().map(|v| at(&v.referenced)),
            "transient",
            format!(
                "{} s leaves {analysed} sample(s) in the analysed window \
                 transient <= t < duration = {} s at {} Hz; at least 2 are needed \
                 (a transient of at most {} s, or a longer duration)",
                number(transient),
                number(sampling.duration),
                number(sampling.sample_rate),
                number(last_sample.saturating_sub(2) as f64 / sampling.sample_rate)
            ),
        ));
    }
    Ok(transient)
}

/// The series a study may analyse.
#[derive(Debug, Clone, Copy)]
pub(super) enum Analysed<'a> {
    /// A simulated study's channels under its effects, and its sensors' series.
    Simulated(&'a [Sensor], &'a Effects),
    /// A recordings study's one measured series.
    Recording(&'a AnalysisChannel),
}

/// The spectrum window's name and the channels with spectra (simulated channels or
/// the series of `sensors`; by default the slider acceleration, crank moment and
/// bearing force, or a recordings study's series).
pub(super) fn spectra_settings(
    ctx: &Ctx<'_>,
    spectra: Option<&SpectraSection>,
    analysed: Analysed<'_>,
) -> Result<(String, Vec<AnalysisChannel>), StudyError> {
    let default = SpectraSection::default();
    let spectra = spectra.unwrap_or(&default);
    let window = match &spectra.window {
        None => "hann".to_string(),
        Some(w) if w.value == "hann" || w.value == "rectangular" => w.value.clone(),
        Some(w) => {
            return Err(ctx.err(
                Some(at(&w.referenced)),
                "spectra.window",
                format!(
                    "`{}` is not a window; expected hann or rectangular",
                    w.value
                ),
            ))
        }
    };
    let channels = match &spectra.channels {
        None => match analysed {
            Analysed::Recording(r) => vec![r.clone()],
            Analysed::Simulated(..) => ["slider_acceleration", "crank_moment", "bearing_force"]
                .into_iter()
                .map(|name| AnalysisChannel::simulated(name).expect("a channel"))
                .collect(),
        },
        Some(list) => list
            .value
            .iter()
            .enumerate()
            .map(|(k, c)| analysis_channel(ctx, c, &format!("spectra.channels[{k}]"), analysed))
            .collect::<Result<_, _>>()?,
    };
    Ok((window, channels))
}

/// The channel of [`CHANNELS`] named by `c` (at `field`), simulated under `effects`.
pub(super) fn channel_named(
    ctx: &Ctx<'_>,
    c: &S<String>,
    field: &str,
    effects: &Effects,
) -> Result<&'static str, StudyError> {
    let channel = CHANNELS
        .iter()
        .find(|ch| ch.name == c.value)
        .ok_or_else(|| {
            let names: Vec<&str> = CHANNELS.iter().map(|ch| ch.name).collect();
            ctx.err(
                Some(at(&c.referenced)),
                field,
                format!(
                    "unknown channel `{}`; expected one of: {}",
                    c.value,
                    names.join(", ")
                ),
            )
        })?;
    match channel.effect {
        Some(effect) if !effects.names().contains(&effect) => Err(ctx.err(
            Some(at(&c.referenced)),
            field,
            format!(
                "channel `{}` is simulated with the {effect} effect only, which is off \
                 (effects: [{}]); add `{effect}` to `effects` to use it",
                c.value,
                effects.names().join(", ")
            ),
        )),
        _ => Ok(channel.name),
    }
}

/// The series named by `c` (at `field`): a channel of [`CHANNELS`] the study's
/// `effects` simulate or a series of `sensors` (`<name>` or `<name>_clean`); in a
/// recordings study its measured series.
pub(super) fn analysis_channel(
    ctx: &Ctx<'_>,
    c: &S<String>,
    field: &str,
    analysed: Analysed<'_>,
) -> Result<AnalysisChannel, StudyError> {
    let (sensors, effects) = match analysed {
        Analysed::Simulated(sensors, effects) => (sensors, effects),
        Analysed::Recording(r) if r.name == c.value => return Ok(r.clone()),
        Analysed::Recording(r) => {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                field,
                format!(
                    "unknown series `{}`: a recordings study has one series, `{}` (the \
                     grid's `series:` names it)",
                    c.value, r.name
                ),
            ))
        }
    };
    if let Some(ch) = AnalysisChannel::simulated(&c.value) {
        channel_named(ctx, c, field, effects)?;
        return Ok(ch);
    }
    for (k, sensor) in sensors.iter().enumerate() {
        let [noisy, clean] = sensor.specs();
        for (j, spec) in [noisy, clean].into_iter().enumerate() {
            if spec.name == c.value {
                let units = CHANNELS
                    .iter()
                    .find(|ch| ch.name == sensor.channel)
                    .expect("sensor channels are validated")
                    .units;
                return Ok(AnalysisChannel {
                    name: spec.name,
                    units,
                    long_name: spec.long_name,
                    source: Source::Sensor(2 * k + j),
                });
            }
        }
    }
    let names: Vec<String> = CHANNELS
        .iter()
        .map(|ch| ch.name.to_string())
        .chain(
            sensors
                .iter()
                .flat_map(|s| [s.name.clone(), format!("{}{CLEAN_SUFFIX}", s.name)]),
        )
        .collect();
    Err(ctx.err(
        Some(at(&c.referenced)),
        field,
        format!(
            "unknown channel `{}`; expected a simulated channel or a sensor series, one of: {}",
            c.value,
            names.join(", ")
        ),
    ))
}

/// The `envelope:` settings: distinct channels, and a band `[low, high]` with
/// `0 <= low < high <= sample_rate / 2` holding at least one bin of the analysed
/// window, or `auto` (the default).
pub(super) fn envelope_settings(
    ctx: &Ctx<'_>,
    section: &S<EnvelopeSection>,
    sampling: &Sampling,
    transient: f64,
    analysed: Analysed<'_>,
) -> Result<EnvelopeSettings, StudyError> {
    let list = &section.value.channels;
    if list.value.is_empty() {
        return Err(ctx.err(
            Some(at(&list.referenced)),
            "envelope.channels",
            "at least one channel is needed",
        ));
    }
    let mut channels: Vec<AnalysisChannel> = Vec::new();
    for (k, c) in list.value.iter().enumerate() {
        let field = format!("envelope.channels[{k}]");
        let channel = analysis_channel(ctx, c, &field, analysed)?;
        if channels.iter().any(|ch| ch.name == channel.name) {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                &field,
                format!("channel `{}` is listed twice", channel.name),
            ));
        }
        channels.push(channel);
    }
    let band = match &section.value.band {
        None => BandChoice::Auto,
        Some(S {
            value: BandValue::Name(name),
            ..
        }) if name == "auto" => BandChoice::Auto,
        Some(S {
            value: BandValue::Name(name),
            ..
        }) if name == "kurtogram" => BandChoice::Kurtogram,
        Some(v) => BandChoice::Fixed(fixed_band(ctx, v, sampling, transient)?),
    };
    Ok(EnvelopeSettings { channels, band })
}

/// A band `[low, high]` (Hz) given in `envelope.band`: `0 <= low < high <=
/// sample_rate / 2`, holding at least one bin of the window analysed after `transient`
/// (s).
fn fixed_band(
    ctx: &Ctx<'_>,
    v: &S<BandValue>,
    sampling: &Sampling,
    transient: f64,
) -> Result<Band, StudyError> {
    let place = Some(at(&v.referenced));
    let bad = |message: String| ctx.err(place, "envelope.band", message);
    let BandValue::Range(edges) = &v.value else {
        return Err(bad(
            "expected `auto`, `kurtogram` or two frequencies [low, high], e.g. [\"2 kHz\", \"8 kHz\"]"
                .to_string(),
        ));
    };
    let [low, high] = edges.as_slice() else {
        return Err(bad(format!(
            "{} values; expected two frequencies [low, high] or `auto`",
            edges.len()
        )));
    };
    let hz = |s: &Scalar| -> Result<f64, StudyError> {
        let x = match s {
            Scalar::Num(x) => *x,
            Scalar::Text(t) => Dimension::Frequency
                .parse(t)
                .map_err(|m| ctx.err(place, "envelope.band", m))?,
        };
        if x.is_finite() {
            Ok(x)
        } else {
            Err(bad(format!("{s} is not a finite frequency")))
        }
    };
    let band = Band {
        low: hz(low)?,
        high: hz(high)?,
    };
    let nyquist = 0.5 * sampling.sample_rate;
    if !(0.0 <= band.low && band.low < band.high && band.high <= nyquist) {
        return Err(bad(format!(
            "[{} Hz, {} Hz] is not allowed: 0 <= low < high <= sample_rate / 2 = {nyquist} Hz",
            band.low, band.high
        )));
    }
    let n = sampling.analysis_window(transient).len();
    let bins = frequencies(n, sampling.sample_rate)
        .into_iter()
        .filter(|&f| band.contains(f))
        .count();
    if bins == 0 {
        return Err(bad(format!(
            "[{} Hz, {} Hz] holds no frequency bin of the analysed window \
             ({n} samples: bins every {} Hz); widen the band",
            band.low,
            band.high,
            sampling.sample_rate / n as f64
        )));
    }
    Ok(band)
}

/// Whether series and spectra are stored as float32, and the deflate level.
pub(super) fn output_settings(
    ctx: &Ctx<'_>,
    output: Option<&OutputSection>,
) -> Result<(bool, u8), StudyError> {
    let default = OutputSection::default();
    let output = output.unwrap_or(&default);
    let float32 = match &output.dtype {
        None => false,
        Some(d) if d.value == "float64" => false,
        Some(d) if d.value == "float32" => true,
        Some(d) => {
            return Err(ctx.err(
                Some(at(&d.referenced)),
                "output.dtype",
                format!("`{}` is not allowed: float64 or float32", d.value),
            ))
        }
    };
    let compression = match &output.compression {
        // Level 1 gets nearly all of deflate's gain on these data (measured: 1.30 vs 1.31 at 4).
        None => 1,
        Some(c) if c.value <= 9 => c.value,
        Some(c) => {
            return Err(ctx.err(
                Some(at(&c.referenced)),
                "output.compression",
                format!("{} is not allowed: a deflate level 0..=9", c.value),
            ))
        }
    };
    Ok((float32, compression))
}

/// `output.series` and `output.decimate`: the series names checked against what
/// `study` simulates (its channels and sensor series; distinct), `decimate` an
/// integer from 1 to the samples per case.
pub(super) fn series_output(
    ctx: &Ctx<'_>,
    output: Option<&OutputSection>,
    study: &Study,
) -> Result<SeriesOutput, StudyError> {
    let mut chosen = SeriesOutput::default();
    let Some(output) = output else {
        return Ok(chosen);
    };
    if let Some(d) = &output.decimate {
        let samples = study.sampling.len();
        let k = match d.value {
            Scalar::Num(x) if x.fract() == 0.0 && (1.0..=samples as f64).contains(&x) => x,
            _ => {
                return Err(ctx.err(
                    Some(at(&d.referenced)),
                    "output.decimate",
                    format!(
                        "{} is not allowed: an integer from 1 (every sample) to {samples} \
                         (the samples per case)",
                        d.value
                    ),
                ))
            }
        };
        chosen.decimate = k as usize;
    }
    let Some(series) = &output.series else {
        return Ok(chosen);
    };
    let place = Some(at(&series.referenced));
    chosen.names = match &series.value {
        SeriesValue::Name(n) if n == "all" => None,
        SeriesValue::Name(n) if n == "none" => Some(Vec::new()),
        SeriesValue::Name(n) => {
            return Err(ctx.err(
                place,
                "output.series",
                format!("`{n}` is not allowed: a list of series names, `all` or `none`"),
            ))
        }
        SeriesValue::List(list) => {
            let allowed: Vec<String> = study
                .simulated_channels()
                .into_iter()
                .map(|c| CHANNELS[c].name.to_string())
                .chain(study.sensors.iter().flat_map(|s| s.specs()).map(|v| v.name))
                .chain(study.recordings.iter().map(|r| r.series.name.clone()))
                .collect();
            let mut names: Vec<String> = Vec::new();
            for (k, name) in list.iter().enumerate() {
                let field = format!("output.series[{k}]");
                if !allowed.contains(name) {
                    return Err(ctx.err(
                        place,
                        &field,
                        format!(
                            "unknown series `{name}`; expected one of: {} (or `all` or `none` \
                             instead of a list)",
                            allowed.join(", ")
                        ),
                    ));
                }
                if names.contains(name) {
                    return Err(ctx.err(place, &field, format!("series `{name}` is listed twice")));
                }
                names.push(name.clone());
            }
            Some(names)
        }
    };
    Ok(chosen)
}
