//! Quantities with units: `"40 um"`, `"300 rpm"`, `"9.57e9 N/m^1.5"`, or plain SI numbers.

/// How a unit converts to its dimension's base unit.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Factor {
    /// Multiply by 10^k (applied on the decimal string, so it is exact).
    Pow10(i32),
    /// Multiply by this factor.
    Scale(f64),
}

/// The physical dimension a parameter has, which decides the units it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Pure number (counts, ratios); no unit allowed.
    Dimensionless,
    /// Length, SI unit m.
    Length,
    /// Crank speed, stored in rev/min.
    Speed,
    /// Hertz contact stiffness, SI unit N/m^(3/2) (N m^-1.5).
    Stiffness,
    /// Linear spring stiffness, SI unit N/m.
    SpringStiffness,
    /// Viscous damping, SI unit N s/m.
    Damping,
    /// A rate per unit speed (the Hunt–Crossley `α`), SI unit s/m.
    InverseSpeed,
    /// Time, SI unit s.
    Time,
    /// Frequency, SI unit Hz.
    Frequency,
    /// Mass, SI unit kg.
    Mass,
    /// Moment of inertia, SI unit kg m^2.
    Inertia,
    /// Angle, SI unit rad.
    Angle,
    /// Pressure or elastic modulus, SI unit Pa.
    Pressure,
    /// Dynamic viscosity, SI unit Pa s.
    Viscosity,
    /// A linear speed (a sliding speed), SI unit m/s.
    Velocity,
}

impl Dimension {
    /// The unit values are given and stored in, as messages name it.
    pub fn base_unit(self) -> &'static str {
        self.units()[0].0
    }

    /// The `units` attribute of a study file's variable holding values in
    /// [`base_unit`](Self::base_unit): a UDUNITS string that reads as the right
    /// quantity. That is the base unit itself but for the Hertz stiffness: no UDUNITS
    /// string means N/m^(3/2) (it has no fractional powers), so a file states the
    /// stiffness K as the force at 1 m of deflection, K·(1 m)^(3/2) in `N`, which is K's
    /// number in N/m^(3/2).
    pub fn file_units(self) -> &'static str {
        match self {
            Dimension::Stiffness => "N",
            _ => self.base_unit(),
        }
    }

    /// Accepted unit spellings with their factor to the base unit.
    fn units(self) -> &'static [(&'static str, Factor)] {
        use std::f64::consts::PI;
        use Factor::{Pow10 as P, Scale as X};
        match self {
            Dimension::Dimensionless => &[("1", P(0))],
            Dimension::Length => &[
                ("m", P(0)),
                ("mm", P(-3)),
                ("um", P(-6)),
                ("µm", P(-6)),
                ("μm", P(-6)),
                ("nm", P(-9)),
                ("in", X(0.0254)),
            ],
            Dimension::Speed => &[
                ("rpm", P(0)),
                ("rev/min", P(0)),
                ("rev/s", X(60.0)),
                ("Hz", X(60.0)),
                ("rad/s", X(60.0 / (2.0 * PI))),
            ],
            // UDUNITS reads every spelling of these it accepts (`N m-1.5` as 0.5 kg s-2)
            // as another quantity: files use `file_units` instead.
            Dimension::Stiffness => &[
                ("N/m^(3/2)", P(0)),
                ("N m-1.5", P(0)),
                ("N/m^1.5", P(0)),
                ("N m^-1.5", P(0)),
            ],
            Dimension::SpringStiffness => &[
                ("N m-1", P(0)),
                ("N/m", P(0)),
                ("kN/m", P(3)),
                ("MN/m", P(6)),
                ("N/mm", P(3)),
            ],
            Dimension::Damping => &[
                ("N s m-1", P(0)),
                ("N s/m", P(0)),
                ("N*s/m", P(0)),
                ("Ns/m", P(0)),
                ("kg/s", P(0)),
            ],
            Dimension::InverseSpeed => &[("s m-1", P(0)), ("s/m", P(0))],
            Dimension::Time => &[
                ("s", P(0)),
                ("ms", P(-3)),
                ("us", P(-6)),
                ("µs", P(-6)),
                ("μs", P(-6)),
            ],
            Dimension::Frequency => &[("Hz", P(0)), ("kHz", P(3)), ("MHz", P(6))],
            Dimension::Mass => &[("kg", P(0)), ("g", P(-3))],
            Dimension::Inertia => &[
                ("kg m2", P(0)),
                ("kg m^2", P(0)),
                ("kg*m^2", P(0)),
                ("kg mm^2", P(-6)),
            ],
            Dimension::Angle => &[("rad", P(0)), ("deg", X(PI / 180.0))],
            Dimension::Pressure => &[("Pa", P(0)), ("kPa", P(3)), ("MPa", P(6)), ("GPa", P(9))],
            Dimension::Viscosity => &[
                ("Pa s", P(0)),
                ("Pa*s", P(0)),
                ("mPa s", P(-3)),
                ("cP", P(-3)),
            ],
            Dimension::Velocity => &[("m s-1", P(0)), ("m/s", P(0)), ("mm/s", P(-3))],
        }
    }

    /// The accepted unit spellings, for error messages.
    pub fn accepted(self) -> String {
        match self {
            Dimension::Dimensionless => "a plain number".to_string(),
            _ => {
                let names: Vec<&str> = self.units().iter().map(|u| u.0).collect();
                format!(
                    "a number in {} or a string with one of: {}",
                    self.base_unit(),
                    names.join(", ")
                )
            }
        }
    }

    /// Parses `"<number> <unit>"` (or a bare number, taken in the base unit) into the
    /// base unit. Returns a message naming what is accepted on failure.
    pub fn parse(self, text: &str) -> Result<f64, String> {
        let text = text.trim();
        let split = text
            .find(|c: char| !(c.is_ascii_digit() || matches!(c, '.' | '-' | '+' | 'e' | 'E')))
            .unwrap_or(text.len());
        // "e" may start a unit only after a complete number; back off if the number does not parse.
        let (num, unit) = text.split_at(split);
        let value: f64 = num.trim().parse().map_err(|_| {
            format!(
                "`{text}` is not a number with a unit; expected {}",
                self.accepted()
            )
        })?;
        let unit = unit.trim();
        if unit.is_empty() {
            return Ok(value);
        }
        let factor = self
            .units()
            .iter()
            .find(|(name, _)| *name == unit)
            .map(|(_, factor)| *factor)
            .ok_or_else(|| {
                format!(
                    "unknown unit `{unit}` in `{text}`; expected {}",
                    self.accepted()
                )
            })?;
        Ok(match factor {
            // Shift the decimal exponent so "40 um" is exactly 40e-6 (correctly rounded).
            Factor::Pow10(k) => {
                let num = num.trim();
                let (mantissa, exp) = match num.find(['e', 'E']) {
                    Some(i) => (&num[..i], num[i + 1..].parse::<i32>().unwrap_or(0)),
                    None => (num, 0),
                };
                format!("{mantissa}e{}", exp + k)
                    .parse()
                    .unwrap_or(value * 10f64.powi(k))
            }
            Factor::Scale(x) => value * x,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::Dimension::*;

    #[test]
    fn parses_numbers_with_units() {
        assert_eq!(Length.parse("40 um").unwrap(), 40e-6);
        assert_eq!(Length.parse("4µm").unwrap(), 4e-6);
        assert_eq!(Length.parse("0.3126 in").unwrap(), 0.3126 * 0.0254);
        assert_eq!(Length.parse("0.04 mm").unwrap(), 0.04e-3);
        assert_eq!(Speed.parse("300 rpm").unwrap(), 300.0);
        assert_eq!(Speed.parse("5 Hz").unwrap(), 300.0);
        assert_eq!(Stiffness.parse("9.57e9 N/m^1.5").unwrap(), 9.57e9);
        assert_eq!(Viscosity.parse("0.4 Pa s").unwrap(), 0.4);
        assert_eq!(Viscosity.parse("40 cP").unwrap(), 0.04);
        assert_eq!(Viscosity.parse("40 mPa s").unwrap(), 0.04);
        assert_eq!(Velocity.parse("0.1 mm/s").unwrap(), 1e-4);
        assert_eq!(Velocity.parse("2 m/s").unwrap(), 2.0);
        assert_eq!(Stiffness.parse("9.57e9 N m-1.5").unwrap(), 9.57e9);
        assert_eq!(Stiffness.base_unit(), "N/m^(3/2)");
        assert_eq!(Time.parse("20 us").unwrap(), 20e-6);
        assert_eq!(SpringStiffness.parse("1e8 N/m").unwrap(), 1e8);
        assert_eq!(SpringStiffness.parse("100 MN/m").unwrap(), 1e8);
        assert!(SpringStiffness.parse("1e8 N/m^1.5").is_err());
        assert_eq!(Frequency.parse("50 kHz").unwrap(), 50e3);
        assert_eq!(Length.parse("1e-3").unwrap(), 1e-3);
    }

    #[test]
    fn refuses_wrong_units_naming_the_accepted_ones() {
        let e = Length.parse("40 rpm").unwrap_err();
        assert!(e.contains("unknown unit `rpm`") && e.contains("um"), "{e}");
        assert!(Length.parse("forty um").is_err());
        assert!(Dimensionless.parse("9 balls").is_err());
    }
}
