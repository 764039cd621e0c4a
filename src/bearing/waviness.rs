//! Raceway waviness: `Π(ψ) = Π_T + Σ_h Π_p,h sin(N_h ψ + φ_h)` under each ball.

use crate::error::ParamError;

/// One sinusoidal waviness component of a raceway.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Harmonic {
    /// Waviness number `N` (waves per circumference, ≥ 1).
    pub number: u32,
    /// Amplitude `Π_p` (m, ≥ 0).
    pub amplitude: f64,
    /// Phase `φ` (rad).
    pub phase: f64,
}

/// The waviness of one raceway.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RaceWaviness {
    /// Constant offset `Π_T` (m).
    pub offset: f64,
    /// Sinusoidal components, summed.
    pub harmonics: Vec<Harmonic>,
}

impl RaceWaviness {
    /// One harmonic of `number` waves and `amplitude` (m), zero phase and offset.
    pub fn single(number: u32, amplitude: f64) -> Self {
        Self {
            offset: 0.0,
            harmonics: vec![Harmonic {
                number,
                amplitude,
                phase: 0.0,
            }],
        }
    }

    /// Checks every field; `prefix` names the race in the error.
    pub fn validate(&self, prefix: &str) -> Result<(), ParamError> {
        if !self.offset.is_finite() {
            return Err(ParamError::new(
                format!("{prefix}.offset"),
                self.offset,
                "a finite length in m",
            ));
        }
        if self.harmonics.len() > MAX_HARMONICS {
            return Err(ParamError::new(
                format!("{prefix}.harmonics"),
                format!("{} harmonics", self.harmonics.len()),
                format!("at most {MAX_HARMONICS} per raceway"),
            ));
        }
        for (h, w) in self.harmonics.iter().enumerate() {
            if w.number == 0 {
                return Err(ParamError::new(
                    format!("{prefix}.harmonics[{h}].number"),
                    w.number,
                    "an integer >= 1",
                ));
            }
            super::non_negative(&format!("{prefix}.harmonics[{h}].amplitude"), w.amplitude)?;
            if !w.phase.is_finite() {
                return Err(ParamError::new(
                    format!("{prefix}.harmonics[{h}].phase"),
                    w.phase,
                    "a finite angle in rad",
                ));
            }
        }
        Ok(())
    }
}

/// Most harmonics one raceway may carry (a sanity limit on grid input).
pub const MAX_HARMONICS: usize = 16;
