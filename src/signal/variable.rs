//! What names a stored quantity: [`VarSpec`], the name, units, long name and the
//! attributes saying how it was made that every analysed quantity carries into the
//! result file.

/// Name and CF-style metadata of one variable.
#[derive(Debug, Clone, PartialEq)]
pub struct VarSpec {
    /// Variable name in the file: non-empty, no `/`, no NUL, not starting with `_`
    /// (netCDF reserves those), not one of the dimension or built-in names.
    pub name: String,
    /// CF/UDUNITS units string, e.g. `m s-2`; `1` for dimensionless.
    pub units: String,
    /// Human-readable description (CF `long_name`).
    pub long_name: String,
    /// How the values were made, as attributes of the variable (names from
    /// [`DESCRIPTIVE_ATTRIBUTES`]): a spectrum's window and normalisation, an STFT's
    /// segment and hop, an envelope's band.
    pub attributes: Vec<(String, AttrValue)>,
}

/// The attributes a variable may carry to say how it was made; a reader takes these
/// back from a file, so that a merge copies them.
pub const DESCRIPTIVE_ATTRIBUTES: [&str; 7] = [
    "window",
    "normalisation",
    "band",
    "stft_segment",
    "stft_hop",
    "order_revolutions",
    "order_samples",
];

impl VarSpec {
    /// A spec from its three strings.
    pub fn new(
        name: impl Into<String>,
        units: impl Into<String>,
        long_name: impl Into<String>,
    ) -> Self {
        Self {
            name: name.into(),
            units: units.into(),
            long_name: long_name.into(),
            attributes: Vec::new(),
        }
    }

    /// The spec with the attribute `name` (one of [`DESCRIPTIVE_ATTRIBUTES`]) set to
    /// `value`.
    #[must_use]
    pub fn with(mut self, name: &str, value: impl Into<AttrValue>) -> Self {
        debug_assert!(DESCRIPTIVE_ATTRIBUTES.contains(&name), "{name}");
        self.attributes.push((name.to_string(), value.into()));
        self
    }
}

/// The value of an attribute (of the file's root or of a variable).
#[derive(Debug, Clone, PartialEq)]
pub enum AttrValue {
    /// A variable-length UTF-8 string (no NUL bytes).
    Str(String),
    /// A float64 scalar.
    F64(f64),
    /// An int64 scalar.
    I64(i64),
}

impl AttrValue {
    /// The text of a string value.
    pub fn as_text(&self) -> Option<&str> {
        match self {
            Self::Str(s) => Some(s),
            _ => None,
        }
    }
}

impl From<&str> for AttrValue {
    fn from(s: &str) -> Self {
        Self::Str(s.to_owned())
    }
}

impl From<String> for AttrValue {
    fn from(s: String) -> Self {
        Self::Str(s)
    }
}

impl From<f64> for AttrValue {
    fn from(x: f64) -> Self {
        Self::F64(x)
    }
}

impl From<i64> for AttrValue {
    fn from(x: i64) -> Self {
        Self::I64(x)
    }
}
