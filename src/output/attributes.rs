//! Reading and writing scalar HDF5 attributes (strings as variable-length UTF-8).

use std::str::FromStr;

use hdf5::types::{TypeDescriptor, VarLenAscii, VarLenUnicode};
use hdf5::Location;

use super::layout::AttrValue;

/// A variable-length UTF-8 string, or an HDF5 error if it holds a NUL byte.
pub(super) fn vlen(s: &str) -> hdf5::Result<VarLenUnicode> {
    VarLenUnicode::from_str(s).map_err(|e| hdf5::Error::from(format!("{s:?}: {e}")))
}

/// Writes the scalar attribute `name` on `loc`.
pub(super) fn write(loc: &Location, name: &str, value: &AttrValue) -> hdf5::Result<()> {
    match value {
        AttrValue::Str(s) => write_str(loc, name, s),
        AttrValue::F64(x) => loc.new_attr::<f64>().create(name)?.write_scalar(x),
        AttrValue::I64(x) => loc.new_attr::<i64>().create(name)?.write_scalar(x),
    }
}

/// Writes the scalar string attribute `name` on `loc`.
pub(super) fn write_str(loc: &Location, name: &str, value: &str) -> hdf5::Result<()> {
    loc.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&vlen(value)?)
}

/// Reads the scalar attribute `name` of `loc`: strings (variable-length), floats as
/// f64, integers as i64; other types and non-scalar attributes are errors.
pub(super) fn read(loc: &Location, name: &str) -> hdf5::Result<AttrValue> {
    let attr = loc.attr(name)?;
    match attr.dtype()?.to_descriptor()? {
        TypeDescriptor::VarLenUnicode => Ok(AttrValue::Str(
            attr.read_scalar::<VarLenUnicode>()?.as_str().to_owned(),
        )),
        TypeDescriptor::VarLenAscii => Ok(AttrValue::Str(
            attr.read_scalar::<VarLenAscii>()?.as_str().to_owned(),
        )),
        TypeDescriptor::Float(_) => Ok(AttrValue::F64(attr.read_scalar::<f64>()?)),
        TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) => {
            Ok(AttrValue::I64(attr.read_scalar::<i64>()?))
        }
        other => Err(hdf5::Error::from(format!(
            "attribute `{name}` has type {other}, expected a string or a number"
        ))),
    }
}

/// Reads the scalar string attribute `name` of `loc`.
pub(super) fn read_str(loc: &Location, name: &str) -> hdf5::Result<String> {
    match read(loc, name)? {
        AttrValue::Str(s) => Ok(s),
        other => Err(hdf5::Error::from(format!(
            "attribute `{name}` is {other:?}, expected a string"
        ))),
    }
}
