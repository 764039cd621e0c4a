//! Writers of the small files the readers' tests read back: `.npy` arrays, ZIP
//! archives, WAV files, deflate and zlib streams, each built from its format's
//! layout so a test controls every byte.

use std::path::{Path, PathBuf};

use zlib_rs::{DeflateConfig, ReturnCode};

use super::bytes::Endian;

/// Writes `bytes` to `dir/name` and returns the path.
pub(super) fn file(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("the test directory is writable");
    path
}

/// The concatenated bytes of `values`, each encoded by `f`.
pub(super) fn bytes<T: Copy, const N: usize>(values: &[T], f: fn(T) -> [u8; N]) -> Vec<u8> {
    values.iter().flat_map(|&v| f(v)).collect()
}

/// An `.npy` file of format version `major`.0 with dtype `descr`, Python shape
/// literal `shape` (`(3,)`), `fortran_order` and the element bytes `data`.
pub(super) fn npy(major: u8, descr: &str, shape: &str, fortran: bool, data: &[u8]) -> Vec<u8> {
    let order = if fortran { "True" } else { "False" };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}");
    let prelude = if major == 1 { 10 } else { 12 };
    // NumPy pads the header with spaces and a newline to a multiple of 64 bytes.
    while (prelude + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY".to_vec();
    out.extend([major, 0]);
    if major == 1 {
        out.extend(u16::try_from(header.len()).unwrap().to_le_bytes());
    } else {
        out.extend(u32::try_from(header.len()).unwrap().to_le_bytes());
    }
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

/// `data` deflated at level 6: a zlib stream when `zlib`, else raw deflate.
pub(super) fn deflate(data: &[u8], zlib: bool) -> Vec<u8> {
    let config = DeflateConfig {
        window_bits: if zlib { 15 } else { -15 },
        ..DeflateConfig::new(6)
    };
    let mut out = vec![0; zlib_rs::compress_bound(data.len()) + 64];
    let (written, code) = zlib_rs::compress_slice(&mut out, data, config);
    assert_eq!(code, ReturnCode::Ok);
    let n = written.len();
    out.truncate(n);
    out
}

/// A ZIP archive of `(name, data, deflated)` members, with a central directory.
pub(super) fn zip(members: &[(&str, &[u8], bool)]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut central = Vec::new();
    for &(name, data, deflated) in members {
        let stored = if deflated {
            deflate(data, false)
        } else {
            data.to_vec()
        };
        let offset = u32::try_from(out.len()).unwrap();
        let method: u16 = if deflated { 8 } else { 0 };
        let crc = zlib_rs::crc32::crc32(0, data);
        let sizes = [stored.len(), data.len()].map(|n| u32::try_from(n).unwrap());
        let name_len = u16::try_from(name.len()).unwrap();
        // Local header: signature, version, flags, method, time, date, CRC, sizes,
        // name and extra lengths.
        out.extend(b"PK\x03\x04");
        out.extend([20, 0, 0, 0]);
        out.extend(method.to_le_bytes());
        out.extend([0; 4]);
        out.extend(crc.to_le_bytes());
        out.extend(sizes[0].to_le_bytes());
        out.extend(sizes[1].to_le_bytes());
        out.extend(name_len.to_le_bytes());
        out.extend([0, 0]);
        out.extend(name.as_bytes());
        out.extend(&stored);
        // Central entry: the same, plus comment length, disk, attributes, offset.
        central.extend(b"PK\x01\x02");
        central.extend([20, 0, 20, 0, 0, 0]);
        central.extend(method.to_le_bytes());
        central.extend([0; 4]);
        central.extend(crc.to_le_bytes());
        central.extend(sizes[0].to_le_bytes());
        central.extend(sizes[1].to_le_bytes());
        central.extend(name_len.to_le_bytes());
        central.extend([0; 12]);
        central.extend(offset.to_le_bytes());
        central.extend(name.as_bytes());
    }
    let cd_offset = u32::try_from(out.len()).unwrap();
    let count = u16::try_from(members.len()).unwrap();
    let cd_size = u32::try_from(central.len()).unwrap();
    out.extend(&central);
    out.extend(b"PK\x05\x06");
    out.extend([0; 4]);
    out.extend(count.to_le_bytes());
    out.extend(count.to_le_bytes());
    out.extend(cd_size.to_le_bytes());
    out.extend(cd_offset.to_le_bytes());
    out.extend([0, 0]);
    out
}

/// WAVE encoding, as `wFormatTag` or an extensible subformat gives it.
pub(super) const PCM: u16 = 1;
/// IEEE float encoding.
pub(super) const FLOAT: u16 = 3;

/// A WAV file of interleaved frames `data`: `encoding` (PCM or FLOAT), in a
/// `WAVE_FORMAT_EXTENSIBLE` header when `extensible`, with an odd-sized `LIST`
/// chunk (and its pad byte) before `data`.
pub(super) fn wav(
    encoding: u16,
    extensible: bool,
    channels: u16,
    rate: u32,
    bits: u16,
    data: &[u8],
) -> Vec<u8> {
    let block = channels * bits / 8;
    let mut fmt = Vec::new();
    fmt.extend(if extensible { 0xFFFE } else { encoding }.to_le_bytes());
    fmt.extend(channels.to_le_bytes());
    fmt.extend(rate.to_le_bytes());
    fmt.extend((rate * u32::from(block)).to_le_bytes());
    fmt.extend(block.to_le_bytes());
    fmt.extend(bits.to_le_bytes());
    if extensible {
        fmt.extend(22u16.to_le_bytes());
        fmt.extend(bits.to_le_bytes());
        fmt.extend(0u32.to_le_bytes());
        fmt.extend(encoding.to_le_bytes());
        fmt.extend([0, 0, 0, 0, 0x10, 0, 0x80, 0, 0, 0xAA, 0, 0x38, 0x9B, 0x71]);
    }
    let mut body = b"WAVE".to_vec();
    for (id, chunk) in [(b"fmt ", &fmt[..]), (b"LIST", b"odd"), (b"data", data)] {
        body.extend(id);
        body.extend(u32::try_from(chunk.len()).unwrap().to_le_bytes());
        body.extend(chunk);
        if chunk.len() % 2 == 1 {
            body.push(0);
        }
    }
    let mut out = b"RIFF".to_vec();
    out.extend(u32::try_from(body.len()).unwrap().to_le_bytes());
    out.extend(body);
    out
}

/// A writer of Level 5 MAT-file elements in one byte order.
#[derive(Debug, Clone, Copy)]
pub(super) struct Mat(pub(super) Endian);

/// MAT-file data types and classes the tests write.
pub(super) const MI_INT8: u32 = 1;
pub(super) const MI_UINT8: u32 = 2;
pub(super) const MI_INT16: u32 = 3;
pub(super) const MI_INT32: u32 = 5;
pub(super) const MI_UINT32: u32 = 6;
pub(super) const MI_DOUBLE: u32 = 9;
pub(super) const MI_MATRIX: u32 = 14;
pub(super) const MX_CELL: u32 = 1;
pub(super) const MX_STRUCT: u32 = 2;
pub(super) const MX_CHAR: u32 = 4;
pub(super) const MX_DOUBLE: u32 = 6;
pub(super) const MX_INT32: u32 = 12;
/// The complex flag of the array flags.
pub(super) const COMPLEX: u32 = 0x0800;

impl Mat {
    /// `v` in the writer's byte order.
    pub(super) fn u32(self, v: u32) -> [u8; 4] {
        match self.0 {
            Endian::Little => v.to_le_bytes(),
            Endian::Big => v.to_be_bytes(),
        }
    }

    /// The 128-byte header: text, no subsystem data, version 0x0100, endian indicator.
    pub(super) fn header(self) -> Vec<u8> {
        let mut h = b"MATLAB 5.0 MAT-file, written by the recordings tests".to_vec();
        h.resize(116, b' ');
        h.extend([0; 8]);
        h.extend(match self.0 {
            Endian::Little => [0x00, 0x01, b'I', b'M'],
            Endian::Big => [0x01, 0x00, b'M', b'I'],
        });
        h
    }

    /// A data element: the small format for at most 4 bytes (as MATLAB writes names),
    /// else a full tag and the data padded to 8 bytes.
    pub(super) fn element(self, kind: u32, data: &[u8]) -> Vec<u8> {
        let size = u32::try_from(data.len()).unwrap();
        if (1..=4).contains(&size) && kind != MI_MATRIX {
            let mut out = self.u32((size << 16) | kind).to_vec();
            out.extend(data);
            out.resize(8, 0);
            return out;
        }
        let mut out = self.u32(kind).to_vec();
        out.extend(self.u32(size));
        out.extend(data);
        out.resize(out.len().next_multiple_of(8), 0);
        out
    }

    /// An `miMATRIX` element: array flags (`class | flags`), dimensions, name, then
    /// `content` (the sub-elements of its class).
    pub(super) fn matrix(self, class: u32, dims: &[i32], name: &str, content: &[u8]) -> Vec<u8> {
        let mut body = self.element(MI_UINT32, &[self.u32(class), self.u32(0)].concat());
        let dims: Vec<u8> = dims.iter().flat_map(|&d| self.u32(d as u32)).collect();
        body.extend(self.element(MI_INT32, &dims));
        body.extend(self.element(MI_INT8, name.as_bytes()));
        body.extend(content);
        self.element(MI_MATRIX, &body)
    }

    /// A column vector of class double stored as `f64`.
    pub(super) fn doubles(self, name: &str, values: &[f64]) -> Vec<u8> {
        let data: Vec<u8> = values
            .iter()
            .flat_map(|v| match self.0 {
                Endian::Little => v.to_le_bytes(),
                Endian::Big => v.to_be_bytes(),
            })
            .collect();
        let n = i32::try_from(values.len()).unwrap();
        self.matrix(MX_DOUBLE, &[n, 1], name, &self.element(MI_DOUBLE, &data))
    }

    /// A 1x1 struct whose fields are the unnamed `miMATRIX` elements `fields`.
    pub(super) fn structure(self, name: &str, fields: &[(&str, Vec<u8>)]) -> Vec<u8> {
        let mut names = Vec::new();
        for (field, _) in fields {
            let mut n = field.as_bytes().to_vec();
            n.resize(32, 0);
            names.extend(n);
        }
        let mut content = self.element(MI_INT32, &self.u32(32));
        content.extend(self.element(MI_INT8, &names));
        for (_, value) in fields {
            content.extend(value);
        }
        self.matrix(MX_STRUCT, &[1, 1], name, &content)
    }

    /// `element` in an `miCOMPRESSED` element (a zlib stream, not padded).
    pub(super) fn compressed(self, element: &[u8]) -> Vec<u8> {
        let z = deflate(element, true);
        let mut out = self.u32(15).to_vec();
        out.extend(self.u32(u32::try_from(z.len()).unwrap()));
        out.extend(z);
        out
    }
}
