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

/// A raceway's waviness tabulated for a ball set: per harmonic, the rotation
/// `(cos N α_r, sin N α_r)` of every ball's base angle `α_r`, so that one sin/cos
/// pair per harmonic serves all balls. Harmonics of zero amplitude are dropped,
/// so a race without waviness costs nothing.
#[derive(Debug, Clone)]
pub(crate) struct RaceProfile {
    offset: f64,
    harmonics: Vec<Harmonic>,
    /// `rot[h * balls + r] = (cos N_h α_r, sin N_h α_r)`.
    rot: Vec<[f64; 2]>,
    balls: usize,
}

/// Most harmonics one raceway may carry (keeps the per-evaluation phases on the stack).
pub const MAX_HARMONICS: usize = 16;

/// `(sin, cos)` of `N_h ψ + φ_h` for each harmonic, at one race angle `ψ`.
pub(crate) type RacePhase = [[f64; 2]; MAX_HARMONICS];

impl RaceProfile {
    pub(crate) fn new(w: &RaceWaviness, base_angles: &[f64]) -> Self {
        let harmonics: Vec<Harmonic> = w
            .harmonics
            .iter()
            .copied()
            .filter(|h| h.amplitude > 0.0)
            .collect();
        let rot = harmonics
            .iter()
            .flat_map(|h| {
                base_angles
                    .iter()
                    .map(move |a| [(h.number as f64 * a).cos(), (h.number as f64 * a).sin()])
            })
            .collect();
        Self {
            offset: w.offset,
            harmonics,
            rot,
            balls: base_angles.len(),
        }
    }

    /// Phases of every harmonic at race angle `psi` (rad) of ball 1.
    pub(crate) fn at(&self, psi: f64) -> RacePhase {
        let mut out = [[0.0; 2]; MAX_HARMONICS];
        for (o, h) in out.iter_mut().zip(&self.harmonics) {
            let (s, c) = (h.number as f64 * psi + h.phase).sin_cos();
            *o = [s, c];
        }
        out
    }

    /// Height `Π` (m) under ball `r`: `Π_T + Σ A sin(N(α_r + ψ) + φ)`.
    pub(crate) fn height(&self, r: usize, phase: &RacePhase) -> f64 {
        self.offset
            + self
                .harmonics
                .iter()
                .zip(phase)
                .enumerate()
                .map(|(h, (w, sc))| {
                    let [c, s] = self.rot[h * self.balls + r];
                    w.amplitude * (s * sc[1] + c * sc[0])
                })
                .sum::<f64>()
    }

    /// `dΠ/dψ` (m/rad) under ball `r`: `Σ A N cos(N(α_r + ψ) + φ)`.
    pub(crate) fn slope(&self, r: usize, phase: &RacePhase) -> f64 {
        self.harmonics
            .iter()
            .zip(phase)
            .enumerate()
            .map(|(h, (w, sc))| {
                let [c, s] = self.rot[h * self.balls + r];
                w.amplitude * w.number as f64 * (c * sc[1] - s * sc[0])
            })
            .sum()
    }
}
