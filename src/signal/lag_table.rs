//! The first lags of the squared envelope's spectrum for every kurtogram band of a
//! window at once (docs/model.md §7.6.1), for `band: auto`.
//!
//! A band of bins `k0..end` has the lags `R_d = Σ_{k=k0}^{end−1−d} x_{k+d} x*_k`
//! (`x` the window's scaled analytic bins). The kurtogram's bands are unions of the
//! elementary blocks between their edges, so the products `x_{k+d} x*_k` are summed
//! once per block and lag, and a band's `R_d` is the sum of its blocks that lie wholly
//! below `end − d`, plus the products of the few bins left above the last of them. Every
//! product a band's lag sums is one of its own bins: nothing is added and taken away
//! again, so each lag has the rounding of a direct sum. For `c` lags over `n/2` bins the
//! table costs about `c n/2` complex multiply-adds, once per window, where a transform
//! per band costs two FFTs of twice the band's bins for each of the 220 bands.

use realfft::num_complex::Complex;

/// Block sums of the lag products of one window's bins.
#[derive(Debug, Default)]
pub struct LagTable {
    /// The block edges (bin indices, increasing): block `j` is `edges[j]..edges[j+1]`.
    edges: Vec<usize>,
    /// `sums[d * blocks + j] = Σ_{k in block j, k+d < len} x_{k+d} x*_k`.
    sums: Vec<Complex<f64>>,
    /// Lags tabulated, `d = 0..lags`.
    lags: usize,
}

impl LagTable {
    /// A table over the blocks between `edges` (every band's first bin and end, in any
    /// order, duplicates allowed).
    pub fn new(edges: impl IntoIterator<Item = usize>) -> Self {
        let mut edges: Vec<usize> = edges.into_iter().collect();
        edges.sort_unstable();
        edges.dedup();
        Self {
            edges,
            sums: Vec::new(),
            lags: 0,
        }
    }

    /// Sums the products of the bins `x` for the lags `d = 0..lags`.
    pub fn fill(&mut self, x: &[Complex<f64>], lags: usize) {
        let blocks = self.edges.len().saturating_sub(1);
        self.lags = lags;
        self.sums.clear();
        for d in 0..lags {
            for pair in self.edges.windows(2) {
                let end = pair[1].min(x.len().saturating_sub(d));
                let start = pair[0].min(end);
                self.sums
                    .push(lag_product(&x[start + d..end + d], &x[start..end]));
            }
        }
        debug_assert_eq!(self.sums.len(), lags * blocks);
    }

    /// Fills `out` (`out.len() ≤` the lags filled, `≤ end − k0`) with the lags `R_d` of
    /// the band of bins `k0..end` (both block edges) of `x`, the bins the table was
    /// filled from.
    pub fn band_lags(&self, x: &[Complex<f64>], k0: usize, end: usize, out: &mut [Complex<f64>]) {
        let blocks = self.edges.len() - 1;
        let first = self.edges.partition_point(|&e| e < k0);
        debug_assert_eq!(self.edges[first], k0);
        for (d, r) in out.iter_mut().enumerate() {
            let stop = end - d;
            let last = first + self.edges[first..].partition_point(|&e| e <= stop) - 1;
            let whole: Complex<f64> = self.sums[d * blocks + first..d * blocks + last]
                .iter()
                .sum();
            let rest = self.edges[last];
            *r = whole + lag_product(&x[rest + d..stop + d], &x[rest..stop]);
        }
    }
}

/// `Σ_b a_b b*_b` over the common length of `a` and `b`, in four interleaved partial
/// sums (independent chains of additions, so the loop is not bound by their latency).
fn lag_product(a: &[Complex<f64>], b: &[Complex<f64>]) -> Complex<f64> {
    let (mut re, mut im) = ([0.0; 4], [0.0; 4]);
    let (pa, pb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail = pa.remainder().iter().zip(pb.remainder());
    for (p, q) in pa.zip(pb) {
        for i in 0..4 {
            re[i] += p[i].re * q[i].re + p[i].im * q[i].im;
            im[i] += p[i].im * q[i].re - p[i].re * q[i].im;
        }
    }
    let head = Complex::new(re[0] + re[1] + re[2] + re[3], im[0] + im[1] + im[2] + im[3]);
    tail.fold(head, |sum, (p, q)| sum + p * q.conj())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `R_d` summed term by term.
    fn direct(x: &[Complex<f64>], k0: usize, end: usize, d: usize) -> Complex<f64> {
        (k0..end - d).map(|k| x[k + d] * x[k].conj()).sum()
    }

    #[test]
    fn band_lags_equal_the_direct_sums() {
        // Bins of very different sizes, bands that share an edge bin, overlap, nest,
        // end at the last bin, and lags up to the band's length less one.
        let x: Vec<Complex<f64>> = (0..101)
            .map(|k| {
                let k = k as f64;
                Complex::new(
                    (0.37 * k).sin() * (1.0 + k),
                    (1.3 * k).cos() * 1e3f64.powf(k / 100.0),
                )
            })
            .collect();
        let bands = [
            (0, 101),
            (0, 51),
            (50, 101),
            (20, 34),
            (33, 67),
            (66, 101),
            (40, 41),
        ];
        let mut table = LagTable::new(bands.iter().flat_map(|&(a, b)| [a, b]));
        table.fill(&x, 30);
        for (k0, end) in bands {
            let count = 30.min(end - k0);
            let mut out = vec![Complex::default(); count];
            table.band_lags(&x, k0, end, &mut out);
            for (d, r) in out.iter().enumerate() {
                let want = direct(&x, k0, end, d);
                let scale: f64 = (k0..end - d).map(|k| (x[k + d] * x[k].conj()).norm()).sum();
                assert!(
                    (r - want).norm() <= 1e-14 * scale,
                    "band {k0}..{end}, lag {d}: {r} against {want}"
                );
            }
        }
    }
}
