//! The series a study's spectra, envelope and order analysis read: a simulated
//! channel ([`CHANNELS`]), a sensor's series (docs/model.md §7.8) or a measured
//! recording's (docs/model.md §7.10).

use crate::simulate::{CaseOutput, CHANNELS};

/// Where an analysed series comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The simulated channel at this index of [`CHANNELS`].
    Simulated(usize),
    /// The sensor series at this index of a case's sensor series: sensor `k`'s noisy
    /// series `<name>` at `2k`, its noise-free `<name>_clean` at `2k + 1`.
    Sensor(usize),
    /// A recordings study's measured series: the case's only other series.
    Recording,
}

/// One series a study analyses, with what its derived variables are named after.
#[derive(Debug, Clone, PartialEq)]
pub struct AnalysisChannel {
    /// The series' variable name (a channel's or a sensor series').
    pub name: String,
    /// Its CF units (a sensor's are those of the channel it measures).
    pub units: &'static str,
    /// Its description, for the long names of what is derived from it.
    pub long_name: String,
    /// Where its samples are.
    pub source: Source,
}

impl AnalysisChannel {
    /// The simulated channel called `name`, if there is one.
    pub fn simulated(name: &str) -> Option<Self> {
        let index = CHANNELS.iter().position(|c| c.name == name)?;
        let c = &CHANNELS[index];
        Some(Self {
            name: c.name.to_string(),
            units: c.units,
            long_name: c.long_name.to_string(),
            source: Source::Simulated(index),
        })
    }

    /// Its samples in a case: `out`'s channel or one of `series`, the case's series
    /// that are not simulated (its sensor series in [`Source::Sensor`] order, or a
    /// recording's one measured series).
    pub fn samples<'a>(&self, out: &'a CaseOutput, series: &'a [Vec<f64>]) -> &'a [f64] {
        match self.source {
            Source::Simulated(c) => &out.channels[c],
            Source::Sensor(k) => &series[k],
            Source::Recording => &series[0],
        }
    }

    /// The measured series `name` of a recordings study, in the recording's own
    /// units (CF `1`: a file does not say what it measured in).
    pub fn recording(name: &str) -> Self {
        Self {
            name: name.to_string(),
            units: "1",
            long_name: format!("measured recording {name}"),
            source: Source::Recording,
        }
    }
}
