//! The first lags of the squared envelope's spectrum for every kurtogram band of a
//! window at once (docs/model.md §7.6.1), for `band: auto`.
//!
//! A band of bins `k0..end` has the lags `R_d = Σ_{k=k0}^{end−1−d} x_{k+d} x*_k`
//! (`x` the window's scaled analytic bins). The kurtogram's bands are unions of the
//! elementary blocks between their edges, so the products `x_{k+d} x*_k` are summed
//! once per block and lag, and a band's `R_d` is the sum of its blocks that lie wholly
//! below `end − d`, plus the products of the few bins left above the last of them. That
//! remainder depends only on `end` and `d` (it starts at the last edge at most
//! `end − d`), so it is summed once per band end and lag for the bands that end there. Every
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
    /// Whether edge `j` ends a band.
    ends: Vec<bool>,
    /// `sums[d * blocks + j] = Σ_{k in block j, k+d < len} x_{k+d} x*_k`.
    sums: Vec<Complex<f64>>,
    /// `tails[d * edges + j] = Σ_{k=e}^{end−1−d} x_{k+d} x*_k` for the edge
    /// `end = edges[j]` that ends a band and `e` the last edge `≤ end − d` (zero
    /// elsewhere).
    tails: Vec<Complex<f64>>,
    /// Lags tabulated, `d = 0..lags`.
    lags: usize,
}

impl LagTable {
    /// A table over the blocks between the edges of `bands` (each band's first bin and
    /// end, `k0..end`, in any order, duplicates allowed).
    pub fn new(bands: impl IntoIterator<Item = (usize, usize)>) -> Self {
        let bands: Vec<(usize, usize)> = bands.into_iter().collect();
        let mut edges: Vec<usize> = bands.iter().flat_map(|&(k0, end)| [k0, end]).collect();
        edges.sort_unstable();
        edges.dedup();
        let ends = (edges.iter())
            .map(|e| bands.iter().any(|&(_, end)| end == *e))
            .collect();
        Self {
            edges,
            ends,
            sums: Vec::new(),
            tails: Vec::new(),
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
        self.tails.clear();
        for d in 0..lags {
            for (&end, &is_end) in self.edges.iter().zip(&self.ends) {
                let stop = end.saturating_sub(d);
                let tail = match self.edges.first() {
                    Some(&first) if is_end && stop > first => {
                        let rest = self.edges[self.edges.partition_point(|&e| e <= stop) - 1];
                        lag_product(&x[rest + d..stop + d], &x[rest..stop])
                    }
                    _ => Complex::default(),
                };
                self.tails.push(tail);
            }
        }
    }

    /// Fills `out` (`out.len() ≤` the lags filled, `≤ end − k0`) with the lags `R_d` of
    /// the band of bins `k0..end` (one of the table's bands) of the bins the table was
    /// filled from.
    pub fn band_lags(&self, k0: usize, end: usize, out: &mut [Complex<f64>]) {
        let edges = self.edges.len();
        let blocks = edges - 1;
        let first = self.edges.partition_point(|&e| e < k0);
        let last_edge = first + self.edges[first..].partition_point(|&e| e < end);
        debug_assert_eq!(self.edges[first], k0);
        debug_assert!(self.ends[last_edge] && self.edges[last_edge] == end);
        for (d, r) in out.iter_mut().enumerate() {
            let stop = end - d;
            let last = first + self.edges[first..].partition_point(|&e| e <= stop) - 1;
            let whole: Complex<f64> = self.sums[d * blocks + first..d * blocks + last]
                .iter()
                .sum();
            *r = whole + self.tails[d * edges + last_edge];
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
        let mut table = LagTable::new(bands);
        table.fill(&x, 30);
        for (k0, end) in bands {
            let count = 30.min(end - k0);
            let mut out = vec![Complex::default(); count];
            table.band_lags(k0, end, &mut out);
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
