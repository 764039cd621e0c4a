//! NumPy's `.npy` arrays (format versions 1.0, 2.0 and 3.0) and `.npz` archives of
//! them.
//!
//! An `.npy` file is the magic `\x93NUMPY`, the format's major and minor version,
//! the header's length (2 bytes little-endian in version 1, 4 bytes in versions 2
//! and 3), the header (a Python dict literal, ASCII in versions 1–2 and UTF-8 in 3:
//! `{'descr': '<f8', 'fortran_order': False, 'shape': (1000,), }`), then the
//! elements. For one column the element order is the same C or Fortran.

use super::bytes::{decode, Cursor, Endian, Number};
use super::{listed, zip, Fault, Loaded};

/// The bytes every `.npy` file starts with.
const MAGIC: &[u8] = b"\x93NUMPY";

/// The dtypes read, as messages name them.
const DTYPES: &str =
    "a little- or big-endian float (f4, f8) or integer (i1, i2, i4, i8, u1, u2, u4, u8) dtype";

/// What the header says.
#[derive(Debug, PartialEq)]
struct Header {
    /// The element type and byte order.
    number: Number,
    endian: Endian,
    /// The shape, outermost first.
    shape: Vec<usize>,
}

/// Reads the `.npy` array in `data`, naming it `name` in messages.
pub(super) fn read(data: &[u8], name: &str) -> Result<Loaded, Fault> {
    let mut c = Cursor::new(data);
    if c.take(MAGIC.len(), "the .npy magic")? != MAGIC {
        return Err(Fault::Corrupt(format!(
            "{name} is not a NumPy .npy array (no \\x93NUMPY magic)"
        )));
    }
    let version = c.take(2, "the .npy version")?;
    let length = match version[0] {
        1 => usize::from(c.u16(Endian::Little, "the .npy header length")?),
        2 | 3 => c.u32(Endian::Little, "the .npy header length")? as usize,
        major => {
            return Err(Fault::Unsupported(format!(
                "{name} is .npy format version {major}.{}; versions 1.0, 2.0 and 3.0 are read",
                version[1]
            )))
        }
    };
    let text = std::str::from_utf8(c.take(length, "the .npy header")?)
        .map_err(|_| Fault::Corrupt(format!("{name}: the .npy header is not UTF-8 text")))?;
    let header = parse_header(text).map_err(|e| Fault::Corrupt(format!("{name}: {e}")))?;
    let n = one_column(&header.shape).ok_or_else(|| {
        let shape = tuple(&header.shape);
        Fault::Shape(name.to_string(), shape)
    })?;
    let bytes = n
        .checked_mul(header.number.size())
        .filter(|&b| b == c.remaining())
        .ok_or_else(|| {
            Fault::Corrupt(format!(
                "{name}: the header's shape {} of {}-byte elements does not fit the {} bytes of data",
                tuple(&header.shape),
                header.number.size(),
                c.remaining()
            ))
        })?;
    Ok(Loaded {
        name: name.to_string(),
        values: decode(
            c.take(bytes, "the .npy data")?,
            header.number,
            header.endian,
        ),
        sample_rate: None,
    })
}

/// Reads member `variable` (with or without `.npy`) of the `.npz` archive in `data`,
/// or its only member when `variable` is `None`.
pub(super) fn read_npz(data: &[u8], variable: Option<&str>) -> Result<Loaded, Fault> {
    let members = zip::members(data)?;
    let names: Vec<String> = members
        .iter()
        .map(|m| m.name.strip_suffix(".npy").unwrap_or(&m.name).to_string())
        .collect();
    let at = match variable {
        Some(v) => {
            let v = v.strip_suffix(".npy").unwrap_or(v);
            names.iter().position(|n| n == v).ok_or_else(|| {
                Fault::Select(format!("no member `{v}`; it holds {}", listed(&names)))
            })?
        }
        None if members.len() == 1 => 0,
        None => {
            return Err(Fault::Select(format!(
                "{} members; choose one of {}",
                members.len(),
                listed(&names)
            )))
        }
    };
    let bytes = zip::extract(data, &members[at])?;
    read(&bytes, &names[at])
}

/// The number of elements of a one-column shape: (N,), (N, 1) or (1, N).
fn one_column(shape: &[usize]) -> Option<usize> {
    match *shape {
        [n] | [n, 1] | [1, n] => Some(n),
        _ => None,
    }
}

/// A shape as Python writes it: `(3,)`, `(2, 3)`, `()`.
fn tuple(shape: &[usize]) -> String {
    match shape {
        [n] => format!("({n},)"),
        _ => {
            let dims: Vec<String> = shape.iter().map(usize::to_string).collect();
            format!("({})", dims.join(", "))
        }
    }
}

/// A value of the header dict.
#[derive(Debug, PartialEq)]
enum Value {
    Str(String),
    Bool(bool),
    Tuple(Vec<usize>),
}

/// Parses the header dict: `descr`, `fortran_order` and `shape`, in any order.
fn parse_header(text: &str) -> Result<Header, String> {
    let body = text
        .trim()
        .strip_prefix("{")
        .and_then(|t| t.strip_suffix("}"))
        .ok_or("the .npy header is not a dict literal")?;
    let (mut descr, mut shape, mut order) = (None, None, None);
    let mut rest = body.trim_start();
    while !rest.is_empty() {
        let (key, after) = quoted(rest)?;
        let after = after
            .trim_start()
            .strip_prefix(":")
            .ok_or(format!("no `:` after the header key `{key}`"))?;
        let (value, after) = parse_value(after.trim_start())?;
        match (key.as_str(), value) {
            ("descr", Value::Str(s)) => descr = Some(s),
            ("shape", Value::Tuple(t)) => shape = Some(t),
            ("fortran_order", Value::Bool(b)) => order = Some(b),
            (k, v) => return Err(format!("unexpected header entry `{k}`: {v:?}")),
        }
        let after = after.trim_start();
        rest = after.strip_prefix(",").unwrap_or(after).trim_start();
    }
    order.ok_or("the header has no fortran_order")?;
    let (number, endian) = dtype(&descr.ok_or("the header has no descr")?)?;
    Ok(Header {
        number,
        endian,
        shape: shape.ok_or("the header has no shape")?,
    })
}

/// A quoted string at the start of `text` (single or double quotes, no escapes),
/// and the text after it.
fn quoted(text: &str) -> Result<(String, &str), String> {
    let quote = text
        .chars()
        .next()
        .filter(|&q| q == '\'' || q == '\u{22}')
        .ok_or(format!("expected a quoted string at `{text}`"))?;
    let inner = &text[1..];
    let end = inner
        .find(quote)
        .ok_or(format!("unterminated string at `{text}`"))?;
    Ok((inner[..end].to_string(), &inner[end + 1..]))
}

/// A value at the start of `text` and the text after it: a string, `True`/`False`
/// or a tuple of integers (Python 2's `3L` accepted).
fn parse_value(text: &str) -> Result<(Value, &str), String> {
    if let Some(rest) = text.strip_prefix("True") {
        return Ok((Value::Bool(true), rest));
    }
    if let Some(rest) = text.strip_prefix("False") {
        return Ok((Value::Bool(false), rest));
    }
    if let Some(rest) = text.strip_prefix("(") {
        let end = rest.find(')').ok_or("unterminated shape tuple")?;
        let dims = rest[..end]
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty())
            .map(|d| {
                d.trim_end_matches('L')
                    .parse()
                    .map_err(|_| format!("shape entry `{d}` is not a size"))
            })
            .collect::<Result<_, _>>()?;
        return Ok((Value::Tuple(dims), &rest[end + 1..]));
    }
    if text.starts_with('[') {
        return Err(format!("structured dtypes are not read; expected {DTYPES}"));
    }
    let (s, rest) = quoted(text)?;
    Ok((Value::Str(s), rest))
}

/// The element type and byte order of a `descr` such as `<f8`, `>i2` or `|u1`.
fn dtype(descr: &str) -> Result<(Number, Endian), String> {
    let unsupported = || format!("dtype `{descr}` is not read; expected {DTYPES}");
    let mut chars = descr.chars();
    let order = chars.next().ok_or_else(unsupported)?;
    let kind = chars.next().ok_or_else(unsupported)?;
    let size: usize = chars.as_str().parse().map_err(|_| unsupported())?;
    let number = match (kind, size) {
        ('f', 4) => Number::F32,
        ('f', 8) => Number::F64,
        ('i', 1) => Number::I8,
        ('i', 2) => Number::I16,
        ('i', 4) => Number::I32,
        ('i', 8) => Number::I64,
        ('u', 1) => Number::U8,
        ('u', 2) => Number::U16,
        ('u', 4) => Number::U32,
        ('u', 8) => Number::U64,
        _ => return Err(unsupported()),
    };
    let endian = match order {
        '<' => Endian::Little,
        '>' => Endian::Big,
        '|' | '=' if size == 1 => Endian::Little,
        _ => return Err(unsupported()),
    };
    Ok((number, endian))
}
