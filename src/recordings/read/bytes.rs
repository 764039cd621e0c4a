//! What the byte-level readers share: a bounds-checked cursor over a file's bytes,
//! numeric elements decoded to `f64`, and inflating deflate and zlib streams with a
//! cap on the output.

use zlib_rs::{Inflate, InflateFlush, Status};

use super::Fault;

/// Byte order of multi-byte numbers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Endian {
    /// Least significant byte first.
    Little,
    /// Most significant byte first.
    Big,
}

/// A numeric element type as files store it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Number {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Number {
    /// Bytes per element.
    pub(super) fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::I64 | Self::U64 | Self::F64 => 8,
        }
    }

    /// The value of one element, `b` holding exactly [`Number::size`] bytes. 64-bit
    /// integers beyond 2^53 round to the nearest `f64`.
    fn value(self, b: &[u8], endian: Endian) -> f64 {
        match self {
            Self::I8 => f64::from(i8::from_le_bytes(ordered(b, endian))),
            Self::U8 => f64::from(b[0]),
            Self::I16 => f64::from(i16::from_le_bytes(ordered(b, endian))),
            Self::U16 => f64::from(u16::from_le_bytes(ordered(b, endian))),
            Self::I32 => f64::from(i32::from_le_bytes(ordered(b, endian))),
            Self::U32 => f64::from(u32::from_le_bytes(ordered(b, endian))),
            Self::I64 => i64::from_le_bytes(ordered(b, endian)) as f64,
            Self::U64 => u64::from_le_bytes(ordered(b, endian)) as f64,
            Self::F32 => f64::from(f32::from_le_bytes(ordered(b, endian))),
            Self::F64 => f64::from_le_bytes(ordered(b, endian)),
        }
    }
}

/// The first `N` bytes of `b` in little-endian order.
fn ordered<const N: usize>(b: &[u8], endian: Endian) -> [u8; N] {
    let mut a = [0; N];
    a.copy_from_slice(&b[..N]);
    if endian == Endian::Big {
        a.reverse();
    }
    a
}

/// The elements of `bytes` as `f64`; a trailing partial element is ignored (the
/// callers check the length first).
pub(super) fn decode(bytes: &[u8], number: Number, endian: Endian) -> Vec<f64> {
    bytes
        .chunks_exact(number.size())
        .map(|b| number.value(b, endian))
        .collect()
}

/// A read position in a byte slice; every read checks the bytes are there.
#[derive(Debug, Clone)]
pub(super) struct Cursor<'a> {
    data: &'a [u8],
    pos: usize,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `data`.
    pub(super) fn new(data: &'a [u8]) -> Self {
        Self { data, pos: 0 }
    }

    /// A cursor at byte `pos` of `data`, or a fault naming `what` past its end.
    pub(super) fn at(data: &'a [u8], pos: usize, what: &str) -> Result<Self, Fault> {
        if pos > data.len() {
            return Err(truncated(what, pos, data.len()));
        }
        Ok(Self { data, pos })
    }

    /// Bytes from the start of the data to the read position.
    pub(super) fn pos(&self) -> usize {
        self.pos
    }

    /// Bytes left after the read position.
    pub(super) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    /// The next `n` bytes, or a truncation fault naming `what`.
    pub(super) fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], Fault> {
        if n > self.remaining() {
            return Err(truncated(what, self.pos.saturating_add(n), self.data.len()));
        }
        let bytes = &self.data[self.pos..self.pos + n];
        self.pos += n;
        Ok(bytes)
    }

    /// Skips `n` bytes, or as many as remain.
    pub(super) fn skip_at_most(&mut self, n: usize) {
        self.pos += n.min(self.remaining());
    }

    /// The next 2 bytes as an unsigned integer.
    pub(super) fn u16(&mut self, endian: Endian, what: &str) -> Result<u16, Fault> {
        Ok(u16::from_le_bytes(ordered(self.take(2, what)?, endian)))
    }

    /// The next 4 bytes as an unsigned integer.
    pub(super) fn u32(&mut self, endian: Endian, what: &str) -> Result<u32, Fault> {
        Ok(u32::from_le_bytes(ordered(self.take(4, what)?, endian)))
    }

    /// The next 8 bytes as an unsigned integer.
    pub(super) fn u64(&mut self, endian: Endian, what: &str) -> Result<u64, Fault> {
        Ok(u64::from_le_bytes(ordered(self.take(8, what)?, endian)))
    }
}

/// The fault for `what` needing bytes up to `end` where the data hold `len`.
fn truncated(what: &str, end: usize, len: usize) -> Fault {
    Fault::Corrupt(format!(
        "truncated: {what} needs bytes up to {end}, the data hold {len}"
    ))
}

/// Deflate's largest compression ratio (a 258-byte match in about 2 bits).
const MAX_RATIO: usize = 1032;

/// The most bytes `compressed` bytes of a deflate stream can inflate to.
pub(super) fn inflated_bound(compressed: usize) -> usize {
    compressed.saturating_mul(MAX_RATIO).saturating_add(64)
}

/// Inflates `input`, a zlib stream (RFC 1950, Adler-32 checked) when `zlib`, else a
/// raw deflate stream (RFC 1951), to at most `limit` bytes. The output grows as
/// the stream yields bytes, never by a size the file declares. Bytes after the
/// stream's end are ignored.
pub(super) fn inflate(input: &[u8], zlib: bool, limit: usize) -> Result<Vec<u8>, String> {
    let mut stream = Inflate::new(zlib, 15);
    let mut out = Vec::new();
    let mut buf = vec![0; (1 << 16).min(limit.max(1))];
    loop {
        let (used, made) = (stream.total_in(), stream.total_out());
        let rest = usize::try_from(used)
            .ok()
            .and_then(|u| input.get(u..))
            .unwrap_or_default();
        let status = stream
            .decompress(rest, &mut buf, InflateFlush::NoFlush)
            .map_err(|e| format!("corrupt compressed data: {}", e.as_str()))?;
        let produced = usize::try_from(stream.total_out() - made).unwrap_or(usize::MAX);
        out.extend_from_slice(&buf[..produced.min(buf.len())]);
        if out.len() > limit {
            return Err(format!("compressed data inflate past {limit} bytes"));
        }
        if status == Status::StreamEnd {
            return Ok(out);
        }
        if produced == 0 && stream.total_in() == used {
            return Err("truncated: the compressed data end before their stream does".into());
        }
    }
}
