//! Encoding one row of a `[case, *]` or `[reference, time]` array into the bytes HDF5
//! stores for its chunk, so that any thread can compress and the writer only copies
//! the result into the file (HDF5's direct chunk write, see
//! [`StudyWriter::write_encoded`](super::StudyWriter::write_encoded)).
//!
//! With a deflate level of 0 a chunk is the row's elements as they are (native byte
//! order, float64 or float32). Otherwise it is what HDF5's shuffle filter followed by
//! its deflate filter store: the elements' bytes regrouped into byte planes (all first
//! bytes, then all second bytes, …), as one zlib stream (RFC 1950 header, deflate
//! blocks, Adler-32 of the shuffled bytes). Every zlib reader (h5py, netCDF-C, xarray)
//! inflates it like a chunk HDF5 deflated. Either way the chunk ends with what HDF5's
//! Fletcher-32 filter, the last of the pipeline ([`filters`]), appends: the checksum
//! of the bytes before it, little-endian, which every HDF5 reader checks.
//!
//! The deflate blocks are chosen plane by plane: a byte plane whose sampled byte
//! entropy is above [`STORE_ABOVE_BITS`] (the noisy low-order mantissa bytes of
//! floating-point data, on which deflate gains nothing) goes into *stored* blocks,
//! which cost a copy; runs of the other planes (sign, exponent, leading mantissa,
//! constant or integer-valued data) are deflated at the storage's level with
//! [`zlib_rs`], each run ending on a byte boundary (sync flush). On float64 series of
//! the paper's study this is several times faster than deflating every plane and
//! stores a few per cent more bytes (measured figures in the run report).

use zlib_rs::{Deflate, DeflateConfig, DeflateFlush, Method, Strategy};

use super::layout::Storage;
use super::shuffle::shuffle;

/// Byte planes whose estimated entropy (bits per byte, of at most [`SAMPLE`] bytes)
/// exceeds this are stored without compression. On the 384 float64 series of
/// `studies/paper.yaml`, the planes sampled between 6.5 and 7.5 bits are 2.5 % of the
/// bytes and deflate gains 15 % on them: storing them makes the series 0.3 % larger
/// (the paper's whole file, spectra included, 1.5 %) and encoding a third faster
/// (1.7–1.8 ms per case of 12 series at level 1, against 2.6–3.4 ms deflating every plane).
/// Planes above 7.5 bits gain about 1 %.
const STORE_ABOVE_BITS: f64 = 6.5;

/// Bytes of a plane sampled, evenly spaced, to estimate its entropy.
const SAMPLE: usize = 1024;

/// Largest payload of one stored deflate block (bytes).
const STORED_MAX: usize = u16::MAX as usize;

/// zlib's window: 2^15 bytes, as the header's CINFO says.
const WINDOW_BITS: i32 = 15;

/// Encodes rows of float64 values into stored chunk bytes for one [`Storage`]. Holds
/// the deflate state and scratch buffers, so one encoder per thread is reused.
pub struct ChunkEncoder {
    storage: Storage,
    /// Raw deflate state (no zlib header: the encoder writes the stream's frame).
    deflate: Option<Deflate>,
    /// The row's bytes in byte-plane order.
    shuffled: Vec<u8>,
}

impl std::fmt::Debug for ChunkEncoder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChunkEncoder")
            .field("storage", &self.storage)
            .finish_non_exhaustive()
    }
}

impl ChunkEncoder {
    /// An encoder for `storage` (its deflate level must be 0–9, as
    /// [`Layout::validate`](super::Layout::validate) checks; higher levels act as 9).
    pub fn new(storage: Storage) -> Self {
        let deflate = (storage.deflate_level > 0).then(|| {
            Deflate::new_with_config(DeflateConfig {
                level: i32::from(storage.deflate_level.min(9)),
                method: Method::Deflated,
                window_bits: -WINDOW_BITS,
                mem_level: 8,
                strategy: Strategy::Default,
            })
        });
        Self {
            storage,
            deflate,
            shuffled: Vec::new(),
        }
    }

    /// The storage this encoder encodes for.
    pub fn storage(&self) -> Storage {
        self.storage
    }

    /// Appends to `out` the stored bytes of one chunk holding `values` (float64, or
    /// rounded to nearest float32 when the storage says so).
    pub fn encode(&mut self, values: &[f64], out: &mut Vec<u8>) {
        let start = out.len();
        if self.storage.float32 {
            self.encode_elements(values, |v| (v as f32).to_ne_bytes(), out);
        } else {
            self.encode_elements(values, f64::to_ne_bytes, out);
        }
        let sum = fletcher32(&out[start..]);
        out.extend_from_slice(&sum.to_le_bytes());
    }

    fn encode_elements<const E: usize>(
        &mut self,
        values: &[f64],
        bytes: impl Fn(f64) -> [u8; E],
        out: &mut Vec<u8>,
    ) {
        let Some(deflate) = self.deflate.as_mut() else {
            out.reserve(values.len() * E);
            for &v in values {
                out.extend_from_slice(&bytes(v));
            }
            return;
        };
        let n = values.len();
        self.shuffled.resize(n * E, 0);
        shuffle(values, E == 4, &mut self.shuffled);
        // Whether to deflate each byte plane, decided once per plane.
        let deflated: Vec<bool> = if n == 0 {
            Vec::new()
        } else {
            self.shuffled.chunks_exact(n).map(compressible).collect()
        };
        out.extend_from_slice(&zlib_header(self.storage.deflate_level));
        let mut first = 0;
        while first < deflated.len() {
            let last = (first + 1..deflated.len())
                .find(|&j| deflated[j] != deflated[first])
                .unwrap_or(deflated.len());
            let run = &self.shuffled[first * n..last * n];
            if deflated[first] {
                deflate_run(deflate, run, out);
            } else {
                stored_blocks(run, out);
            }
            first = last;
        }
        // An empty final stored block ends the deflate stream on a byte boundary.
        out.extend_from_slice(&[1, 0, 0, 0xff, 0xff]);
        out.extend_from_slice(&zlib_rs::adler32::adler32(1, &self.shuffled).to_be_bytes());
    }
}

/// The filter pipeline of the datasets whose chunks a [`ChunkEncoder`] for `storage`
/// makes: shuffle and deflate (with a deflate level above 0), then Fletcher-32.
pub(super) fn filters(storage: Storage) -> Vec<hdf5::filters::Filter> {
    use hdf5::filters::Filter;
    let level = storage.deflate_level;
    let compress = (level > 0).then(|| [Filter::shuffle(), Filter::deflate(level)]);
    compress
        .into_iter()
        .flatten()
        .chain([Filter::fletcher32()])
        .collect()
}

/// HDF5's Fletcher-32 checksum of `data` (`H5_checksum_fletcher32`): sums of its
/// big-endian 16-bit words (a last odd byte as the high byte of a word), folded to
/// 16 bits every 360 words; the Fletcher-32 filter appends it little-endian.
///
/// Per block of `L` words `w_i` the running sums become `sum1 + Σ w_i` and
/// `sum2 + L·sum1 + Σ (L − i) w_i` (wrapping, as the word-by-word definition wraps);
/// the block sums come from eight interleaved lanes ([`block_sums`]), so the loop
/// runs on vector registers.
pub(super) fn fletcher32(data: &[u8]) -> u32 {
    let (mut sum1, mut sum2) = (0u32, 0u32);
    let fold = |s: u32| (s & 0xffff) + (s >> 16);
    let even = data.len() & !1;
    for block in data[..even].chunks(2 * FLETCHER_BLOCK) {
        let lanes = block.len() / (2 * LANE_WORDS) * (2 * LANE_WORDS);
        let (a, b) = block_sums(&block[..lanes]);
        let words = (lanes / 2) as u32;
        sum2 = sum2.wrapping_add(words.wrapping_mul(sum1)).wrapping_add(b);
        sum1 = sum1.wrapping_add(a);
        for w in block[lanes..].chunks_exact(2) {
            sum1 = sum1.wrapping_add((u32::from(w[0]) << 8) | u32::from(w[1]));
            sum2 = sum2.wrapping_add(sum1);
        }
        sum1 = fold(sum1);
        sum2 = fold(sum2);
    }
    if let Some(&b) = data.get(even) {
        sum1 = sum1.wrapping_add(u32::from(b) << 8);
        sum2 = sum2.wrapping_add(sum1);
        sum1 = fold(sum1);
        sum2 = fold(sum2);
    }
    sum1 = fold(sum1);
    sum2 = fold(sum2);
    (sum2 << 16) | sum1
}

/// Words per block of [`fletcher32`] between foldings (HDF5's 360).
const FLETCHER_BLOCK: usize = 360;

/// Lanes of [`block_sums`]: words side by side.
const LANE_WORDS: usize = 8;

/// `(Σ w_i, Σ (L − i) w_i)` over the `L` big-endian 16-bit words of `bytes` (a
/// multiple of [`LANE_WORDS`] words, at most [`FLETCHER_BLOCK`]): lane `j` keeps
/// `a_j`, the sum of its words so far, and `b_j`, the sum of its `a_j` after each
/// group of [`LANE_WORDS`] words; then `Σ (L − i) w_i = 8 Σ b_j − Σ j a_j`.
fn block_sums(bytes: &[u8]) -> (u32, u32) {
    let (mut a, mut b) = ([0u32; LANE_WORDS], [0u32; LANE_WORDS]);
    for group in bytes.chunks_exact(2 * LANE_WORDS) {
        for (j, w) in group.chunks_exact(2).enumerate() {
            a[j] = a[j].wrapping_add((u32::from(w[0]) << 8) | u32::from(w[1]));
            b[j] = b[j].wrapping_add(a[j]);
        }
    }
    let sum_a = a.iter().fold(0u32, |s, &x| s.wrapping_add(x));
    let sum_b = b.iter().fold(0u32, |s, &x| s.wrapping_add(x));
    let weighted = (0..LANE_WORDS as u32)
        .zip(a)
        .fold(0u32, |s, (j, x)| s.wrapping_add(j.wrapping_mul(x)));
    (
        sum_a,
        (LANE_WORDS as u32)
            .wrapping_mul(sum_b)
            .wrapping_sub(weighted),
    )
}

/// Whether deflate is worth running on a byte plane: its byte entropy, estimated on
/// at most [`SAMPLE`] evenly spaced bytes, is at most [`STORE_ABOVE_BITS`].
fn compressible(plane: &[u8]) -> bool {
    let step = plane.len().div_ceil(SAMPLE).max(1);
    let mut counts = [0u32; 256];
    let mut m = 0u32;
    for &b in plane.iter().step_by(step) {
        counts[usize::from(b)] += 1;
        m += 1;
    }
    if m == 0 {
        return true;
    }
    let m = f64::from(m);
    let entropy: f64 = counts
        .iter()
        .filter(|&&c| c > 0)
        .map(|&c| {
            let p = f64::from(c) / m;
            -p * p.log2()
        })
        .sum();
    entropy <= STORE_ABOVE_BITS
}

/// The two-byte zlib header (deflate, 32 KiB window) with the level hint zlib writes.
fn zlib_header(level: u8) -> [u8; 2] {
    const CMF: u8 = 0x78;
    let flevel: u8 = match level {
        0 | 1 => 0,
        2..=5 => 1,
        6 => 2,
        _ => 3,
    };
    let flg = flevel << 6;
    let rem = (u16::from(CMF) * 256 + u16::from(flg)) % 31;
    [CMF, flg + ((31 - rem) % 31) as u8]
}

/// Appends `data` as non-final stored deflate blocks (byte-aligned, ≤ 64 KiB each).
fn stored_blocks(data: &[u8], out: &mut Vec<u8>) {
    out.reserve(data.len() + 5 * data.len().div_ceil(STORED_MAX));
    for block in data.chunks(STORED_MAX) {
        let len = block.len() as u16;
        out.push(0); // BFINAL = 0, BTYPE = 00 (stored), padded to the byte boundary
        out.extend_from_slice(&len.to_le_bytes());
        out.extend_from_slice(&(!len).to_le_bytes());
        out.extend_from_slice(block);
    }
}

/// Appends `data` deflated as non-final blocks ending on a byte boundary (a fresh
/// deflate state, so no match reaches back across blocks this stream does not
/// share), or as stored blocks if deflating did not make it smaller.
fn deflate_run(deflate: &mut Deflate, data: &[u8], out: &mut Vec<u8>) {
    deflate.reset();
    let start = out.len();
    // Room for incompressible input plus the sync flush's trailer; grown if short.
    out.resize(start + data.len() + data.len() / 64 + 64, 0);
    let mut written = 0;
    loop {
        let consumed = deflate.total_in() as usize;
        let status = deflate.compress(
            &data[consumed..],
            &mut out[start + written..],
            DeflateFlush::SyncFlush,
        );
        written = deflate.total_out() as usize;
        let done = deflate.total_in() as usize == data.len() && start + written < out.len();
        if status.is_err() || done {
            break;
        }
        out.resize(out.len() + data.len() / 2 + 64, 0);
    }
    out.truncate(start + written);
    if deflate.total_in() as usize != data.len() || written >= data.len() {
        out.truncate(start);
        stored_blocks(data, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use zlib_rs::InflateConfig;

    /// Fletcher-32 word by word, as `H5_checksum_fletcher32` computes it.
    fn fletcher32_words(data: &[u8]) -> u32 {
        let (mut sum1, mut sum2) = (0u32, 0u32);
        let fold = |s: u32| (s & 0xffff) + (s >> 16);
        let even = data.len() & !1;
        for block in data[..even].chunks(2 * 360) {
            for w in block.chunks_exact(2) {
                sum1 = sum1.wrapping_add((u32::from(w[0]) << 8) | u32::from(w[1]));
                sum2 = sum2.wrapping_add(sum1);
            }
            (sum1, sum2) = (fold(sum1), fold(sum2));
        }
        if let Some(&b) = data.get(even) {
            sum1 = sum1.wrapping_add(u32::from(b) << 8);
            sum2 = sum2.wrapping_add(sum1);
            (sum1, sum2) = (fold(sum1), fold(sum2));
        }
        (fold(sum2) << 16) | fold(sum1)
    }

    #[test]
    fn fletcher32_equals_the_word_by_word_sums() {
        let mut x = 0x9e37_79b9_u32;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as u8
        };
        let random: Vec<u8> = (0..4000).map(|_| next()).collect();
        // All ones: the largest sums, where the 32-bit sums wrap.
        let ones = vec![0xff_u8; 4000];
        for data in [&random, &ones] {
            for len in (0..40).chain([719, 720, 721, 735, 736, 737, 1440, 1441, 3999, 4000]) {
                let d = &data[..len];
                assert_eq!(fletcher32(d), fletcher32_words(d), "length {len}");
            }
        }
    }

    /// Inflates a zlib stream of `len` bytes (checking its Adler-32) and unshuffles it.
    fn decode(chunk: &[u8], storage: Storage, n: usize) -> Vec<f64> {
        let (stream, sum) = chunk.split_at(chunk.len() - 4);
        assert_eq!(sum, fletcher32(stream).to_le_bytes(), "Fletcher-32");
        let e = if storage.float32 { 4 } else { 8 };
        let bytes = if storage.deflate_level == 0 {
            stream.to_vec()
        } else {
            let mut out = vec![0u8; n * e];
            let (got, rc) = zlib_rs::decompress_slice(&mut out, stream, InflateConfig::default());
            assert_eq!(rc, zlib_rs::ReturnCode::Ok, "inflate");
            assert_eq!(got.len(), n * e);
            let mut plain = vec![0u8; n * e];
            for i in 0..n {
                for j in 0..e {
                    plain[i * e + j] = out[j * n + i];
                }
            }
            plain
        };
        assert_eq!(bytes.len(), n * e);
        bytes
            .chunks_exact(e)
            .map(|c| {
                if storage.float32 {
                    f64::from(f32::from_ne_bytes(c.try_into().unwrap()))
                } else {
                    f64::from_ne_bytes(c.try_into().unwrap())
                }
            })
            .collect()
    }

    /// Smooth signal with noisy mantissas, integers, NaN, a constant: both kinds of
    /// planes and every run pattern.
    fn rows() -> Vec<Vec<f64>> {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut noise = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 20_001;
        vec![
            (0..n)
                .map(|k| 100.0 * (k as f64 * 1e-3).sin() + 1e-3 * noise())
                .collect(),
            (0..n).map(|k| (k % 7) as f64).collect(),
            vec![f64::NAN; n],
            vec![0.0; 13],
            (0..70_001).map(|_| noise()).collect(),
            Vec::new(),
            vec![1.5; 3],
        ]
    }

    #[test]
    fn chunks_decode_to_the_values_for_every_storage() {
        for float32 in [false, true] {
            for level in [0u8, 1, 4, 9] {
                let storage = Storage {
                    float32,
                    deflate_level: level,
                };
                let mut enc = ChunkEncoder::new(storage);
                for row in rows() {
                    let mut chunk = vec![0xAB]; // appended to what is there
                    enc.encode(&row, &mut chunk);
                    let got = decode(&chunk[1..], storage, row.len());
                    let want: Vec<u64> = row
                        .iter()
                        .map(|&v| {
                            if float32 {
                                f64::from(v as f32).to_bits()
                            } else {
                                v.to_bits()
                            }
                        })
                        .collect();
                    let got: Vec<u64> = got.iter().map(|v| v.to_bits()).collect();
                    assert_eq!(got, want, "float32 {float32} level {level} n {}", row.len());
                }
            }
        }
    }

    #[test]
    fn noisy_planes_are_stored_and_smooth_ones_deflated() {
        let rows = rows();
        let storage = Storage {
            float32: false,
            deflate_level: 1,
        };
        let mut enc = ChunkEncoder::new(storage);
        let mut smooth = Vec::new();
        enc.encode(&rows[0], &mut smooth);
        let raw = rows[0].len() * 8;
        // The noisy low planes stored (about their size), the top ones deflated well.
        assert!(smooth.len() < raw * 7 / 8, "{} of {raw}", smooth.len());
        assert!(smooth.len() > raw / 2, "{} of {raw}", smooth.len());
        let mut noise = Vec::new();
        enc.encode(&rows[4], &mut noise);
        let raw = rows[4].len() * 8;
        assert!(
            noise.len() <= raw + raw / 100,
            "never much above the raw size"
        );
        let mut nan = Vec::new();
        enc.encode(&rows[2], &mut nan);
        let raw = rows[2].len() * 8;
        assert!(
            nan.len() < raw / 50,
            "a constant row deflates to little: {}",
            nan.len()
        );
    }

    #[test]
    fn zlib_headers_carry_a_valid_check() {
        for level in 0..=9 {
            let [cmf, flg] = zlib_header(level);
            assert_eq!((u16::from(cmf) * 256 + u16::from(flg)) % 31, 0);
        }
        assert_eq!(zlib_header(1), [0x78, 0x01]);
        assert_eq!(zlib_header(6), [0x78, 0x9c]);
        assert_eq!(zlib_header(9), [0x78, 0xda]);
    }
}
