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

#[cfg(test)]
mod tests {
    use super::super::fixtures::{bytes, deflate, npy, zip};
    use super::*;

    /// Values that every float type holds exactly.
    const VALUES: [f64; 5] = [0.0, -1.5, 2.25, 1024.0, -0.125];

    fn f8(values: &[f64]) -> Vec<u8> {
        bytes(values, f64::to_le_bytes)
    }

    fn values(data: &[u8]) -> Vec<f64> {
        read(data, "a").unwrap().values
    }

    #[test]
    fn versions_1_2_and_3_read_the_same_values() {
        for major in [1, 2, 3] {
            let file = npy(major, "<f8", "(5,)", false, &f8(&VALUES));
            assert_eq!(values(&file), VALUES, "version {major}");
        }
        let tiny = [1e-300, -7.5e300, f64::MIN_POSITIVE];
        assert_eq!(values(&npy(1, "<f8", "(3,)", false, &f8(&tiny))), tiny);
    }

    #[test]
    fn little_endian_dtypes_convert_exactly() {
        let ints: [i16; 4] = [-32768, -1, 0, 32767];
        let expect: Vec<f64> = ints.iter().map(|&v| f64::from(v)).collect();
        let f4 = bytes(&[0.5f32, -3.0, 1e-3], f32::to_le_bytes);
        let cases: [(&str, Vec<u8>, Vec<f64>); 7] = [
            ("<f4", f4, vec![0.5, -3.0, f64::from(1e-3f32)]),
            ("<i2", bytes(&ints, i16::to_le_bytes), expect),
            (
                "<i4",
                bytes(&[-70000i32, 5], i32::to_le_bytes),
                vec![-70000.0, 5.0],
            ),
            (
                "<i8",
                bytes(&[-(1i64 << 40), 3], i64::to_le_bytes),
                vec![-(2f64.powi(40)), 3.0],
            ),
            ("|u1", vec![0, 128, 255], vec![0.0, 128.0, 255.0]),
            ("|i1", vec![0x80, 0xFF, 0x7F], vec![-128.0, -1.0, 127.0]),
            (
                "<u2",
                bytes(&[65535u16, 1], u16::to_le_bytes),
                vec![65535.0, 1.0],
            ),
        ];
        for (descr, data, expect) in cases {
            let n = expect.len();
            let file = npy(1, descr, &format!("({n},)"), false, &data);
            assert_eq!(values(&file), expect, "{descr}");
        }
    }

    #[test]
    fn big_endian_dtypes_convert_exactly() {
        let cases: [(&str, Vec<u8>, Vec<f64>); 4] = [
            (">f8", bytes(&VALUES, f64::to_be_bytes), VALUES.to_vec()),
            (
                ">f4",
                bytes(&[0.5f32, -3.0], f32::to_be_bytes),
                vec![0.5, -3.0],
            ),
            (
                ">i2",
                bytes(&[-2i16, 300], i16::to_be_bytes),
                vec![-2.0, 300.0],
            ),
            (
                ">i4",
                bytes(&[-70000i32, 9], i32::to_be_bytes),
                vec![-70000.0, 9.0],
            ),
        ];
        for (descr, data, expect) in cases {
            let n = expect.len();
            let file = npy(2, descr, &format!("({n},)"), false, &data);
            assert_eq!(values(&file), expect, "{descr}");
        }
    }

    #[test]
    fn a_column_or_a_row_reads_in_either_order() {
        for (shape, fortran) in [("(5, 1)", false), ("(5, 1)", true), ("(1, 5)", true)] {
            let file = npy(1, "<f8", shape, fortran, &f8(&VALUES));
            assert_eq!(values(&file), VALUES, "{shape}");
        }
        // Python 2 wrote `5L`.
        assert_eq!(values(&npy(1, "<f8", "(5L,)", false, &f8(&VALUES))), VALUES);
    }

    #[test]
    fn other_shapes_are_refused_naming_the_shape() {
        let six = f8(&[1.0; 6]);
        for (shape, data) in [
            ("(2, 3)", &six[..]),
            ("(1, 2, 3)", &six[..]),
            ("()", &six[..8]),
        ] {
            let err = read(&npy(1, "<f8", shape, false, data), "a").unwrap_err();
            assert_eq!(err, Fault::Shape("a".into(), shape.into()));
        }
    }

    #[test]
    fn an_empty_array_reads_as_no_values() {
        assert_eq!(
            values(&npy(1, "<f8", "(0,)", false, &[])),
            Vec::<f64>::new()
        );
    }

    #[test]
    fn unread_dtypes_are_named_with_what_is_read() {
        for descr in ["<c16", "<f2", "<U8", ">b1"] {
            let Err(Fault::Corrupt(m)) = read(&npy(1, descr, "(1,)", false, &[0; 16]), "a") else {
                panic!("{descr} was read");
            };
            assert!(m.contains(descr) && m.contains("f4, f8"), "{m}");
        }
        // The longer descr takes 9 of the header's padding spaces.
        let mut structured = npy(1, "<f8", "(1,)", false, &[0; 8]);
        let at = structured.windows(5).position(|w| w == b"'<f8'").unwrap();
        structured.splice(at..at + 5, b"[('x', '<f8')]".iter().copied());
        let pad = structured.iter().position(|&b| b == b'\n').unwrap() - 9;
        structured.drain(pad..pad + 9);
        let Err(Fault::Corrupt(m)) = read(&structured, "a") else {
            panic!("a structured dtype was read");
        };
        assert!(m.contains("structured"), "{m}");
    }

    #[test]
    fn truncated_or_corrupt_files_are_refused() {
        let good = npy(1, "<f8", "(5,)", false, &f8(&VALUES));
        let short = &good[..good.len() - 1];
        let Err(Fault::Corrupt(m)) = read(short, "a") else {
            panic!("a truncated array was read");
        };
        assert!(m.contains("(5,)") && m.contains("39 bytes"), "{m}");
        let mut long = good.clone();
        long.push(0);
        assert!(matches!(read(&long, "a"), Err(Fault::Corrupt(_))));
        // A header length past the end of the file.
        let mut lying = good.clone();
        lying[8..10].copy_from_slice(&u16::MAX.to_le_bytes());
        let Err(Fault::Corrupt(m)) = read(&lying, "a") else {
            panic!("a header past the end was read");
        };
        assert!(m.starts_with("truncated"), "{m}");
        assert!(matches!(read(b"PK\x03\x04", "a"), Err(Fault::Corrupt(_))));
        let mut v9 = good;
        v9[6] = 9;
        assert!(matches!(read(&v9, "a"), Err(Fault::Unsupported(_))));
        for cut in 0..90 {
            assert!(read(&npy(1, "<f8", "(5,)", false, &f8(&VALUES))[..cut], "a").is_err());
        }
    }

    #[test]
    fn npz_members_stored_or_deflated_read_by_name() {
        let a = npy(1, "<f8", "(5,)", false, &f8(&VALUES));
        let b = npy(
            1,
            "<i2",
            "(2,)",
            false,
            &bytes(&[7i16, -7], i16::to_le_bytes),
        );
        let archive = zip(&[("a.npy", &a, false), ("b.npy", &b, true)]);
        assert_eq!(read_npz(&archive, Some("a")).unwrap().values, VALUES);
        assert_eq!(read_npz(&archive, Some("a.npy")).unwrap().values, VALUES);
        let b_read = read_npz(&archive, Some("b")).unwrap();
        assert_eq!(
            (b_read.name.as_str(), b_read.values),
            ("b", vec![7.0, -7.0])
        );
        let single = zip(&[("only.npy", &b, true)]);
        assert_eq!(read_npz(&single, None).unwrap().values, vec![7.0, -7.0]);
    }

    #[test]
    fn npz_selection_errors_list_the_members() {
        let a = npy(1, "<f8", "(5,)", false, &f8(&VALUES));
        let archive = zip(&[("a.npy", &a, false), ("b.npy", &a, true)]);
        let Err(Fault::Select(m)) = read_npz(&archive, Some("c")) else {
            panic!("a missing member was read");
        };
        assert_eq!(m, "no member `c`; it holds a, b");
        let Err(Fault::Select(m)) = read_npz(&archive, None) else {
            panic!("one of two members was read without a name");
        };
        assert_eq!(m, "2 members; choose one of a, b");
    }

    #[test]
    fn damaged_npz_archives_are_refused() {
        let a = npy(1, "<f8", "(5,)", false, &f8(&VALUES));
        let archive = zip(&[("a.npy", &a, true)]);
        let deflated = deflate(&a, false).len();
        // Flip a byte inside the deflated data: inflate or the CRC-32 catches it.
        let mut flipped = archive.clone();
        flipped[30 + 5 + deflated / 2] ^= 0x55;
        let Err(Fault::Corrupt(m)) = read_npz(&flipped, Some("a")) else {
            panic!("a damaged member was read");
        };
        assert!(m.contains("member `a.npy`"), "{m}");
        for cut in 0..archive.len() {
            assert!(
                read_npz(&archive[..cut], Some("a")).is_err(),
                "cut at {cut}"
            );
        }
    }
}
