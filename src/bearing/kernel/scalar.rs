//! The kernel's scalar twin: one ball at a time, every waviness height from its own
//! `sin`, the reference for parity tests and the energy terms.

use super::*;

impl BallSet {
    /// Ball `r` (0-based) at state `s`, computed on its own: the scalar twin of
    /// [`BallSet::force`], with each waviness height from its own `sin(N ψ_r + φ)`.
    pub fn ball(&self, r: usize, s: &ContactState) -> Ball {
        self.ball_in(r, s, None)
    }

    /// [`BallSet::ball`] under a held `regime` (the natural law when `None`): the
    /// scalar twin of [`BallSet::force_in`]. A ball of the regime's loaded set has
    /// the elastic force `K δ |δ|^{1/2}` whatever the sign of `δ`, plus its damping
    /// law's branch as the regime records it; any other ball carries nothing.
    pub fn ball_in(&self, r: usize, s: &ContactState, regime: Option<&Regime>) -> Ball {
        let alpha = std::f64::consts::TAU * r as f64 / self.balls as f64;
        let phi = alpha + s.cage;
        let normal = [phi.cos(), phi.sin()];
        let mut delta = s.e[0] * normal[0] + s.e[1] * normal[1] + self.base_offset;
        let (mut slope_in, mut slope_out) = (0.0, 0.0);
        for w in &self.waves {
            let psi = alpha
                + match w.race {
                    Race::Inner => s.psi_in,
                    Race::Outer => s.psi_out,
                };
            let arg = w.number * psi + w.phase;
            delta += w.amplitude * arg.sin();
            let slope = w.amplitude * w.number * arg.cos();
            match w.race {
                Race::Inner => slope_in += slope,
                Race::Outer => slope_out += slope,
            }
        }
        if let Some(defects) = &self.defects {
            for (k, track) in defects.tracks.iter().enumerate() {
                if r >= track.balls {
                    continue;
                }
                let pos = track.position(r, track.base_angle(s));
                let zone = match regime {
                    Some(held) => held.zone(k, r),
                    None => track.zone(pos),
                };
                let (lowering, rate) = track.lowering(zone, pos);
                delta -= lowering;
                let slope = -rate * track.arc_rate();
                if track.inner {
                    slope_in += slope;
                } else {
                    slope_out += slope;
                }
            }
        }
        let approach = s.v[0] * normal[0] + s.v[1] * normal[1];
        let rate = match self.law {
            ContactLaw::Hysteresis => self.hysteresis.of(r),
            _ => 0.0,
        };
        let (force, elastic) = match regime {
            None if delta > 0.0 => {
                let elastic = self.stiffness * delta * delta.sqrt();
                (self.law.force(elastic, approach, rate), elastic)
            }
            Some(held) if held.loaded(r) => {
                let elastic = self.stiffness * delta * delta.abs().sqrt();
                let force = self.law.held_force(elastic, approach, rate, held.acting(r));
                (force, elastic)
            }
            _ => (0.0, 0.0),
        };
        Ball {
            normal,
            delta,
            approach,
            force,
            elastic,
            slope_in,
            slope_out,
        }
    }
}
