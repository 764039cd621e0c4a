//! The weighted sums of an explicit step's stage slopes, `y + h Σ_j w_j k_j`, over
//! the nonzero weights of a tableau's rows only.
//!
//! DOP853's rows are sparse: a step with its continuous extension has 184 weights in
//! the rows of its stages, its extra stages and its dense-output terms, 54 of them
//! zero. [`SparseRows`] keeps each row's nonzero weights with their stage numbers,
//! once per run, and [`weighted_sum`] adds those alone. A zero weight contributes
//! `±0` to a sum, so leaving it out changes no finite result; a non-finite slope is
//! still seen by the first later stage, since every stage's slope has a nonzero
//! weight in the next stage's row (the tests check it of every tableau), and the
//! last stage's by the error estimate, whose rows are summed in full.

use super::tableau::ExplicitTableau;

/// Components kept side by side by [`weighted_sum`].
const LANES: usize = 4;

/// The nonzero weights of the rows an explicit step sums, as `(stage, weight)`
/// pairs: the rows of `a` of the step's stages, the weights `b`, then the rows of
/// `a` of the continuous extension's extra stages and its rows `d`.
#[derive(Debug, Clone)]
pub(super) struct SparseRows {
    /// Every row's pairs, row after row.
    terms: Vec<(usize, f64)>,
    /// Where each row starts in `terms`, and after the last, where it ends.
    starts: Vec<usize>,
    /// Number of step stages (rows of `a` of the step, the first of them empty).
    stages: usize,
    /// Number of extra stages of the continuous extension.
    extra: usize,
}

impl SparseRows {
    /// The nonzero weights of `tab`'s rows.
    pub(super) fn new(tab: &ExplicitTableau) -> Self {
        let (extra_a, d): (&[&[f64]], &[&[f64]]) =
            tab.dense.as_ref().map_or((&[], &[]), |d| (d.a, d.d));
        let rows = tab.a.iter().chain([&tab.b]).chain(extra_a).chain(d);
        let mut terms = Vec::new();
        let mut starts = vec![0];
        for row in rows {
            let nonzero = row.iter().copied().enumerate().filter(|&(_, w)| w != 0.0);
            terms.extend(nonzero);
            starts.push(terms.len());
        }
        Self {
            terms,
            starts,
            stages: tab.stages(),
            extra: extra_a.len(),
        }
    }

    /// Row `r` of all rows.
    fn row(&self, r: usize) -> &[(usize, f64)] {
        &self.terms[self.starts[r]..self.starts[r + 1]]
    }

    /// The nonzero weights of stage `i`'s row of `a`.
    pub(super) fn stage(&self, i: usize) -> &[(usize, f64)] {
        self.row(i)
    }

    /// The nonzero weights `b` of the propagated solution.
    pub(super) fn b(&self) -> &[(usize, f64)] {
        self.row(self.stages)
    }

    /// The nonzero weights of the continuous extension's extra stage `x`'s row of `a`.
    pub(super) fn extra_stage(&self, x: usize) -> &[(usize, f64)] {
        self.row(self.stages + 1 + x)
    }

    /// The nonzero weights of the continuous extension's row `d[j]`.
    pub(super) fn dense_term(&self, j: usize) -> &[(usize, f64)] {
        self.row(self.stages + 1 + self.extra + j)
    }
}

/// `out[m] = base[m] + h Σ_j w_j k_j[m]` for every component `m` (`base` absent:
/// just the increment), over the `(j, w_j)` pairs `w` and the stage-major slopes `k`
/// of `n` components each.
///
/// The sum runs over the pairs outermost, four components side by side in registers
/// (independent add chains instead of one serial chain per component); each component
/// still adds its terms in the pairs' order from `-0.0`, so the result is the same as
/// the plain per-component sum, bit for bit.
pub(super) fn weighted_sum<W>(
    h: f64,
    w: W,
    k: &[f64],
    n: usize,
    base: Option<&[f64]>,
    out: &mut [f64],
) where
    W: Iterator<Item = (usize, f64)> + Clone,
{
    // A state of exactly four components (the production model's): the slopes as
    // rows of four, with no index arithmetic per term.
    if let (Ok(out), LANES) = (<&mut [f64; LANES]>::try_from(&mut *out), n) {
        let (rows, _) = k.as_chunks::<LANES>();
        let mut acc = [-0.0; LANES];
        for (j, wj) in w {
            for (a, kj) in acc.iter_mut().zip(&rows[j]) {
                *a += wj * kj;
            }
        }
        finish(h, acc, base, 0, out);
        return;
    }
    let mut m0 = 0;
    let mut chunks = out.chunks_exact_mut(LANES);
    for chunk in &mut chunks {
        components::<LANES, W>(h, w.clone(), k, n, base, m0, chunk);
        m0 += LANES;
    }
    for o in chunks.into_remainder().chunks_exact_mut(1) {
        components::<1, W>(h, w.clone(), k, n, base, m0, o);
        m0 += 1;
    }
}

/// [`weighted_sum`] for the `L` components `m0 .. m0 + L` (a fixed-size accumulator,
/// so it lives in registers).
#[inline(always)]
fn components<const L: usize, W: Iterator<Item = (usize, f64)>>(
    h: f64,
    w: W,
    k: &[f64],
    n: usize,
    base: Option<&[f64]>,
    m0: usize,
    out: &mut [f64],
) {
    let mut acc = [-0.0; L];
    for (j, wj) in w {
        let row = &k[j * n + m0..][..L];
        for (a, kj) in acc.iter_mut().zip(row) {
            *a += wj * kj;
        }
    }
    finish(h, acc, base, m0, out);
}

/// `out[l] = base[m0 + l] + h acc[l]` (`base` absent: `h acc[l]`).
#[inline(always)]
fn finish<const L: usize>(h: f64, acc: [f64; L], base: Option<&[f64]>, m0: usize, out: &mut [f64]) {
    for (l, (o, a)) in out.iter_mut().zip(acc).enumerate() {
        *o = match base {
            Some(b) => b[m0 + l] + h * a,
            None => h * a,
        };
    }
}

/// `out = y + h Σ_j w_j k_j` over the pairs `terms` and the stage-major slopes `k`.
pub(super) fn combine(y: &[f64], h: f64, terms: &[(usize, f64)], k: &[f64], out: &mut [f64]) {
    weighted_sum(h, terms.iter().copied(), k, y.len(), Some(y), out);
}

#[cfg(test)]
mod tests {
    use super::super::tableau::{DOP853, DORMAND_PRINCE, RK4, TSITOURAS5};
    use super::*;

    /// A generator of values over many magnitudes and both signs.
    fn values() -> impl FnMut() -> f64 {
        let mut x = 0.618_033_988_749_895_f64;
        move || {
            x = (x * 9_301.0 + 0.497).fract();
            (x - 0.5) * 10f64.powi((x * 1e4) as i32 % 9 - 4)
        }
    }

    /// The side-by-side sums equal the plain per-component sums bit for bit, for state
    /// sizes with and without a remainder after the groups of four (and of exactly four,
    /// which has its own path), with and without a base, for every stage count of
    /// DOP853 and its dense output, with some weights zero and left out of the pairs.
    #[test]
    fn weighted_sums_equal_the_plain_sums_bit_for_bit() {
        let mut next = values();
        for n in 1..=11 {
            for stages in [1, 4, 7, 12, 16] {
                let k: Vec<f64> = (0..stages * n).map(|_| next()).collect();
                let w: Vec<f64> = (0..stages)
                    .map(|j| if j % 3 == 1 { 0.0 } else { next() })
                    .collect();
                let pairs: Vec<(usize, f64)> = w
                    .iter()
                    .copied()
                    .enumerate()
                    .filter(|p| p.1 != 0.0)
                    .collect();
                let base: Vec<f64> = (0..n).map(|_| next()).collect();
                let h = next().abs() + 1e-6;
                for with_base in [false, true] {
                    let mut out = vec![0.0; n];
                    let b = with_base.then_some(base.as_slice());
                    weighted_sum(h, pairs.iter().copied(), &k, n, b, &mut out);
                    for (m, got) in out.iter().enumerate() {
                        let sum: f64 = w.iter().enumerate().map(|(j, wj)| wj * k[j * n + m]).sum();
                        let want = if with_base {
                            base[m] + h * sum
                        } else {
                            h * sum
                        };
                        assert_eq!(got.to_bits(), want.to_bits(), "n {n} stages {stages} m {m}");
                    }
                }
            }
        }
    }

    /// What leaving zeros out relies on: in every explicit tableau each stage's slope
    /// has a nonzero weight in the next row (the next stage's, or for the last stage
    /// of a continuous extension, some dense-output term), so a non-finite slope still
    /// reaches a stage state or the interpolant.
    #[test]
    fn every_slope_has_a_nonzero_weight_in_the_next_row() {
        for tab in [&RK4, &DORMAND_PRINCE, &TSITOURAS5, &DOP853] {
            let extra_a: &[&[f64]] = tab.dense.as_ref().map_or(&[], |d| d.a);
            let rows: Vec<&[f64]> = tab.a.iter().chain(extra_a).copied().collect();
            for (i, row) in rows.iter().enumerate().skip(1) {
                assert_ne!(row[i - 1], 0.0, "order {} row {i}", tab.order);
            }
            if let Some(d) = tab.dense.as_ref().filter(|d| !d.c.is_empty()) {
                let last = tab.all_stages() - 1;
                assert!(
                    d.d.iter().any(|row| row[last] != 0.0),
                    "order {}",
                    tab.order
                );
            }
        }
    }

    /// DOP853's sparse rows hold exactly the nonzero weights of its rows, in order.
    #[test]
    fn sparse_rows_hold_the_nonzero_weights_of_each_row() {
        let sparse = SparseRows::new(&DOP853);
        let dense = DOP853
            .dense
            .as_ref()
            .expect("DOP853 has a continuous extension");
        let nonzero = |row: &[f64]| -> Vec<(usize, f64)> {
            row.iter()
                .copied()
                .enumerate()
                .filter(|p| p.1 != 0.0)
                .collect()
        };
        for (i, row) in DOP853.a.iter().enumerate() {
            assert_eq!(sparse.stage(i), nonzero(row), "stage {i}");
        }
        assert_eq!(sparse.b(), nonzero(DOP853.b));
        for (x, row) in dense.a.iter().enumerate() {
            assert_eq!(sparse.extra_stage(x), nonzero(row), "extra stage {x}");
        }
        for (j, row) in dense.d.iter().enumerate() {
            assert_eq!(sparse.dense_term(j), nonzero(row), "dense term {j}");
        }
        let total: usize = DOP853
            .a
            .iter()
            .chain(dense.a)
            .chain(dense.d)
            .map(|r| r.len())
            .sum();
        let kept: usize = (0..DOP853.stages())
            .map(|i| sparse.stage(i).len())
            .sum::<usize>()
            + (0..dense.a.len())
                .map(|x| sparse.extra_stage(x).len())
                .sum::<usize>()
            + (0..dense.d.len())
                .map(|j| sparse.dense_term(j).len())
                .sum::<usize>();
        assert_eq!((total, total - kept), (184, 54), "weights, zeros");
    }
}
