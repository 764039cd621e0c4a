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

#[cfg(test)]
mod tests {
    use super::super::fixtures::{bytes, wav, FLOAT, PCM};
    use super::*;

    fn channel(file: &[u8], i: Option<usize>) -> Vec<f64> {
        read(file, i).unwrap().values
    }

    #[test]
    fn pcm16_stereo_reads_each_channel_scaled_with_the_rate() {
        let frames: [i16; 6] = [1000, -1000, -32768, 32767, 0, 1];
        let file = wav(PCM, false, 2, 8000, 16, &bytes(&frames, i16::to_le_bytes));
        let left = read(&file, Some(0)).unwrap();
        assert_eq!(left.values, [1000.0 / 32768.0, -1.0, 0.0]);
        assert_eq!(left.sample_rate, Some(8000.0));
        assert_eq!(left.name, "channel 0");
        let right = [-1000.0 / 32768.0, 32767.0 / 32768.0, 1.0 / 32768.0];
        assert_eq!(channel(&file, Some(1)), right);
    }

    #[test]
    fn pcm8_24_and_32_scale_to_unit_range() {
        let file = wav(PCM, false, 1, 100, 8, &[0, 128, 255]);
        assert_eq!(channel(&file, None), [-1.0, 0.0, 127.0 / 128.0]);
        let v24: [i32; 4] = [-8_388_608, 8_388_607, 1, -1];
        let data: Vec<u8> = v24
            .iter()
            .flat_map(|v| v.to_le_bytes()[..3].to_vec())
            .collect();
        let file = wav(PCM, false, 1, 44_100, 24, &data);
        let scaled: Vec<f64> = v24.iter().map(|&v| f64::from(v) / 8_388_608.0).collect();
        assert_eq!(channel(&file, None), scaled);
        let file = wav(
            PCM,
            false,
            1,
            1,
            32,
            &bytes(&[i32::MIN, 1 << 30], i32::to_le_bytes),
        );
        assert_eq!(channel(&file, None), [-1.0, 0.5]);
    }

    #[test]
    fn float32_and_float64_read_as_stored() {
        let file = wav(
            FLOAT,
            false,
            1,
            48_000,
            32,
            &bytes(&[0.5f32, -0.25, 1.5], f32::to_le_bytes),
        );
        let read_back = read(&file, None).unwrap();
        assert_eq!(read_back.values, [0.5, -0.25, 1.5]);
        assert_eq!(read_back.sample_rate, Some(48_000.0));
        let file = wav(
            FLOAT,
            true,
            2,
            10,
            64,
            &bytes(&[0.1, 0.2, 0.3, 0.4], f64::to_le_bytes),
        );
        assert_eq!(channel(&file, Some(1)), [0.2, 0.4]);
    }

    #[test]
    fn extensible_pcm_reads_like_plain_pcm() {
        let frames: [i16; 6] = [1, 2, 3, -4, -5, -6];
        let data = bytes(&frames, i16::to_le_bytes);
        let plain = wav(PCM, false, 3, 12_000, 16, &data);
        let extensible = wav(PCM, true, 3, 12_000, 16, &data);
        for i in 0..3 {
            assert_eq!(channel(&plain, Some(i)), channel(&extensible, Some(i)));
        }
        assert_eq!(
            channel(&extensible, Some(2)),
            [3.0 / 32768.0, -6.0 / 32768.0]
        );
    }

    #[test]
    fn a_channel_must_be_chosen_among_those_there() {
        let file = wav(PCM, false, 2, 8000, 16, &[0; 8]);
        let Err(Fault::Select(m)) = read(&file, None) else {
            panic!("a stereo file was read without a channel");
        };
        assert_eq!(
            m,
            "no channel index given, and the file has 2 channel(s); choose one of 0..=1"
        );
        let Err(Fault::Select(m)) = read(&file, Some(2)) else {
            panic!("channel 2 of 2 was read");
        };
        assert!(m.starts_with("channel index 2 given"), "{m}");
    }

    #[test]
    fn unread_encodings_are_named() {
        let mut adpcm = wav(PCM, false, 1, 8000, 16, &[0; 4]);
        adpcm[20] = 2;
        let Err(Fault::Unsupported(m)) = read(&adpcm, None) else {
            panic!("ADPCM was read");
        };
        assert!(m.contains("0x0002"), "{m}");
        let mut twelve = wav(PCM, false, 1, 8000, 16, &[0; 4]);
        twelve[34] = 12;
        let Err(Fault::Unsupported(m)) = read(&twelve, None) else {
            panic!("12-bit PCM was read");
        };
        assert!(m.starts_with("12-bit integer PCM"), "{m}");
        let mut rf64 = wav(PCM, false, 1, 8000, 16, &[0; 4]);
        rf64[..4].copy_from_slice(b"RF64");
        assert!(matches!(read(&rf64, None), Err(Fault::Unsupported(_))));
    }

    #[test]
    fn truncated_or_inconsistent_files_are_refused() {
        let file = wav(PCM, false, 2, 8000, 16, &[0; 8]);
        for cut in 0..file.len() {
            assert!(read(&file[..cut], Some(0)).is_err(), "cut at {cut}");
        }
        let Err(Fault::Corrupt(m)) = read(&file[..file.len() - 1], Some(0)) else {
            panic!("a truncated data chunk was read");
        };
        assert!(m.contains("the `data` chunk"), "{m}");
        // A data chunk of 7 bytes: not whole 4-byte frames.
        let odd = wav(PCM, false, 2, 8000, 16, &[0; 7]);
        let Err(Fault::Corrupt(m)) = read(&odd, Some(0)) else {
            panic!("a partial frame was read");
        };
        assert!(m.contains("not whole frames"), "{m}");
        let mut align = file.clone();
        align[32] = 3;
        assert!(matches!(read(&align, Some(0)), Err(Fault::Corrupt(_))));
        assert!(matches!(
            read(b"RIFF\0\0\0\0AVI ", None),
            Err(Fault::Corrupt(_))
        ));
    }
}
