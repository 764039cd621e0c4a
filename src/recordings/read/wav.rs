//! RIFF WAVE files: integer PCM of 8, 16, 24 or 32 bits, IEEE float of 32 or 64
//! bits, plain or `WAVE_FORMAT_EXTENSIBLE`, any number of channels.
//!
//! The file is `RIFF`, a size, `WAVE`, then chunks (an ID, a little-endian size,
//! the body and a pad byte after an odd size). The `fmt ` chunk gives the encoding,
//! channel count, sample rate and bits per sample; the `data` chunk holds the
//! frames, one sample per channel each. Other chunks are skipped. Integer samples
//! are scaled to [-1, 1): divided by 2^(bits − 1), 8-bit samples (unsigned)
//! offset by 128 first.

use super::bytes::{decode, Cursor, Endian, Number};
use super::{Fault, Loaded};

/// `wFormatTag` of integer PCM.
const PCM: u16 = 1;
/// `wFormatTag` of IEEE float.
const IEEE_FLOAT: u16 = 3;
/// `wFormatTag` whose subformat GUID gives the encoding.
const EXTENSIBLE: u16 = 0xFFFE;
/// The 14 bytes after the 2-byte format code in the subformat GUIDs of PCM and
/// IEEE float (`xxxx0000-0000-0010-8000-00aa00389b71`).
const GUID_TAIL: [u8; 14] = [0, 0, 0, 0, 0x10, 0, 0x80, 0, 0, 0xAA, 0, 0x38, 0x9B, 0x71];

const LE: Endian = Endian::Little;

/// What the `fmt ` chunk says.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Fmt {
    /// `PCM` or `IEEE_FLOAT`.
    encoding: u16,
    channels: usize,
    /// Hz.
    rate: u32,
    /// Bytes per frame.
    block_align: usize,
    /// Bits per sample as stored (the container size).
    bits: u16,
}

/// Reads channel `channel` of the WAV file in `data` (the only one when `None`),
/// scaled as the module docs say, with the header's sample rate.
pub(super) fn read(data: &[u8], channel: Option<usize>) -> Result<Loaded, Fault> {
    let (fmt, frames) = chunks(data)?;
    let channel = match channel {
        Some(i) if i < fmt.channels => i,
        None if fmt.channels == 1 => 0,
        asked => {
            let asked = asked.map_or("no channel index".into(), |i| format!("channel index {i}"));
            return Err(Fault::Select(format!(
                "{asked} given, and the file has {} channel(s); choose one of 0..={}",
                fmt.channels,
                fmt.channels - 1
            )));
        }
    };
    if !frames.len().is_multiple_of(fmt.block_align) {
        return Err(Fault::Corrupt(format!(
            "truncated: the data chunk's {} bytes are not whole frames of {} bytes",
            frames.len(),
            fmt.block_align
        )));
    }
    let width = usize::from(fmt.bits / 8);
    let mut values = Vec::with_capacity(frames.len() / fmt.block_align);
    for frame in frames.chunks_exact(fmt.block_align) {
        let sample = &frame[channel * width..(channel + 1) * width];
        values.push(sample_value(sample, fmt));
    }
    Ok(Loaded {
        name: format!("channel {channel}"),
        values,
        sample_rate: Some(f64::from(fmt.rate)),
    })
}

/// One sample's value: floats as stored, integers scaled to [-1, 1).
fn sample_value(b: &[u8], fmt: Fmt) -> f64 {
    let scale = |v: f64| v / f64::from(1u32 << (fmt.bits - 1));
    match (fmt.encoding, fmt.bits) {
        (IEEE_FLOAT, 32) => decode(b, Number::F32, LE)[0],
        (IEEE_FLOAT, _) => decode(b, Number::F64, LE)[0],
        (_, 8) => scale(f64::from(b[0]) - 128.0),
        (_, 16) => scale(decode(b, Number::I16, LE)[0]),
        // Sign-extend the 3 bytes: place them high in an i32, shift back.
        (_, 24) => scale(f64::from(i32::from_le_bytes([0, b[0], b[1], b[2]]) >> 8)),
        _ => scale(decode(b, Number::I32, LE)[0]),
    }
}

/// The `fmt ` chunk and the `data` chunk's bytes.
fn chunks(data: &[u8]) -> Result<(Fmt, &[u8]), Fault> {
    let mut c = Cursor::new(data);
    let riff = c.take(4, "the RIFF header")?;
    if riff == b"RF64" {
        return Err(Fault::Unsupported(
            "RF64 (64-bit RIFF) WAV files are not read".into(),
        ));
    }
    c.take(4, "the RIFF header")?;
    if riff != b"RIFF" || c.take(4, "the RIFF header")? != b"WAVE" {
        return Err(Fault::Corrupt(
            "not a WAV file (no RIFF/WAVE header)".into(),
        ));
    }
    let (mut fmt, mut samples) = (None, None);
    while c.remaining() >= 8 && (fmt.is_none() || samples.is_none()) {
        let id = c.take(4, "a chunk ID")?;
        let size = c.u32(LE, "a chunk size")? as usize;
        let shown = String::from_utf8_lossy(id);
        let body = c.take(size, &format!("the `{shown}` chunk"))?;
        c.skip_at_most(size % 2);
        match id {
            b"fmt " => fmt = Some(parse_fmt(body)?),
            b"data" => samples = Some(body),
            _ => {}
        }
    }
    match (fmt, samples) {
        (Some(f), Some(s)) => Ok((f, s)),
        (None, _) => Err(Fault::Corrupt("no `fmt ` chunk".into())),
        (_, None) => Err(Fault::Corrupt("no `data` chunk".into())),
    }
}

/// Parses and checks a `fmt ` chunk.
fn parse_fmt(body: &[u8]) -> Result<Fmt, Fault> {
    let what = "the `fmt ` chunk";
    let mut c = Cursor::new(body);
    let mut encoding = c.u16(LE, what)?;
    let channels = usize::from(c.u16(LE, what)?);
    let rate = c.u32(LE, what)?;
    let _byte_rate = c.u32(LE, what)?;
    let block_align = usize::from(c.u16(LE, what)?);
    let bits = c.u16(LE, what)?;
    if encoding == EXTENSIBLE {
        c.take(8, what)?; // cbSize, valid bits per sample, channel mask
        let code = c.u16(LE, what)?;
        if c.take(14, what)? != GUID_TAIL {
            return Err(Fault::Unsupported(
                "extensible WAV with a subformat that is neither PCM nor IEEE float".into(),
            ));
        }
        encoding = code;
    }
    let fmt = Fmt {
        encoding,
        channels,
        rate,
        block_align,
        bits,
    };
    match (encoding, bits) {
        (PCM, 8 | 16 | 24 | 32) | (IEEE_FLOAT, 32 | 64) => {}
        (PCM | IEEE_FLOAT, _) => {
            let kind = if encoding == PCM { "integer PCM" } else { "IEEE float" };
            return Err(Fault::Unsupported(format!(
                "{bits}-bit {kind}; read are integer PCM of 8, 16, 24 or 32 bits and IEEE float of 32 or 64 bits"
            )));
        }
        _ => {
            return Err(Fault::Unsupported(format!(
                "WAV format tag {encoding:#06x} (compressed); read are integer PCM (1) and IEEE float (3)"
            )))
        }
    }
    if channels == 0 || rate == 0 || block_align != channels * usize::from(bits / 8) {
        return Err(Fault::Corrupt(format!(
            "{what} is inconsistent: {channels} channel(s), {rate} Hz, {bits} bits, {block_align} bytes per frame"
        )));
    }
    Ok(fmt)
}
