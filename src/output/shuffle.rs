//! HDF5's shuffle filter on one row of float64 values, stored as float64 or rounded
//! to float32: byte `j` of element `i` goes to `dst[j * n + i]`, so the bytes of equal
//! significance (sign and exponent, leading mantissa, …) lie together in byte planes.
//!
//! On x86-64 sixteen elements at a time go through a byte-transpose network of SSE2
//! unpacks (part of the x86-64 baseline, so every build can run it and nothing is
//! chosen at run time); elsewhere, and for the last `n % 16` elements, one element at
//! a time. [`shuffle_portable`] is the plain definition the SSE2 path is tested
//! against (`tests::simd_equals_the_portable_shuffle`).

/// Shuffles `values` (as float64, or rounded to nearest float32 when `float32`) into
/// `dst`, which holds exactly `n × 8` (or `n × 4`) bytes for the `n` values.
pub(super) fn shuffle(values: &[f64], float32: bool, dst: &mut [u8]) {
    #[cfg(target_arch = "x86_64")]
    let done = if float32 {
        sse2::shuffle_f32(values, dst)
    } else {
        sse2::shuffle_f64(values, dst)
    };
    #[cfg(not(target_arch = "x86_64"))]
    let done = 0;
    if float32 {
        tail(values, done, |v| (v as f32).to_ne_bytes(), dst);
    } else {
        tail(values, done, f64::to_ne_bytes, dst);
    }
}

/// Shuffles elements `from..` of `values` one at a time (`n = values.len()`).
fn tail<const E: usize>(
    values: &[f64],
    from: usize,
    bytes: impl Fn(f64) -> [u8; E],
    dst: &mut [u8],
) {
    let n = values.len();
    assert_eq!(dst.len(), n * E, "the destination holds the row's bytes");
    for (i, &v) in values.iter().enumerate().skip(from) {
        for (j, b) in bytes(v).into_iter().enumerate() {
            dst[j * n + i] = b;
        }
    }
}

/// The shuffle by its definition, one element at a time: the reference the SSE2 path
/// is tested against, and what other architectures run (through [`shuffle`]).
#[cfg(test)]
fn shuffle_portable(values: &[f64], float32: bool, dst: &mut [u8]) {
    if float32 {
        tail(values, 0, |v| (v as f32).to_ne_bytes(), dst);
    } else {
        tail(values, 0, f64::to_ne_bytes, dst);
    }
}

#[cfg(target_arch = "x86_64")]
mod sse2 {
    //! Sixteen elements are a 16 × E byte matrix, held in `E` registers of 16 bytes
    //! (two float64 or four float32 elements each). A byte's address in that matrix,
    //! `(element, byte)`, has 4 + log2 E bits, the leading ones naming its register
    //! and the last four its lane. [`interleave`] (unpack the low and high halves of
    //! registers `p` and `p + E/2`, byte by byte, into registers `2p` and `2p + 1`)
    //! rotates every address left by one bit, so four rounds move the element's four
    //! bits from the front to the back: register `j` then holds byte `j` of the
    //! sixteen elements, in element order.

    use std::arch::x86_64::{
        __m128i, _mm_castps_si128, _mm_cvtpd_ps, _mm_loadu_pd, _mm_loadu_si128, _mm_movelh_ps,
        _mm_storeu_si128, _mm_unpackhi_epi8, _mm_unpacklo_epi8,
    };

    /// Elements per block.
    const BLOCK: usize = 16;

    /// One round of the transpose network on `R` registers.
    #[inline(always)]
    fn interleave<const R: usize>(a: [__m128i; R]) -> [__m128i; R] {
        let mut out = a;
        for p in 0..R / 2 {
            // SAFETY: SSE2 is part of the x86-64 baseline: every x86-64 CPU has it.
            unsafe {
                out[2 * p] = _mm_unpacklo_epi8(a[p], a[p + R / 2]);
                out[2 * p + 1] = _mm_unpackhi_epi8(a[p], a[p + R / 2]);
            }
        }
        out
    }

    /// Transposes block `k` (held in `a`) and stores plane `j` at `dst[j n + 16 k..]`.
    #[inline(always)]
    fn store<const R: usize>(a: [__m128i; R], k: usize, n: usize, dst: &mut [u8]) {
        let planes = interleave(interleave(interleave(interleave(a))));
        for (j, plane) in planes.into_iter().enumerate() {
            let at = &mut dst[j * n + BLOCK * k..][..BLOCK];
            // SAFETY: `at` is 16 writable bytes; the store is unaligned (SSE2, baseline).
            unsafe { _mm_storeu_si128(at.as_mut_ptr().cast(), plane) };
        }
    }

    /// Shuffles the whole blocks of `values` into `dst` (`R n` bytes: `R` bytes per
    /// element), `load` giving the registers of one block of [`BLOCK`] elements;
    /// returns how many elements it did.
    #[inline(always)]
    fn blocks<const R: usize>(
        values: &[f64],
        dst: &mut [u8],
        load: impl Fn(&[f64; BLOCK]) -> [__m128i; R],
    ) -> usize {
        let n = values.len();
        assert_eq!(dst.len(), R * n, "the destination holds the row's bytes");
        let blocks = values.chunks_exact(BLOCK);
        let whole = n - blocks.remainder().len();
        for (k, block) in blocks.enumerate() {
            store(load(block.try_into().expect("a whole block")), k, n, dst);
        }
        whole
    }

    /// Shuffles the whole blocks of float64 `values` into `dst` (`8 n` bytes);
    /// returns how many elements it did.
    pub(super) fn shuffle_f64(values: &[f64], dst: &mut [u8]) -> usize {
        blocks::<8>(values, dst, |block| {
            let p: *const __m128i = block.as_ptr().cast();
            // SAFETY: `block` is 16 float64 = 128 readable bytes, eight unaligned loads
            // (SSE2, baseline).
            std::array::from_fn(|r| unsafe { _mm_loadu_si128(p.add(r)) })
        })
    }

    /// Shuffles the whole blocks of `values`, rounded to nearest float32 (as `as f32`
    /// does), into `dst` (`4 n` bytes); returns how many elements it did.
    pub(super) fn shuffle_f32(values: &[f64], dst: &mut [u8]) -> usize {
        blocks::<4>(values, dst, |block| {
            let p = block.as_ptr();
            std::array::from_fn(|r| {
                // SAFETY: elements 4r..4r + 4 of the 16 in `block` (unaligned loads);
                // SSE and SSE2 are part of the x86-64 baseline.
                unsafe {
                    let (lo, hi) = (_mm_loadu_pd(p.add(4 * r)), _mm_loadu_pd(p.add(4 * r + 2)));
                    _mm_castps_si128(_mm_movelh_ps(_mm_cvtpd_ps(lo), _mm_cvtpd_ps(hi)))
                }
            })
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Values with every kind of byte: signs, subnormals, infinities, NaNs with
    /// payloads, values that round differently to float32.
    fn values(n: usize) -> Vec<f64> {
        let specials = [
            0.0,
            -0.0,
            f64::MIN_POSITIVE / 3.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::from_bits(0x7ff8_0000_0000_1234),
            f64::from_bits(0xfff0_0000_dead_beef),
            1.0 + f64::EPSILON,
            f64::from(f32::MAX) * 1.5,
            1e-40,
        ];
        (0..n)
            .map(|i| {
                specials
                    .get(i % 23)
                    .copied()
                    .unwrap_or((i as f64 * 0.37 + 0.1).exp() - 3.0)
            })
            .collect()
    }

    #[test]
    fn simd_equals_the_portable_shuffle() {
        for n in (0..70).chain([255, 256, 257, 20_001]) {
            let v = values(n);
            for (float32, e) in [(false, 8), (true, 4)] {
                let (mut got, mut want) = (vec![0u8; e * n], vec![0u8; e * n]);
                shuffle(&v, float32, &mut got);
                shuffle_portable(&v, float32, &mut want);
                assert_eq!(got, want, "n {n} float32 {float32}");
            }
        }
    }

    #[test]
    fn byte_j_of_element_i_goes_to_j_n_plus_i() {
        for n in [0, 1, 7, 16, 17, 67] {
            let v = values(n);
            let mut dst = vec![0u8; 8 * n];
            shuffle(&v, false, &mut dst);
            let mut dst32 = vec![0u8; 4 * n];
            shuffle(&v, true, &mut dst32);
            for (i, x) in v.iter().enumerate() {
                for (j, b) in x.to_ne_bytes().into_iter().enumerate() {
                    assert_eq!(dst[j * n + i], b, "n {n} element {i} byte {j}");
                }
                for (j, b) in (*x as f32).to_ne_bytes().into_iter().enumerate() {
                    assert_eq!(dst32[j * n + i], b, "f32 n {n} element {i} byte {j}");
                }
            }
        }
    }
}
