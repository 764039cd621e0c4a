//! Reading and writing HDF5 attributes. studyrun writes scalars (strings as
//! variable-length UTF-8, except `history`: see [`write`]); it reads them back however
//! netCDF tools rewrote them: strings of any kind ([`text`](super::text)), and any
//! one-element dataspace as a scalar.

use std::str::FromStr;

use hdf5::types::{TypeDescriptor, VarLenUnicode};
use hdf5::Location;

use super::layout::AttrValue;
use super::text::{self, Strings};
use crate::signal::DESCRIPTIVE_ATTRIBUTES;

/// The root attribute netCDF tools append their command lines to (CF §2.6.2).
pub(super) const HISTORY: &str = "history";

/// A variable-length UTF-8 string, or an HDF5 error if it holds a NUL byte.
pub(super) fn vlen(s: &str) -> hdf5::Result<VarLenUnicode> {
    VarLenUnicode::from_str(s).map_err(|e| hdf5::Error::from(format!("{s:?}: {e}")))
}

/// Writes the scalar attribute `name` on `loc`. A string named `history` is written
/// as netCDF's NC_CHAR (a fixed-length string, as netCDF-C and NCO write it), so that
/// NCO appends its own lines to it.
pub(super) fn write(loc: &Location, name: &str, value: &AttrValue) -> hdf5::Result<()> {
    match value {
        AttrValue::Str(s) if name == HISTORY => write_char(loc, name, s),
        AttrValue::Str(s) => write_str(loc, name, s),
        AttrValue::F64(x) => loc.new_attr::<f64>().create(name)?.write_scalar(x),
        AttrValue::I64(x) => loc.new_attr::<i64>().create(name)?.write_scalar(x),
    }
}

/// Writes the scalar string attribute `name` on `loc` (variable-length UTF-8).
pub(super) fn write_str(loc: &Location, name: &str, value: &str) -> hdf5::Result<()> {
    loc.new_attr::<VarLenUnicode>()
        .create(name)?
        .write_scalar(&vlen(value)?)
}

/// Writes `value` as netCDF's NC_CHAR: a scalar fixed-length string of exactly its
/// bytes, NUL-terminated pad, ASCII character set (netCDF-C's choice; UTF-8 bytes are
/// kept as they are). An empty string gets one NUL byte (HDF5 has no empty type).
fn write_char(loc: &Location, name: &str, value: &str) -> hdf5::Result<()> {
    use hdf5_sys::h5a::{H5Aclose, H5Acreate2, H5Awrite};
    use hdf5_sys::h5p::H5P_DEFAULT;
    use hdf5_sys::h5s::{H5S_class_t, H5Sclose, H5Screate};
    use hdf5_sys::h5t::{
        H5T_cset_t, H5T_str_t, H5Tclose, H5Tcopy, H5Tset_cset, H5Tset_size, H5Tset_strpad, H5T_C_S1,
    };
    if value.contains('\0') {
        return Err(format!("attribute `{name}` contains NUL").into());
    }
    let c_name = std::ffi::CString::new(name).map_err(|e| e.to_string())?;
    let mut bytes = value.as_bytes().to_vec();
    if bytes.is_empty() {
        bytes.push(0);
    }
    let id = loc.id();
    hdf5::sync::sync(|| {
        // SAFETY: every id is created here and closed before returning; `c_name` and
        // `bytes` outlive the calls, and `bytes` holds exactly the type's size.
        unsafe {
            let t = hdf5::h5check(H5Tcopy(*H5T_C_S1))?;
            let s = H5Screate(H5S_class_t::H5S_SCALAR);
            let written = (|| {
                hdf5::h5check(s)?;
                hdf5::h5check(H5Tset_size(t, bytes.len()))?;
                hdf5::h5check(H5Tset_strpad(t, H5T_str_t::H5T_STR_NULLTERM))?;
                hdf5::h5check(H5Tset_cset(t, H5T_cset_t::H5T_CSET_ASCII))?;
                let a = hdf5::h5check(H5Acreate2(
                    id,
                    c_name.as_ptr(),
                    t,
                    s,
                    H5P_DEFAULT,
                    H5P_DEFAULT,
                ))?;
                let status = H5Awrite(a, t, bytes.as_ptr().cast());
                H5Aclose(a);
                hdf5::h5check(status).map(|_| ())
            })();
            if s >= 0 {
                H5Sclose(s);
            }
            H5Tclose(t);
            written
        }
    })
}

/// Reads attribute `name` of `loc` as a scalar: a string (any kind; a NULL dataspace
/// reads as ""), a float (as f64) or an integer (as i64), each in a scalar or a
/// one-element dataspace. Ok(Err(why)) for anything else (arrays, other types).
pub(super) fn read_value(loc: &Location, name: &str) -> hdf5::Result<Result<AttrValue, String>> {
    let attr = loc.attr(name)?;
    if let Strings::Text(mut v) = text::read_attribute(&attr)? {
        return Ok(if v.len() == 1 {
            Ok(AttrValue::Str(v.remove(0)))
        } else {
            Err(format!("attribute `{name}` holds {} strings", v.len()))
        });
    }
    let n = attr.space()?.size();
    let value = match attr.dtype()?.to_descriptor()? {
        TypeDescriptor::Float(_) if n == 1 => AttrValue::F64(attr.read_raw::<f64>()?[0]),
        TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) if n == 1 => {
            AttrValue::I64(attr.read_raw::<i64>()?[0])
        }
        TypeDescriptor::Float(_) | TypeDescriptor::Integer(_) | TypeDescriptor::Unsigned(_) => {
            return Ok(Err(format!("attribute `{name}` holds {n} numbers")))
        }
        other => return Ok(Err(format!("attribute `{name}` has type {other}"))),
    };
    Ok(Ok(value))
}

/// Reads attribute `name` of `loc` like [`read_value`]; anything but a string or a
/// number is an error.
pub(super) fn read(loc: &Location, name: &str) -> hdf5::Result<AttrValue> {
    read_value(loc, name)?
        .map_err(|why| hdf5::Error::from(format!("{why}, expected a string or a number")))
}

/// Reads the string attribute `name` of `loc`.
pub(super) fn read_str(loc: &Location, name: &str) -> hdf5::Result<String> {
    match read(loc, name)? {
        AttrValue::Str(s) => Ok(s),
        other => Err(hdf5::Error::from(format!(
            "attribute `{name}` is {other:?}, expected a string"
        ))),
    }
}

/// The [`DESCRIPTIVE_ATTRIBUTES`] among `names`, the attributes of `ds`, with their
/// values, in that list's order.
pub(super) fn descriptive(
    ds: &Location,
    names: &[String],
) -> hdf5::Result<Vec<(String, AttrValue)>> {
    DESCRIPTIVE_ATTRIBUTES
        .iter()
        .filter(|d| names.iter().any(|n| n == *d))
        .map(|&d| Ok((d.to_string(), read(ds, d)?)))
        .collect()
}
