//! The series a study's spectra, envelope and order analysis read: a simulated
//! channel ([`CHANNELS`]) or a sensor's series (docs/model.md §7.8).

use crate::simulate::{CaseOutput, CHANNELS};

/// Where an analysed series comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The simulated channel at this index of [`CHANNELS`].
    Simulated(usize),
    /// The sensor series at this index of a case's sensor series: sensor `k`'s noisy
    /// series `<name>` at `2k`, its noise-free `<name>_clean` at `2k + 1`.
    Sensor(usize),
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

    /// Its samples in a case: `out`'s channel or one of `sensors` (the case's sensor
    /// series, [`Source::Sensor`] order).
    pub fn samples<'a>(&self, out: &'a CaseOutput, sensors: &'a [Vec<f64>]) -> &'a [f64] {
        match self.source {
            Source::Simulated(c) => &out.channels[c],
            Source::Sensor(k) => &sensors[k],
        }
    }
}
