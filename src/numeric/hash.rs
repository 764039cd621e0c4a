//! A small, stable hash for fingerprints.

/// FNV-1a, 64 bit, over the bytes of `parts` in order: stable across versions and
/// machines, so a fingerprint written today is recognised tomorrow.
pub fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for part in parts {
        for &b in *part {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}
