//! MATLAB Level 5 MAT-files (what MATLAB saves with `-v6` and `-v7`, and
//! `scipy.io.savemat`), from MathWorks' "MAT-File Format" specification.
//!
//! A 128-byte header (text, subsystem offset, version, and the endian indicator
//! `IM` in a little-endian file, `MI` in a big-endian one) precedes data elements.
//! An element's 8-byte tag holds its type and byte count, its data follow padded to
//! 8 bytes; a *small* element packs a count of at most 4 into the tag's upper half
//! and its data into the tag's second word. A top-level element is an `miMATRIX`
//! (one variable) or an `miCOMPRESSED` zlib stream holding one (not padded).
//!
//! An `miMATRIX` holds sub-elements: array flags (class, complex and logical bits),
//! dimensions, name, then by class: the real (and imaginary) data of a numeric
//! array, stored in any numeric type (MATLAB stores a double of small integers as
//! `miINT16` or `miUINT8`, converted back here), or for a struct the field-name
//! length, the names, and one `miMATRIX` per field and element. Variables are
//! selected by name, fields of scalar structs by `struct.field`.

use std::borrow::Cow;

use super::bytes::{decode, inflate, inflated_bound, Cursor, Endian, Number};
use super::{listed, Fault, Loaded};

/// Bytes of the file header.
const HEADER: usize = 128;
/// The HDF5 signature, found at byte 512 of a v7.3 MAT-file (after its user block).
const HDF5_SIGNATURE: &[u8] = b"\x89HDF\r\n\x1a\n";
/// Structs nested deeper than this are refused (each level recurses).
const MAX_DEPTH: usize = 32;

/// Data types of the element tags (the specification's `mi*` codes).
const MI_INT8: u32 = 1;
const MI_UINT8: u32 = 2;
const MI_INT16: u32 = 3;
const MI_UINT16: u32 = 4;
const MI_INT32: u32 = 5;
const MI_UINT32: u32 = 6;
const MI_SINGLE: u32 = 7;
const MI_DOUBLE: u32 = 9;
const MI_INT64: u32 = 12;
const MI_UINT64: u32 = 13;
const MI_MATRIX: u32 = 14;
const MI_COMPRESSED: u32 = 15;
const MI_UTF8: u32 = 16;

/// Array classes (the specification's `mx*_CLASS` codes) that are not numeric.
const MX_CELL: u8 = 1;
const MX_STRUCT: u8 = 2;
const MX_OBJECT: u8 = 3;
const MX_CHAR: u8 = 4;
const MX_SPARSE: u8 = 5;
/// The numeric classes: double, single, int8, uint8, … uint64.
const MX_NUMERIC: std::ops::RangeInclusive<u8> = 6..=15;
/// The complex bit of the array flags' first word.
const COMPLEX: u32 = 0x0800;

/// One data element: its type and its data (without tag or padding).
#[derive(Debug, Clone, Copy)]
struct Element<'a> {
    kind: u32,
    data: &'a [u8],
}

/// A MATLAB array, as much as selecting and reading need.
#[derive(Debug)]
enum Matrix<'a> {
    /// A real or complex numeric array; `real` is its real part's element.
    Numeric {
        name: String,
        dims: Vec<usize>,
        complex: bool,
        real: Element<'a>,
    },
    /// A 1x1 struct and its fields, in file order.
    Struct {
        name: String,
        fields: Vec<Matrix<'a>>,
    },
    /// Anything else, with what it is: `a cell array`, `a 1x3 struct array`.
    Other { name: String, what: String },
}

impl Matrix<'_> {
    fn name(&self) -> &str {
        match self {
            Self::Numeric { name, .. } | Self::Struct { name, .. } | Self::Other { name, .. } => {
                name
            }
        }
    }

    fn rename(&mut self, new: String) {
        match self {
            Self::Numeric { name, .. } | Self::Struct { name, .. } | Self::Other { name, .. } => {
                *name = new
            }
        }
    }
}

/// Whether `data` is a MAT-file v7.3, which is HDF5 behind a 512-byte user block.
pub(super) fn is_hdf5(data: &[u8]) -> bool {
    data.get(512..520) == Some(HDF5_SIGNATURE)
}

/// Reads variable `variable` (`name` or `struct.field…`) of the Level 5 MAT-file in
/// `data`, or its only numeric top-level variable when `None`.
pub(super) fn read(data: &[u8], variable: Option<&str>) -> Result<Loaded, Fault> {
    let endian = endian(data)?;
    let bodies = top_level(data, endian)?;
    let mut vars = Vec::new();
    for body in &bodies {
        let m = matrix(body, endian, 0)?;
        // The subsystem data MATLAB appends is an unnamed uint8 array.
        if !m.name().is_empty() {
            vars.push(m);
        }
    }
    let (path, found) = match variable {
        Some(v) => (v.to_string(), find(&vars, v)?),
        None => only_numeric(&vars)?,
    };
    let values = match found {
        Matrix::Numeric {
            dims,
            complex,
            real,
            ..
        } => numeric(&path, dims, *complex, *real, endian)?,
        Matrix::Struct { .. } => {
            let parent = path.rsplit_once('.').map(|(p, _)| p);
            return Err(Fault::Select(format!(
                "`{path}` is a struct; choose one of its fields: {}",
                listed(&paths(std::slice::from_ref(found), parent))
            )));
        }
        Matrix::Other { what, .. } => {
            return Err(Fault::Unsupported(format!(
                "`{path}` is {what}; numeric arrays are read (the file holds {})",
                listed(&paths(&vars, None))
            )))
        }
    };
    Ok(Loaded {
        name: path,
        values,
        sample_rate: None,
    })
}

/// The values of the numeric array at `path`, which must be real, not empty, and
/// one column.
fn numeric(
    path: &str,
    dims: &[usize],
    complex: bool,
    real: Element,
    endian: Endian,
) -> Result<Vec<f64>, Fault> {
    if complex {
        return Err(Fault::Unsupported(format!(
            "`{path}` is complex; only real arrays are read"
        )));
    }
    if dims.contains(&0) {
        return Err(Fault::Empty(path.to_string()));
    }
    if !matches!(dims, [_, 1] | [1, _]) {
        let dims: Vec<String> = dims.iter().map(usize::to_string).collect();
        return Err(Fault::Shape(path.to_string(), dims.join("x")));
    }
    numbers(real, dims, endian, path)
}

/// The byte order from the header's endian indicator.
fn endian(data: &[u8]) -> Result<Endian, Fault> {
    let header = Cursor::new(data).take(HEADER, "the 128-byte MAT-file header")?;
    match &header[126..128] {
        b"IM" => Ok(Endian::Little),
        b"MI" => Ok(Endian::Big),
        _ => Err(Fault::Corrupt(
            "not a Level 5 MAT-file (no IM/MI endian indicator at bytes 126-127; \
             MATLAB v4 files are not read)"
                .into(),
        )),
    }
}

/// The data of every top-level `miMATRIX`, compressed ones inflated.
fn top_level(data: &[u8], endian: Endian) -> Result<Vec<Cow<'_, [u8]>>, Fault> {
    let mut c = Cursor::at(data, HEADER, "the MAT-file header")?;
    let mut bodies = Vec::new();
    while c.remaining() >= 8 {
        let at = c.pos();
        let e = element(&mut c, endian)?;
        match e.kind {
            MI_MATRIX => bodies.push(Cow::Borrowed(e.data)),
            MI_COMPRESSED => {
                let inflated = inflate(e.data, true, inflated_bound(e.data.len()))
                    .map_err(|m| Fault::Corrupt(format!("compressed element at byte {at}: {m}")))?;
                let inner = element(&mut Cursor::new(&inflated), endian)?;
                if inner.kind == MI_MATRIX {
                    bodies.push(Cow::Owned(inner.data.to_vec()));
                }
            }
            _ => {}
        }
    }
    Ok(bodies)
}

/// The element at the cursor, small or not; the cursor moves past its padding
/// (an `miCOMPRESSED` element has none).
fn element<'a>(c: &mut Cursor<'a>, endian: Endian) -> Result<Element<'a>, Fault> {
    let at = c.pos();
    let first = c.u32(endian, "a data element's tag")?;
    let small = first >> 16;
    if small != 0 {
        let packed = c.take(4, "a small data element")?;
        let size = usize::try_from(small).unwrap_or(usize::MAX);
        let data = packed.get(..size).ok_or_else(|| {
            Fault::Corrupt(format!(
                "small data element at byte {at} claims {size} bytes"
            ))
        })?;
        return Ok(Element {
            kind: first & 0xFFFF,
            data,
        });
    }
    let size = c.u32(endian, "a data element's tag")? as usize;
    let data = c.take(size, "a data element")?;
    if first != MI_COMPRESSED {
        c.skip_at_most((8 - size % 8) % 8);
    }
    Ok(Element { kind: first, data })
}

/// The data of the next element at the cursor, which must be of one of `kinds`.
fn expect<'a>(
    c: &mut Cursor<'a>,
    endian: Endian,
    kinds: &[u32],
    what: &str,
) -> Result<&'a [u8], Fault> {
    let e = element(c, endian)?;
    if !kinds.contains(&e.kind) {
        return Err(Fault::Corrupt(format!(
            "an array's {what} has data type {}, expected {kinds:?}",
            e.kind
        )));
    }
    Ok(e.data)
}

/// Parses the data of an `miMATRIX` element; `depth` counts the structs around it.
fn matrix(body: &[u8], endian: Endian, depth: usize) -> Result<Matrix<'_>, Fault> {
    if body.is_empty() {
        // MATLAB writes an empty array (`[]`) in a struct or cell as no data at all.
        return Ok(Matrix::Numeric {
            name: String::new(),
            dims: vec![0, 0],
            complex: false,
            real: Element {
                kind: MI_DOUBLE,
                data: &[],
            },
        });
    }
    let mut c = Cursor::new(body);
    let flags = expect(&mut c, endian, &[MI_UINT32], "array flags")?;
    let flags = Cursor::new(flags).u32(endian, "array flags")?;
    let class = (flags & 0xFF) as u8;
    if class > *MX_NUMERIC.end() {
        // Function handles and opaque objects (strings, tables…) lay out their
        // sub-elements differently: only their name is looked for.
        let name = opaque_name(&mut c, endian);
        let what = format!("an array of class {class} (a function handle or an opaque object)");
        return Ok(Matrix::Other { name, what });
    }
    let dims = dimensions(expect(&mut c, endian, &[MI_INT32], "dimensions")?, endian)?;
    let name = expect(&mut c, endian, &[MI_INT8, MI_UINT8, MI_UTF8], "name")?;
    let name = String::from_utf8_lossy(name).into_owned();
    let what = match class {
        c if MX_NUMERIC.contains(&c) => "",
        MX_STRUCT => return structure(&mut c, endian, name, &dims, depth),
        MX_CELL => "a cell array",
        MX_SPARSE => "a sparse array",
        MX_CHAR => "a char array",
        MX_OBJECT => "an object",
        _ => "an array of an unknown class",
    };
    if !what.is_empty() {
        let what = what.to_string();
        return Ok(Matrix::Other { name, what });
    }
    Ok(Matrix::Numeric {
        name,
        dims,
        complex: flags & COMPLEX != 0,
        real: element(&mut c, endian)?,
    })
}

/// The name of an array of a class beyond the numeric ones: the first `miINT8`
/// element among the two after the flags (empty if there is none).
fn opaque_name(c: &mut Cursor, endian: Endian) -> String {
    for _ in 0..2 {
        match element(c, endian) {
            Ok(e) if e.kind == MI_INT8 => return String::from_utf8_lossy(e.data).into_owned(),
            Ok(_) => {}
            Err(_) => break,
        }
    }
    String::new()
}

/// The dimensions of an array from its `miINT32` dimensions element.
fn dimensions(data: &[u8], endian: Endian) -> Result<Vec<usize>, Fault> {
    let dims = decode(data, Number::I32, endian);
    if dims.len() < 2 || !data.len().is_multiple_of(4) || dims.iter().any(|&d| d < 0.0) {
        return Err(Fault::Corrupt(format!(
            "bad dimensions element ({} bytes)",
            data.len()
        )));
    }
    Ok(dims.into_iter().map(|d| d as usize).collect())
}

/// The rest of a struct's `miMATRIX` after its name: field names and, for a 1x1
/// struct, its fields.
fn structure<'a>(
    c: &mut Cursor<'a>,
    endian: Endian,
    name: String,
    dims: &[usize],
    depth: usize,
) -> Result<Matrix<'a>, Fault> {
    if dims.iter().product::<usize>() != 1 {
        let dims: Vec<String> = dims.iter().map(usize::to_string).collect();
        let what = format!("a {} struct array", dims.join("x"));
        return Ok(Matrix::Other { name, what });
    }
    if depth >= MAX_DEPTH {
        return Err(Fault::Corrupt(format!(
            "structs nested more than {MAX_DEPTH} deep"
        )));
    }
    let len = expect(c, endian, &[MI_INT32], "field name length")?;
    let len = Cursor::new(len).u32(endian, "field name length")? as usize;
    let names = expect(c, endian, &[MI_INT8, MI_UINT8], "field names")?;
    if (len == 0 && !names.is_empty()) || (len != 0 && !names.len().is_multiple_of(len)) {
        return Err(Fault::Corrupt(format!(
            "struct `{name}`: {} bytes of field names are not names of {len} bytes",
            names.len()
        )));
    }
    let mut fields = Vec::new();
    for raw in names.chunks(len.max(1)) {
        let end = raw.iter().position(|&b| b == 0).unwrap_or(raw.len());
        let field = String::from_utf8_lossy(&raw[..end]).into_owned();
        let body = expect(c, endian, &[MI_MATRIX], "field")?;
        let mut value = matrix(body, endian, depth + 1)?;
        value.rename(field);
        fields.push(value);
    }
    Ok(Matrix::Struct { name, fields })
}

/// The array at `path` (`name` or `struct.field…`), or a fault listing what is there.
fn find<'m, 'a>(vars: &'m [Matrix<'a>], path: &str) -> Result<&'m Matrix<'a>, Fault> {
    let mut level = vars;
    let mut found = None;
    for part in path.split('.') {
        let m = level.iter().find(|m| m.name() == part).ok_or_else(|| {
            Fault::Select(format!(
                "no variable `{path}`; it holds {}",
                listed(&paths(vars, None))
            ))
        })?;
        level = match m {
            Matrix::Struct { fields, .. } => fields,
            _ => &[],
        };
        found = Some(m);
    }
    found.ok_or_else(|| Fault::Select("an empty variable name".into()))
}

/// The only numeric top-level variable, or a fault listing every variable.
fn only_numeric<'m, 'a>(vars: &'m [Matrix<'a>]) -> Result<(String, &'m Matrix<'a>), Fault> {
    let numeric: Vec<&Matrix> = vars
        .iter()
        .filter(|m| matches!(m, Matrix::Numeric { .. }))
        .collect();
    if let [only] = numeric[..] {
        return Ok((only.name().to_string(), only));
    }
    let what = match numeric.len() {
        0 => "no numeric variable at top level".to_string(),
        n => format!("{n} numeric variables at top level"),
    };
    Err(Fault::Select(format!(
        "{what}; choose a variable among {}",
        listed(&paths(vars, None))
    )))
}

/// The paths of `vars` and of their struct fields (`a`, `s.b`, `s.t.c`), under
/// `prefix`.
fn paths(vars: &[Matrix], prefix: Option<&str>) -> Vec<String> {
    let mut out = Vec::new();
    for m in vars {
        let path = match prefix {
            Some(p) => format!("{p}.{}", m.name()),
            None => m.name().to_string(),
        };
        match m {
            Matrix::Struct { fields, .. } => out.extend(paths(fields, Some(&path))),
            _ => out.push(path),
        }
    }
    out
}

/// The values of a numeric array's real part, whatever type stores them.
fn numbers(real: Element, dims: &[usize], endian: Endian, path: &str) -> Result<Vec<f64>, Fault> {
    let number = match real.kind {
        MI_INT8 => Number::I8,
        MI_UINT8 => Number::U8,
        MI_INT16 => Number::I16,
        MI_UINT16 => Number::U16,
        MI_INT32 => Number::I32,
        MI_UINT32 => Number::U32,
        MI_SINGLE => Number::F32,
        MI_DOUBLE => Number::F64,
        MI_INT64 => Number::I64,
        MI_UINT64 => Number::U64,
        other => {
            return Err(Fault::Corrupt(format!(
                "`{path}`: its data have data type {other}, not a numeric type"
            )))
        }
    };
    let count = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
    if count.and_then(|n| n.checked_mul(number.size())) != Some(real.data.len()) {
        let dims: Vec<String> = dims.iter().map(usize::to_string).collect();
        return Err(Fault::Corrupt(format!(
            "`{path}` is {} but holds {} bytes of {}-byte elements",
            dims.join("x"),
            real.data.len(),
            number.size()
        )));
    }
    Ok(decode(real.data, number, endian))
}

#[cfg(test)]
mod tests {
    use super::super::fixtures::{self as f, Mat};
    use super::*;

    const LE: Mat = Mat(Endian::Little);
    const BE: Mat = Mat(Endian::Big);

    /// A MAT-file of `elements` after `w`'s header.
    fn file(w: Mat, elements: &[Vec<u8>]) -> Vec<u8> {
        let mut out = w.header();
        for e in elements {
            out.extend(e);
        }
        out
    }

    fn values(data: &[u8], variable: &str) -> Vec<f64> {
        read(data, Some(variable)).unwrap().values
    }

    /// `bearing` (compressed): `gs` of class double stored as `miINT16`, scalar
    /// `sr`, and `rate` stored as `miUINT8`.
    fn bearing(w: Mat) -> Vec<u8> {
        let gs: Vec<u8> = [-3i16, 0, 7, 32000]
            .iter()
            .flat_map(|&v| match w.0 {
                Endian::Little => v.to_le_bytes(),
                Endian::Big => v.to_be_bytes(),
            })
            .collect();
        let gs = w.matrix(f::MX_DOUBLE, &[4, 1], "", &w.element(f::MI_INT16, &gs));
        let rate = w.matrix(f::MX_DOUBLE, &[1, 1], "", &w.element(f::MI_UINT8, &[200]));
        let fields = [
            ("gs", gs),
            ("sr", w.doubles("", &[12_000.0])),
            ("rate", rate),
        ];
        w.compressed(&w.structure("bearing", &fields))
    }

    #[test]
    fn an_uncompressed_double_vector_reads_exactly() {
        let x = [0.5, -1.25, 1e-300, 7.0e200, 0.0];
        let data = file(LE, &[LE.doubles("x", &x)]);
        assert_eq!(values(&data, "x"), x);
        assert_eq!(read(&data, None).unwrap().values, x);
        let row = LE.matrix(
            f::MX_DOUBLE,
            &[1, 2],
            "row",
            &LE.element(f::MI_DOUBLE, &[0; 16]),
        );
        assert_eq!(values(&file(LE, &[row]), "row"), [0.0, 0.0]);
    }

    #[test]
    fn compressed_struct_fields_read_through_their_path() {
        let data = file(LE, &[bearing(LE), LE.doubles("x", &[1.0])]);
        assert_eq!(values(&data, "bearing.gs"), [-3.0, 0.0, 7.0, 32000.0]);
        assert_eq!(values(&data, "bearing.sr"), [12_000.0]);
        assert_eq!(values(&data, "bearing.rate"), [200.0]);
        let Err(Fault::Select(m)) = read(&data, Some("bearing.gx")) else {
            panic!("a missing field was read");
        };
        assert_eq!(
            m,
            "no variable `bearing.gx`; it holds bearing.gs, bearing.sr, bearing.rate, x"
        );
        let Err(Fault::Select(m)) = read(&data, Some("bearing")) else {
            panic!("a struct was read as samples");
        };
        assert!(
            m.ends_with("fields: bearing.gs, bearing.sr, bearing.rate"),
            "{m}"
        );
        // `x` is the only numeric variable at top level.
        assert_eq!(read(&data, None).unwrap().values, [1.0]);
    }

    #[test]
    fn nested_structs_and_empty_fields() {
        let inner = LE.structure("", &[("c", LE.doubles("", &[4.0, 5.0]))]);
        let empty = [f::MI_MATRIX.to_le_bytes(), [0; 4]].concat();
        let data = file(LE, &[LE.structure("a", &[("b", inner), ("e", empty)])]);
        assert_eq!(values(&data, "a.b.c"), [4.0, 5.0]);
        assert_eq!(
            read(&data, Some("a.e")).unwrap_err(),
            Fault::Empty("a.e".into())
        );
        let Err(Fault::Select(m)) = read(&data, None) else {
            panic!("a struct was read without a variable");
        };
        assert_eq!(
            m,
            "no numeric variable at top level; choose a variable among a.b.c, a.e"
        );
    }

    #[test]
    fn a_big_endian_file_reads_the_same() {
        let ints: Vec<u8> = [-70_000i32, 3]
            .iter()
            .flat_map(|&v| BE.u32(v as u32))
            .collect();
        let i32s = BE.matrix(f::MX_INT32, &[2, 1], "n", &BE.element(f::MI_INT32, &ints));
        let data = file(
            BE,
            &[BE.doubles("x", &[0.5, -2.0, 1e10]), i32s, bearing(BE)],
        );
        assert_eq!(values(&data, "x"), [0.5, -2.0, 1e10]);
        assert_eq!(values(&data, "n"), [-70_000.0, 3.0]);
        assert_eq!(values(&data, "bearing.gs"), [-3.0, 0.0, 7.0, 32000.0]);
        let Err(Fault::Select(m)) = read(&data, None) else {
            panic!("one of two numeric variables was read without a name");
        };
        assert!(m.starts_with("2 numeric variables at top level"), "{m}");
    }

    #[test]
    fn complex_sparse_cell_char_and_tables_are_refused_by_name() {
        let z = LE.matrix(
            f::MX_DOUBLE | f::COMPLEX,
            &[1, 1],
            "z",
            &[
                LE.element(f::MI_DOUBLE, &[0; 8]),
                LE.element(f::MI_DOUBLE, &[0; 8]),
            ]
            .concat(),
        );
        let cell = LE.matrix(f::MX_CELL, &[1, 1], "c", &LE.doubles("", &[1.0]));
        let text = LE.matrix(f::MX_CHAR, &[1, 2], "s", &LE.element(f::MI_UINT8, b"hi"));
        let table = LE.matrix(
            f::MX_DOUBLE,
            &[2, 3],
            "m",
            &LE.element(f::MI_DOUBLE, &[0; 48]),
        );
        // Sparse: row indices, column starts and values follow the name.
        let sparse = LE.matrix(5, &[2, 1], "sp", &LE.element(f::MI_INT32, &[0; 4]));
        let data = file(LE, &[z, cell, text, table, sparse]);
        for (name, says) in [
            ("z", "`z` is complex"),
            ("sp", "`sp` is a sparse array"),
            ("c", "`c` is a cell array"),
            ("s", "`s` is a char array"),
        ] {
            let Err(Fault::Unsupported(m)) = read(&data, Some(name)) else {
                panic!("{name} was read");
            };
            assert!(m.starts_with(says), "{m}");
        }
        assert_eq!(
            read(&data, Some("m")).unwrap_err(),
            Fault::Shape("m".into(), "2x3".into())
        );
    }

    #[test]
    fn corrupt_or_truncated_files_are_refused() {
        let data = file(LE, &[bearing(LE), LE.doubles("x", &[1.0, 2.0])]);
        for cut in 0..data.len() {
            // Cut anywhere, the file is refused or (cut after `bearing`) lacks `x`.
            assert!(read(&data[..cut], Some("x")).is_err(), "cut at {cut}");
        }
        // Dimensions that say 3 values over 2 stored.
        let lying = LE.matrix(
            f::MX_DOUBLE,
            &[3, 1],
            "y",
            &LE.element(f::MI_DOUBLE, &[0; 16]),
        );
        let Err(Fault::Corrupt(m)) = read(&file(LE, &[lying]), Some("y")) else {
            panic!("a short array was read");
        };
        assert_eq!(m, "`y` is 3x1 but holds 16 bytes of 8-byte elements");
        // A byte flipped inside the zlib stream fails its checks.
        let mut flipped = file(LE, &[bearing(LE)]);
        let middle = 128 + 8 + (flipped.len() - 136) / 2;
        flipped[middle] ^= 0x55;
        assert!(matches!(
            read(&flipped, Some("bearing.gs")),
            Err(Fault::Corrupt(_))
        ));
        let mut v4 = data;
        v4[126..128].copy_from_slice(b"\0\0");
        let Err(Fault::Corrupt(m)) = read(&v4, None) else {
            panic!("a file without an endian indicator was read");
        };
        assert!(m.contains("Level 5"), "{m}");
    }
}
