//! Quantities with units: `"40 um"`, `"300 rpm"`, `"9.57e9 N/m^1.5"`, or plain SI numbers.

/// The physical dimension a parameter has, which decides the units it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Pure number (counts, ratios); no unit allowed.
    Dimensionless,
    /// Length, SI unit m.
    Length,
    /// Crank speed, stored in rev/min.
    Speed,
    /// Hertz contact stiffness, SI unit N/m^1.5.
    Stiffness,
    /// Viscous damping, SI unit N s/m.
    Damping,
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
}

impl Dimension {
    /// The unit values are stored in (CF-style string for files).
    pub fn base_unit(self) -> &'static str {
        self.units()[0].0
    }

    /// Accepted unit spellings with their factor to the base unit.
    fn units(self) -> &'static [(&'static str, f64)] {
        use std::f64::consts::PI;
        match self {
            Dimension::Dimensionless => &[("1", 1.0)],
            Dimension::Length => &[
                ("m", 1.0),
                ("mm", 1e-3),
                ("um", 1e-6),
                ("µm", 1e-6),
                ("μm", 1e-6),
                ("nm", 1e-9),
            ],
            Dimension::Speed => &[
                ("rpm", 1.0),
                ("rev/min", 1.0),
                ("rev/s", 60.0),
                ("Hz", 60.0),
                ("rad/s", 60.0 / (2.0 * PI)),
            ],
            Dimension::Stiffness => &[
                ("N m-1.5", 1.0),
                ("N/m^1.5", 1.0),
                ("N/m^(3/2)", 1.0),
                ("N m^-1.5", 1.0),
            ],
            Dimension::Damping => &[
                ("N s m-1", 1.0),
                ("N s/m", 1.0),
                ("N*s/m", 1.0),
                ("Ns/m", 1.0),
                ("kg/s", 1.0),
            ],
            Dimension::Time => &[
                ("s", 1.0),
                ("ms", 1e-3),
                ("us", 1e-6),
                ("µs", 1e-6),
                ("μs", 1e-6),
            ],
            Dimension::Frequency => &[("Hz", 1.0), ("kHz", 1e3), ("MHz", 1e6)],
            Dimension::Mass => &[("kg", 1.0), ("g", 1e-3)],
            Dimension::Inertia => &[
                ("kg m2", 1.0),
                ("kg m^2", 1.0),
                ("kg*m^2", 1.0),
                ("kg mm^2", 1e-6),
            ],
            Dimension::Angle => &[("rad", 1.0), ("deg", PI / 180.0)],
            Dimension::Pressure => &[("Pa", 1.0), ("kPa", 1e3), ("MPa", 1e6), ("GPa", 1e9)],
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
        self.units()
            .iter()
            .find(|(name, _)| *name == unit)
            .map(|(_, factor)| value * factor)
            .ok_or_else(|| {
                format!(
                    "unknown unit `{unit}` in `{text}`; expected {}",
                    self.accepted()
                )
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
        assert_eq!(Length.parse("0.04 mm").unwrap(), 0.04e-3);
        assert_eq!(Speed.parse("300 rpm").unwrap(), 300.0);
        assert_eq!(Speed.parse("5 Hz").unwrap(), 300.0);
        assert_eq!(Stiffness.parse("9.57e9 N/m^1.5").unwrap(), 9.57e9);
        assert_eq!(Time.parse("20 us").unwrap(), 20e-6);
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
