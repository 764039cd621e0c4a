//! The `effects:` switches: which physics a study simulates, and what "off" means.

use super::*;

/// Which effects a study simulates; anything off is not computed at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Effects {
    /// The ball bearing's diametral and the journal's radial clearance (off: zero
    /// clearance).
    pub clearance: bool,
    /// Raceway waviness (off: perfect races, no per-ball waviness terms).
    pub waviness: bool,
    /// Contact damping (off: C = 0).
    pub damping: bool,
    /// Gravity along −y.
    pub gravity: bool,
    /// Localized defects (off: no defects, no defect code in the kernel).
    pub defects: bool,
    /// The sprung housing at crank_ground (docs/model.md §3.9; off: rigid ground, no
    /// housing state, no `housing_*` series).
    pub housing: bool,
}

impl Effects {
    /// Every effect off: a study that simulates nothing (measured recordings).
    pub(super) const NONE: Effects = Effects {
        clearance: false,
        waviness: false,
        damping: false,
        gravity: false,
        defects: false,
        housing: false,
    };

    pub(super) const NAMES: [&'static str; 6] = [
        "clearance",
        "waviness",
        "damping",
        "gravity",
        "defects",
        "housing",
    ];

    /// The names of the effects that are on.
    pub fn names(&self) -> Vec<&'static str> {
        let on = [
            self.clearance,
            self.waviness,
            self.damping,
            self.gravity,
            self.defects,
            self.housing,
        ];
        Self::NAMES
            .iter()
            .zip(on)
            .filter(|(_, o)| *o)
            .map(|(n, _)| *n)
            .collect()
    }

    /// The indices into [`CHANNELS`] of the channels simulated under these effects:
    /// those whose effect is `None` or on, in [`CHANNELS`] order.
    pub fn channels(&self) -> Vec<usize> {
        let on = self.names();
        (0..CHANNELS.len())
            .filter(|&c| CHANNELS[c].effect.is_none_or(|e| on.contains(&e)))
            .collect()
    }

    /// The parameters a study file records per case: every one of [`PARAMETERS`]
    /// but the housing's (`m_h`, `k_h`, `c_h`) while the housing effect is off.
    pub fn recorded_parameters(&self) -> impl Iterator<Item = &'static ParamDef> + '_ {
        PARAMETERS
            .iter()
            .filter(|p| self.housing || !HOUSING_PARAMETERS.contains(&p.name))
    }

    /// The effect a parameter belongs to, if switching that effect off forbids it.
    pub(super) fn governing(&self, param: &str) -> Option<(&'static str, bool)> {
        if param.contains("waviness") {
            Some(("waviness", self.waviness))
        } else if param == "damping" {
            Some(("damping", self.damping))
        } else if param == "clearance" || param == "journal_clearance" {
            Some(("clearance", self.clearance))
        } else if param.starts_with("defect") {
            Some(("defects", self.defects))
        } else if HOUSING_PARAMETERS.contains(&param) {
            Some(("housing", self.housing))
        } else {
            None
        }
    }
}

/// The parameters of the housing (`housing:`, docs/model.md §3.9).
pub(super) const HOUSING_PARAMETERS: [&str; 3] = ["m_h", "k_h", "c_h"];

pub(super) fn effects(ctx: &Ctx<'_>, file: &GridFile) -> Result<Effects, StudyError> {
    let Some(list) = &file.effects else {
        return Ok(Effects {
            clearance: true,
            waviness: true,
            damping: true,
            gravity: false,
            defects: false,
            housing: false,
        });
    };
    let mut e = Effects::NONE;
    for (k, name) in list.value.iter().enumerate() {
        let slot = match name.value.as_str() {
            "clearance" => &mut e.clearance,
            "waviness" => &mut e.waviness,
            "damping" => &mut e.damping,
            "gravity" => &mut e.gravity,
            "defects" => &mut e.defects,
            "housing" => &mut e.housing,
            other => {
                return Err(ctx.err(
                    Some(at(&name.referenced)),
                    &format!("effects[{k}]"),
                    format!(
                        "unknown effect `{other}`; expected any of: {}",
                        Effects::NAMES.join(", ")
                    ),
                ))
            }
        };
        if *slot {
            return Err(ctx.err(
                Some(at(&name.referenced)),
                &format!("effects[{k}]"),
                format!("`{}` is listed twice; list each effect once", name.value),
            ));
        }
        *slot = true;
    }
    Ok(e)
}
