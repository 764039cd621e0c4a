//! What names a stored quantity: [`VarSpec`], the name, units and long name every
//! analysed quantity carries into the result file.

/// Name and CF-style metadata of one variable.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VarSpec {
    /// Variable name in the file: non-empty, no `/`, no NUL, not starting with `_`
    /// (netCDF reserves those), not one of the dimension or built-in names.
    pub name: String,
    /// CF/UDUNITS units string, e.g. `m s-2`; `1` for dimensionless.
    pub units: String,
    /// Human-readable description (CF `long_name`).
    pub long_name: String,
}

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
        }
    }
}
