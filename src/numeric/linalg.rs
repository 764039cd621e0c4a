//! Small dense linear algebra: an in-place LU factorisation with partial pivoting.
//!
//! The systems studyrun solves are tiny (a handful of constraint equations, a few
//! implicit stages), so a plain row-major LU beats a general-purpose library and
//! lets every buffer be allocated once per case and reused on every step.

/// The matrix handed to [`Lu::factor`] is singular (a pivot is zero or not finite).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("singular matrix: pivot {pivot:e} in column {column}")]
pub struct Singular {
    /// Column (0-based) whose pivot vanished.
    pub column: usize,
    /// The offending pivot value.
    pub pivot: f64,
}

/// LU factors of a square matrix, `P A = L U`, stored in place (row-major).
#[derive(Debug, Clone)]
pub struct Lu {
    n: usize,
    lu: Vec<f64>,
    perm: Vec<usize>,
}

impl Lu {
    /// Workspace for `n × n` matrices; allocates once.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            lu: vec![0.0; n * n],
            perm: (0..n).collect(),
        }
    }

    /// Order of the matrices this workspace factors.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Factors the row-major `n × n` matrix `a` (copied; `a` is left untouched).
    pub fn factor(&mut self, a: &[f64]) -> Result<(), Singular> {
        let n = self.n;
        assert_eq!(a.len(), n * n, "Lu::factor: matrix must be {n}x{n}");
        self.lu.copy_from_slice(a);
        for (i, p) in self.perm.iter_mut().enumerate() {
            *p = i;
        }
        let lu = &mut self.lu;
        for k in 0..n {
            let mut p = k;
            let mut best = lu[k * n + k].abs();
            for i in k + 1..n {
                let v = lu[i * n + k].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best == 0.0 || !best.is_finite() {
                return Err(Singular {
                    column: k,
                    pivot: lu[p * n + k],
                });
            }
            if p != k {
                for j in 0..n {
                    lu.swap(k * n + j, p * n + j);
                }
                self.perm.swap(k, p);
            }
            let pivot = lu[k * n + k];
            for i in k + 1..n {
                let f = lu[i * n + k] / pivot;
                lu[i * n + k] = f;
                if f != 0.0 {
                    for j in k + 1..n {
                        lu[i * n + j] -= f * lu[k * n + j];
                    }
                }
            }
        }
        Ok(())
    }

    /// Solves `A x = b` in place with the factors from the last [`Lu::factor`];
    /// `scratch` must have length `n`.
    pub fn solve_in_place(&self, b: &mut [f64], scratch: &mut [f64]) {
        let n = self.n;
        let lu = &self.lu;
        for (i, s) in scratch.iter_mut().enumerate() {
            *s = b[self.perm[i]];
        }
        for i in 0..n {
            let mut s = scratch[i];
            for j in 0..i {
                s -= lu[i * n + j] * scratch[j];
            }
            scratch[i] = s;
        }
        for i in (0..n).rev() {
            let mut s = scratch[i];
            for j in i + 1..n {
                s -= lu[i * n + j] * scratch[j];
            }
            scratch[i] = s / lu[i * n + i];
        }
        b.copy_from_slice(scratch);
    }

    /// Solves `Aᵀ x = b` in place with the factors from the last [`Lu::factor`];
    /// `scratch` must have length `n`.
    pub fn solve_transpose_in_place(&self, b: &mut [f64], scratch: &mut [f64]) {
        // A = Pᵀ L U, so Aᵀ = Uᵀ Lᵀ P: solve Uᵀ w = b, Lᵀ z = w, then x = Pᵀ z.
        let n = self.n;
        let lu = &self.lu;
        scratch.copy_from_slice(b);
        for i in 0..n {
            let mut s = scratch[i];
            for j in 0..i {
                s -= lu[j * n + i] * scratch[j];
            }
            scratch[i] = s / lu[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = scratch[i];
            for j in i + 1..n {
                s -= lu[j * n + i] * scratch[j];
            }
            scratch[i] = s;
        }
        for i in 0..n {
            b[self.perm[i]] = scratch[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matvec(a: &[f64], x: &[f64], n: usize, transpose: bool) -> Vec<f64> {
        (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| if transpose { a[j * n + i] } else { a[i * n + j] } * x[j])
                    .sum()
            })
            .collect()
    }

    #[test]
    fn solves_and_transposed_solves_a_pivoting_system() {
        // Zero leading pivot forces a row exchange.
        let n = 4;
        let a = [
            0.0, 2.0, 1.0, -1.0, //
            3.0, -1.0, 0.5, 2.0, //
            1.0, 1.0, 4.0, 0.0, //
            -2.0, 0.0, 1.0, 5.0,
        ];
        let x = [1.0, -2.0, 0.25, 3.0];
        let mut lu = Lu::new(n);
        lu.factor(&a).unwrap();
        let mut scratch = vec![0.0; n];
        for transpose in [false, true] {
            let mut b = matvec(&a, &x, n, transpose);
            if transpose {
                lu.solve_transpose_in_place(&mut b, &mut scratch);
            } else {
                lu.solve_in_place(&mut b, &mut scratch);
            }
            for (got, want) in b.iter().zip(x) {
                assert!((got - want).abs() < 1e-13, "{got} vs {want}");
            }
        }
    }

    #[test]
    fn reports_singular_matrix() {
        let mut lu = Lu::new(2);
        let err = lu.factor(&[1.0, 2.0, 2.0, 4.0]).unwrap_err();
        assert_eq!(err.column, 1);
    }
}
