//! The crank's speed profile (docs/model.md §1.5): what a grid file's `speed:` gives
//! ([`SpeedProfile`], in rev/min, s and Hz), and the crank motion it prescribes
//! ([`CrankDrive`], in rad, rad/s and rad/s²), with the angle `θ2 = ∫ω dt` from 0,
//! its rate and its acceleration in closed form for every profile.

use std::f64::consts::PI;
use std::sync::Arc;

use crate::error::ParamError;

/// rad/s per rev/min.
const RAD_PER_S_PER_RPM: f64 = 2.0 * PI / 60.0;

/// A crank speed that varies in time (speeds in rev/min, times in s, frequencies in Hz).
#[derive(Debug, Clone, PartialEq)]
pub enum SpeedProfile {
    /// `ω` linear from `from` at `t = 0` to `to` at `t = over`, constant after.
    Ramp {
        /// Speed at `t = 0` (rev/min).
        from: f64,
        /// Speed from `t = over` on (rev/min).
        to: f64,
        /// Duration of the ramp (s).
        over: f64,
    },
    /// `ω = mean + amplitude · sin(2π frequency t)`.
    Sine {
        /// Mean speed (rev/min).
        mean: f64,
        /// Amplitude of the fluctuation (rev/min, below `mean`).
        amplitude: f64,
        /// Frequency of the fluctuation (Hz).
        frequency: f64,
    },
    /// `ω` piecewise linear through `(time[i], rpm[i])`, constant after the last knot.
    Table {
        /// Knot times (s): from 0, increasing.
        time: Vec<f64>,
        /// Speeds at the knots (rev/min).
        rpm: Vec<f64>,
    },
}

impl SpeedProfile {
    /// The profile's name in grid files and result files.
    pub fn name(&self) -> &'static str {
        match self {
            SpeedProfile::Ramp { .. } => "ramp",
            SpeedProfile::Sine { .. } => "sine",
            SpeedProfile::Table { .. } => "table",
        }
    }

    /// Checks every field: the speed is finite and > 0 at every instant, times and
    /// frequencies > 0, table times from 0 and increasing; the error names the field
    /// (`speed.from`, `speed.time[2]`, ...), its value and what is allowed.
    pub fn validate(&self) -> Result<(), ParamError> {
        let positive = |field: &str, v: f64, unit: &str| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(ParamError::new(field, v, format!("finite and > 0 {unit}")))
            }
        };
        match *self {
            SpeedProfile::Ramp { from, to, over } => {
                positive("speed.from", from, "rev/min")?;
                positive("speed.to", to, "rev/min")?;
                positive("speed.over", over, "s")
            }
            SpeedProfile::Sine {
                mean,
                amplitude,
                frequency,
            } => {
                positive("speed.mean", mean, "rev/min")?;
                if !(amplitude.is_finite() && (0.0..mean).contains(&amplitude)) {
                    return Err(ParamError::new(
                        "speed.amplitude",
                        amplitude,
                        format!(
                            ">= 0 and below speed.mean = {mean} rev/min (the speed must stay > 0)"
                        ),
                    ));
                }
                positive("speed.frequency", frequency, "Hz")
            }
            SpeedProfile::Table { ref time, ref rpm } => {
                if time.len() < 2 || time.len() != rpm.len() {
                    return Err(ParamError::new(
                        "speed.time",
                        format!("{} times and {} speeds", time.len(), rpm.len()),
                        "as many times as speeds (`rpm`), at least 2",
                    ));
                }
                if time[0] != 0.0 {
                    return Err(ParamError::new(
                        "speed.time[0]",
                        time[0],
                        "0 s (the profile starts at t = 0)",
                    ));
                }
                for k in 1..time.len() {
                    if !(time[k].is_finite() && time[k] > time[k - 1]) {
                        return Err(ParamError::new(
                            format!("speed.time[{k}]"),
                            time[k],
                            format!(
                                "finite and above speed.time[{}] = {} s (times increase)",
                                k - 1,
                                time[k - 1]
                            ),
                        ));
                    }
                }
                for (k, &v) in rpm.iter().enumerate() {
                    positive(&format!("speed.rpm[{k}]"), v, "rev/min")?;
                }
                Ok(())
            }
        }
    }

    /// The crank motion this profile prescribes. A profile whose speed never changes
    /// (a ramp with `from == to`, a sine of zero amplitude, a table of one speed) is
    /// [`CrankDrive::Constant`], the constant-speed model's own arithmetic.
    pub fn drive(&self) -> CrankDrive {
        if let Some(rpm) = self.constant_rpm() {
            return CrankDrive::constant(rpm);
        }
        let w = |rpm: f64| RAD_PER_S_PER_RPM * rpm;
        match *self {
            SpeedProfile::Ramp { from, to, over } => CrankDrive::Ramp {
                start: w(from),
                accel: (w(to) - w(from)) / over,
                over,
            },
            SpeedProfile::Sine {
                mean,
                amplitude,
                frequency,
            } => CrankDrive::Sine {
                mean: w(mean),
                amplitude: w(amplitude),
                nu: 2.0 * PI * frequency,
            },
            SpeedProfile::Table { ref time, ref rpm } => {
                let rate: Vec<f64> = rpm.iter().map(|&v| w(v)).collect();
                let n = time.len();
                let mut angle = vec![0.0; n];
                let mut slope = vec![0.0; n];
                for k in 1..n {
                    let dt = time[k] - time[k - 1];
                    angle[k] = angle[k - 1] + 0.5 * (rate[k - 1] + rate[k]) * dt;
                    slope[k - 1] = (rate[k] - rate[k - 1]) / dt;
                }
                CrankDrive::Table(Arc::new(Knots {
                    time: time.clone(),
                    rate,
                    angle,
                    slope,
                }))
            }
        }
    }

    /// The speed (rev/min) of a profile whose speed never changes, else `None`.
    pub fn constant_rpm(&self) -> Option<f64> {
        match *self {
            SpeedProfile::Ramp { from, to, .. } if from == to => Some(from),
            SpeedProfile::Sine {
                mean,
                amplitude: 0.0,
                ..
            } => Some(mean),
            SpeedProfile::Table { ref rpm, .. } if rpm.iter().all(|&v| v == rpm[0]) => Some(rpm[0]),
            _ => None,
        }
    }

    /// The time of the crank's first revolution (s): `60/rpm` for a profile whose
    /// speed never changes, else [`CrankDrive::first_revolution`].
    pub fn revolution_time(&self) -> f64 {
        match self.constant_rpm() {
            Some(rpm) => 60.0 / rpm,
            None => self.drive().first_revolution(),
        }
    }

    /// The profile's numbers as bits, for hashing equal profiles together (`-0` is `0`).
    pub fn key(&self) -> Vec<u64> {
        let bits = |x: f64| (x + 0.0).to_bits();
        match self {
            SpeedProfile::Ramp { from, to, over } => vec![0, bits(*from), bits(*to), bits(*over)],
            SpeedProfile::Sine {
                mean,
                amplitude,
                frequency,
            } => vec![1, bits(*mean), bits(*amplitude), bits(*frequency)],
            SpeedProfile::Table { time, rpm } => std::iter::once(2)
                .chain(time.iter().chain(rpm).map(|&x| bits(x)))
                .collect(),
        }
    }
}

/// The crank's angle, rate and acceleration at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CrankMotion {
    /// `θ2` (rad), 0 at `t = 0`.
    pub angle: f64,
    /// `θ̇2 = ω` (rad/s).
    pub rate: f64,
    /// `θ̈2 = α` (rad/s²).
    pub accel: f64,
}

/// The knots of a piecewise-linear speed: times (s), speeds (rad/s), the crank
/// angle reached at each (rad) and the acceleration after each (rad/s², 0 after
/// the last).
#[derive(Debug, Clone, PartialEq)]
pub struct Knots {
    time: Vec<f64>,
    rate: Vec<f64>,
    angle: Vec<f64>,
    slope: Vec<f64>,
}

/// The prescribed crank motion of one case (docs/model.md §1.5), each variant in
/// closed form.
#[derive(Debug, Clone, PartialEq)]
pub enum CrankDrive {
    /// `θ2 = ω t`.
    Constant {
        /// ω (rad/s).
        omega: f64,
    },
    /// `θ2 = ω0 t + α t²/2` up to `T`, then at the final speed `ω0 + α T`.
    Ramp {
        /// ω0 (rad/s).
        start: f64,
        /// α (rad/s²).
        accel: f64,
        /// T (s).
        over: f64,
    },
    /// `θ2 = ω_m t + (ω_a/ν)(1 − cos ν t)`.
    Sine {
        /// ω_m (rad/s).
        mean: f64,
        /// ω_a (rad/s).
        amplitude: f64,
        /// ν (rad/s).
        nu: f64,
    },
    /// Piecewise-linear ω through knots, constant after the last.
    Table(Arc<Knots>),
}

impl CrankDrive {
    /// Constant speed `rpm` (rev/min).
    pub fn constant(rpm: f64) -> Self {
        CrankDrive::Constant {
            omega: 2.0 * PI * rpm / 60.0,
        }
    }

    /// Whether the speed varies (else the crank's acceleration is 0 throughout).
    pub fn varies(&self) -> bool {
        !matches!(self, CrankDrive::Constant { .. })
    }

    /// Angle (rad), rate (rad/s) and acceleration (rad/s²) at time `t` (s, ≥ 0).
    #[inline]
    pub fn motion(&self, t: f64) -> CrankMotion {
        match *self {
            CrankDrive::Constant { omega } => CrankMotion {
                angle: omega * t,
                rate: omega,
                accel: 0.0,
            },
            CrankDrive::Ramp { start, accel, over } => {
                if t < over {
                    CrankMotion {
                        angle: t * (start + 0.5 * accel * t),
                        rate: start + accel * t,
                        accel,
                    }
                } else {
                    let end = start + accel * over;
                    CrankMotion {
                        angle: over * (start + 0.5 * accel * over) + end * (t - over),
                        rate: end,
                        accel: 0.0,
                    }
                }
            }
            CrankDrive::Sine {
                mean,
                amplitude,
                nu,
            } => {
                // One sin_cos of the half angle h = νt/2: 1 − cos νt = 2 sin²h (no
                // cancellation at small t), sin νt = 2 sin h cos h, cos νt = 1 − 2 sin²h.
                let (sh, ch) = (0.5 * nu * t).sin_cos();
                let versine = 2.0 * sh * sh;
                CrankMotion {
                    angle: mean * t + amplitude / nu * versine,
                    rate: mean + amplitude * (2.0 * sh * ch),
                    accel: amplitude * nu * (1.0 - versine),
                }
            }
            CrankDrive::Table(ref k) => {
                let n = k.time.len();
                let i = k.time.partition_point(|&ti| ti <= t);
                if i >= n {
                    let last = n - 1;
                    return CrankMotion {
                        angle: k.angle[last] + k.rate[last] * (t - k.time[last]),
                        rate: k.rate[last],
                        accel: 0.0,
                    };
                }
                let j = i.max(1) - 1;
                let slope = k.slope[j];
                let tau = t - k.time[j];
                CrankMotion {
                    angle: k.angle[j] + tau * (k.rate[j] + 0.5 * slope * tau),
                    rate: k.rate[j] + slope * tau,
                    accel: slope,
                }
            }
        }
    }

    /// The time (s) the crank takes for its first revolution, `θ2(t) = 2π`: one
    /// revolution, the default transient (docs/model.md §5.3). The angle grows
    /// strictly (ω > 0), so bisection finds it to round-off.
    pub fn first_revolution(&self) -> f64 {
        if let CrankDrive::Constant { omega } = *self {
            return 2.0 * PI / omega;
        }
        let turn = 2.0 * PI;
        let mut hi = 1e-3;
        while self.motion(hi).angle < turn && hi < 1e12 {
            hi *= 2.0;
        }
        let mut lo = 0.0;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if self.motion(mid).angle < turn {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        hi
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profiles() -> Vec<SpeedProfile> {
        vec![
            SpeedProfile::Ramp {
                from: 300.0,
                to: 900.0,
                over: 0.3,
            },
            SpeedProfile::Ramp {
                from: 900.0,
                to: 300.0,
                over: 0.2,
            },
            SpeedProfile::Sine {
                mean: 600.0,
                amplitude: 150.0,
                frequency: 7.0,
            },
            SpeedProfile::Table {
                time: vec![0.0, 0.1, 0.25, 0.3],
                rpm: vec![300.0, 800.0, 500.0, 650.0],
            },
        ]
    }

    /// The closed-form angle equals `∫ω dt` by composite Simpson over 0..0.5 s
    /// (steps of 1e-5 s, knots on the grid: exact for the piecewise quadratics,
    /// 1e-12 rad for the sine), and the acceleration is dω/dt by central differences.
    #[test]
    fn angle_is_the_integral_of_the_rate_and_accel_its_derivative() {
        for p in profiles() {
            p.validate().unwrap();
            let d = p.drive();
            assert!(d.varies(), "{p:?}");
            let h = 1e-5;
            let mut integral = 0.0;
            for k in 0..50_000 {
                let t = k as f64 * h;
                let (a, m, b) = (d.motion(t), d.motion(t + 0.5 * h), d.motion(t + h));
                integral += h / 6.0 * (a.rate + 4.0 * m.rate + b.rate);
                if k % 997 == 0 {
                    let angle = d.motion(t + h).angle;
                    assert!(
                        (angle - integral).abs() <= 1e-11 * angle.max(1.0),
                        "{p:?} at {} s: {angle} vs {integral}",
                        t + h
                    );
                }
            }
            for t in [0.013, 0.17, 0.23, 0.41] {
                let e = 1e-6;
                let fd = (d.motion(t + e).rate - d.motion(t - e).rate) / (2.0 * e);
                let scale = d.motion(t).accel.abs().max(1.0);
                assert!(
                    (fd - d.motion(t).accel).abs() < 1e-6 * scale,
                    "{p:?} at {t} s"
                );
            }
        }
    }

    #[test]
    fn first_revolution_turns_the_crank_once() {
        for p in profiles() {
            let d = p.drive();
            let t = d.first_revolution();
            assert!((d.motion(t).angle - 2.0 * PI).abs() < 1e-12, "{p:?}");
        }
        assert_eq!(CrankDrive::constant(300.0).first_revolution(), 0.2);
    }

    #[test]
    fn unchanging_profiles_are_the_constant_drive() {
        let constant = CrankDrive::constant(300.0);
        for p in [
            SpeedProfile::Ramp {
                from: 300.0,
                to: 300.0,
                over: 1.0,
            },
            SpeedProfile::Sine {
                mean: 300.0,
                amplitude: 0.0,
                frequency: 3.0,
            },
            SpeedProfile::Table {
                time: vec![0.0, 1.0],
                rpm: vec![300.0, 300.0],
            },
        ] {
            assert_eq!(p.drive(), constant, "{p:?}");
        }
    }

    #[test]
    fn bad_profiles_are_refused_naming_the_field() {
        let cases = [
            (
                SpeedProfile::Ramp {
                    from: 0.0,
                    to: 900.0,
                    over: 1.0,
                },
                "speed.from",
            ),
            (
                SpeedProfile::Ramp {
                    from: 300.0,
                    to: 900.0,
                    over: 0.0,
                },
                "speed.over",
            ),
            (
                SpeedProfile::Sine {
                    mean: 300.0,
                    amplitude: 300.0,
                    frequency: 1.0,
                },
                "speed.amplitude",
            ),
            (
                SpeedProfile::Sine {
                    mean: 300.0,
                    amplitude: 10.0,
                    frequency: -1.0,
                },
                "speed.frequency",
            ),
            (
                SpeedProfile::Table {
                    time: vec![0.0, 0.2, 0.2],
                    rpm: vec![300.0, 400.0, 500.0],
                },
                "speed.time[2]",
            ),
            (
                SpeedProfile::Table {
                    time: vec![0.1, 0.2],
                    rpm: vec![300.0, 400.0],
                },
                "speed.time[0]",
            ),
            (
                SpeedProfile::Table {
                    time: vec![0.0, 0.2],
                    rpm: vec![300.0, -1.0],
                },
                "speed.rpm[1]",
            ),
            (
                SpeedProfile::Table {
                    time: vec![0.0, 0.2],
                    rpm: vec![300.0],
                },
                "speed.time",
            ),
        ];
        for (p, field) in cases {
            assert_eq!(p.validate().unwrap_err().field, field, "{p:?}");
        }
    }
}
