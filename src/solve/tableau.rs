//! Butcher tableaus as data, with their literature sources.
//!
//! The coefficients are checked against the Runge–Kutta order conditions (all rooted
//! trees up to the claimed order) by the unit tests at the bottom of this file.

/// An explicit Runge–Kutta method: `a` is strictly lower triangular, row `i` holding
/// `a[i][0..i]`.
#[derive(Debug)]
pub(crate) struct ExplicitTableau {
    /// Nodes `c_i` (fractions of the step).
    pub c: &'static [f64],
    /// Stage coefficients, row `i` of length `i`.
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution.
    pub b: &'static [f64],
    /// Weights of the embedded solution used for the error estimate (empty: none).
    pub b_hat: &'static [f64],
    /// Order of the propagated solution.
    pub order: u32,
    /// Order of the embedded solution (0 without one).
    pub embedded_order: u32,
    /// First-same-as-last: the last stage is evaluated at the new solution
    /// (its row of `a` equals `b`), so its slope is the next step's first stage.
    pub fsal: bool,
    /// Continuous extension `y(t0 + θh) = H(θ) + θ²(1−θ)² h Σ d_i k_i`, where `H` is
    /// the cubic Hermite interpolant of `y0, y1, f0, f1`; needs `fsal` (so that `f1`
    /// is the last stage). `None`: plain cubic Hermite.
    pub dense: Option<&'static [f64]>,
}

impl ExplicitTableau {
    /// Number of stages.
    pub fn stages(&self) -> usize {
        self.c.len()
    }
}

/// The classic fourth-order Runge–Kutta method (Kutta 1901; Hairer, Nørsett &
/// Wanner, *Solving ODEs I*, 2nd ed., Table II.1.2, left).
pub(crate) const RK4: ExplicitTableau = ExplicitTableau {
    c: &[0.0, 0.5, 0.5, 1.0],
    a: &[&[], &[0.5], &[0.0, 0.5], &[0.0, 0.0, 1.0]],
    b: &[1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
    b_hat: &[],
    order: 4,
    embedded_order: 0,
    fsal: false,
    dense: None,
};

/// Dormand & Prince, "A family of embedded Runge–Kutta formulae", J. Comput. Appl.
/// Math. 6 (1980) 19–26: the 5(4) pair of Hairer, Nørsett & Wanner, *Solving ODEs I*,
/// 2nd ed., Table II.5.2 (DOPRI5), with the order-4 continuous extension of §II.6
/// in the form used by Hairer's code `DOPRI5` (routine `CONTD5`, coefficients `d_i`).
pub(crate) const DORMAND_PRINCE: ExplicitTableau = ExplicitTableau {
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[
            19372.0 / 6561.0,
            -25360.0 / 2187.0,
            64448.0 / 6561.0,
            -212.0 / 729.0,
        ],
        &[
            9017.0 / 3168.0,
            -355.0 / 33.0,
            46732.0 / 5247.0,
            49.0 / 176.0,
            -5103.0 / 18656.0,
        ],
        &[
            35.0 / 384.0,
            0.0,
            500.0 / 1113.0,
            125.0 / 192.0,
            -2187.0 / 6784.0,
            11.0 / 84.0,
        ],
    ],
    b: &[
        35.0 / 384.0,
        0.0,
        500.0 / 1113.0,
        125.0 / 192.0,
        -2187.0 / 6784.0,
        11.0 / 84.0,
        0.0,
    ],
    b_hat: &[
        5179.0 / 57600.0,
        0.0,
        7571.0 / 16695.0,
        393.0 / 640.0,
        -92097.0 / 339200.0,
        187.0 / 2100.0,
        1.0 / 40.0,
    ],
    order: 5,
    embedded_order: 4,
    fsal: true,
    dense: Some(&[
        -12715105075.0 / 11282082432.0,
        0.0,
        87487479700.0 / 32700410799.0,
        -10690763975.0 / 1880347072.0,
        701980252875.0 / 199316789632.0,
        -1453857185.0 / 822651844.0,
        69997945.0 / 29380423.0,
    ]),
};

/// A singly diagonally implicit Runge–Kutta method: `a` is lower triangular with
/// `gamma` on the diagonal, row `i` holding `a[i][0..=i]`.
#[derive(Debug)]
pub(crate) struct SdirkTableau {
    /// The common diagonal coefficient.
    pub gamma: f64,
    /// Nodes `c_i` (fractions of the step).
    pub c: &'static [f64],
    /// Stage coefficients, row `i` of length `i + 1` (diagonal included).
    pub a: &'static [&'static [f64]],
    /// Weights of the propagated solution (equal to the last row of `a`:
    /// stiffly accurate, so the new solution is the last stage value).
    pub b: &'static [f64],
    /// Weights of the embedded solution used for the error estimate.
    pub b_hat: &'static [f64],
    /// Order of the propagated solution.
    pub order: u32,
    /// Order of the embedded solution.
    pub embedded_order: u32,
}

impl SdirkTableau {
    /// Number of stages.
    pub fn stages(&self) -> usize {
        self.c.len()
    }
}

/// The L-stable, stiffly accurate SDIRK method of order 4 with embedded order 3,
/// γ = 1/4: Hairer & Wanner, *Solving ODEs II*, 2nd ed., Table IV.6.5 (the method
/// of their code `SDIRK4`).
pub(crate) const SDIRK4: SdirkTableau = SdirkTableau {
    gamma: 0.25,
    c: &[0.25, 0.75, 11.0 / 20.0, 0.5, 1.0],
    a: &[
        &[0.25],
        &[0.5, 0.25],
        &[17.0 / 50.0, -1.0 / 25.0, 0.25],
        &[371.0 / 1360.0, -137.0 / 2720.0, 15.0 / 544.0, 0.25],
        &[25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25],
    ],
    b: &[25.0 / 24.0, -49.0 / 48.0, 125.0 / 16.0, -85.0 / 12.0, 0.25],
    b_hat: &[59.0 / 48.0, -17.0 / 96.0, 225.0 / 32.0, -85.0 / 12.0, 0.0],
    order: 4,
    embedded_order: 3,
};

#[cfg(test)]
mod tests {
    use super::*;

    /// A rooted tree, as the list of its root's subtrees.
    #[derive(Debug, Clone)]
    struct Tree(Vec<Tree>);

    impl Tree {
        fn order(&self) -> usize {
            1 + self.0.iter().map(Tree::order).sum::<usize>()
        }
        /// The density γ(t): the exact solution's elementary weight is 1/γ.
        fn density(&self) -> f64 {
            self.order() as f64 * self.0.iter().map(Tree::density).product::<f64>()
        }
        /// Per-stage elementary weights g_i(t) = Π_children (A g(child))_i.
        fn stage_weights(&self, a: &[Vec<f64>]) -> Vec<f64> {
            let s = a.len();
            let mut g = vec![1.0; s];
            for child in &self.0 {
                let gc = child.stage_weights(a);
                for (i, gi) in g.iter_mut().enumerate() {
                    *gi *= (0..s).map(|j| a[i][j] * gc[j]).sum::<f64>();
                }
            }
            g
        }
    }

    /// All rooted trees of order `n` (duplicates allowed: checking a condition
    /// twice is harmless).
    fn trees(n: usize) -> Vec<Tree> {
        forests(n - 1).into_iter().map(Tree).collect()
    }

    /// All ordered forests of total order `m`.
    fn forests(m: usize) -> Vec<Vec<Tree>> {
        if m == 0 {
            return vec![vec![]];
        }
        let mut out = Vec::new();
        for k in 1..=m {
            for t in trees(k) {
                for rest in forests(m - k) {
                    let mut f = vec![t.clone()];
                    f.extend(rest);
                    out.push(f);
                }
            }
        }
        out
    }

    /// Full square matrix from lower-triangular rows.
    fn square(rows: &[&[f64]]) -> Vec<Vec<f64>> {
        let s = rows.len();
        rows.iter()
            .map(|r| (0..s).map(|j| r.get(j).copied().unwrap_or(0.0)).collect())
            .collect()
    }

    /// Largest violation of the order conditions of order `p` by weights `w`
    /// whose exact elementary weights are `scale^{|t|}/γ(t)` (scale = θ for a
    /// continuous extension, 1 otherwise).
    fn max_violation(a: &[Vec<f64>], w: &[f64], p: usize, scale: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for n in 1..=p {
            for t in trees(n) {
                let g = t.stage_weights(a);
                let phi: f64 = w.iter().zip(&g).map(|(wi, gi)| wi * gi).sum();
                let exact = scale.powi(n as i32) / t.density();
                worst = worst.max((phi - exact).abs());
            }
        }
        worst
    }

    fn assert_row_sums(a: &[Vec<f64>], c: &[f64]) {
        for (row, ci) in a.iter().zip(c) {
            let sum: f64 = row.iter().sum();
            assert!((sum - ci).abs() < 1e-15, "row sum {sum} != c = {ci}");
        }
    }

    #[test]
    fn tree_counts_match_the_known_sequence() {
        // 1, 1, 2, 4, 9, 20 distinct trees; with ordered children the forests
        // give 1, 1, 2, 5, 14, 42 (Catalan numbers) -- a check of the generator.
        let counts: Vec<usize> = (1..=6).map(|n| trees(n).len()).collect();
        assert_eq!(counts, [1, 1, 2, 5, 14, 42]);
    }

    #[test]
    fn rk4_has_order_four_but_not_five() {
        let a = square(RK4.a);
        assert_row_sums(&a, RK4.c);
        assert!(max_violation(&a, RK4.b, 4, 1.0) < 1e-15);
        assert!(max_violation(&a, RK4.b, 5, 1.0) > 1e-3);
        assert_eq!(RK4.order, 4);
        assert!(RK4.b_hat.is_empty() && RK4.dense.is_none() && !RK4.fsal);
    }

    #[test]
    fn dormand_prince_orders_five_and_four() {
        let t = &DORMAND_PRINCE;
        let a = square(t.a);
        assert_row_sums(&a, t.c);
        assert!(max_violation(&a, t.b, 5, 1.0) < 1e-14);
        assert!(max_violation(&a, t.b, 6, 1.0) > 1e-5);
        let b_hat = t.b_hat;
        assert!(max_violation(&a, b_hat, 4, 1.0) < 1e-14);
        assert!(max_violation(&a, b_hat, 5, 1.0) > 1e-5);
        // FSAL: the last row of A is b.
        for (x, y) in t.a[6].iter().zip(t.b) {
            assert_eq!(x, y);
        }
        assert_eq!(t.b[6], 0.0);
        assert!(t.fsal && t.order == 5 && t.embedded_order == 4);
    }

    /// Weights b_i(θ) of the continuous extension: the cubic Hermite part written
    /// in terms of the stages (Δ = h Σ b k, f0 = k_1, f1 = k_s) plus θ²(1−θ)² d.
    fn dense_weights(t: &ExplicitTableau, theta: f64) -> Vec<f64> {
        let s = t.stages();
        let d = t.dense.unwrap();
        let th1 = 1.0 - theta;
        (0..s)
            .map(|i| {
                let first = if i == 0 { 1.0 } else { 0.0 };
                let last = if i == s - 1 { 1.0 } else { 0.0 };
                theta * t.b[i]
                    + theta * th1 * (first - t.b[i])
                    + theta * theta * th1 * (2.0 * t.b[i] - first - last)
                    + theta * theta * th1 * th1 * d[i]
            })
            .collect()
    }

    #[test]
    fn dormand_prince_dense_output_has_order_four() {
        let t = &DORMAND_PRINCE;
        let a = square(t.a);
        for (i, w) in dense_weights(t, 1.0).iter().enumerate() {
            assert!((w - t.b[i]).abs() < 1e-15, "θ = 1 must reproduce b");
        }
        for k in 1..10 {
            let theta = k as f64 / 10.0;
            let w = dense_weights(t, theta);
            let v4 = max_violation(&a, &w, 4, theta);
            assert!(v4 < 1e-14, "θ = {theta}: order-4 violation {v4:e}");
            // The extension is of order 4, not 5: the check above is not vacuous.
            assert!(max_violation(&a, &w, 5, theta) > 1e-6);
        }
    }

    #[test]
    fn dormand_prince_dense_output_interpolates_exp_to_fifth_power_of_h() {
        // One step of y' = y from y = 1: the dense value's error at θ = 1/2 must
        // fall like h^5 (local error of an order-4 extension).
        let t = &DORMAND_PRINCE;
        let err_at = |h: f64| {
            let s = t.stages();
            let mut k = vec![0.0; s];
            for i in 0..s {
                let yi = 1.0 + h * (0..i).map(|j| t.a[i][j] * k[j]).sum::<f64>();
                k[i] = yi;
            }
            let w = dense_weights(t, 0.5);
            let y = 1.0 + h * w.iter().zip(&k).map(|(wi, ki)| wi * ki).sum::<f64>();
            (y - (0.5 * h).exp()).abs()
        };
        let ratio = err_at(0.2) / err_at(0.1);
        let order = ratio.log2();
        assert!((order - 5.0).abs() < 0.3, "local order {order}");
    }

    #[test]
    fn sdirk4_orders_four_and_three_and_l_stability() {
        let t = &SDIRK4;
        let a = square(t.a);
        assert_row_sums(&a, t.c);
        for (i, row) in t.a.iter().enumerate() {
            assert_eq!(row.len(), i + 1);
            assert_eq!(row[i], t.gamma);
        }
        assert!(max_violation(&a, t.b, 4, 1.0) < 1e-13);
        assert!(max_violation(&a, t.b, 5, 1.0) > 1e-5);
        assert!(max_violation(&a, t.b_hat, 3, 1.0) < 1e-13);
        assert!(max_violation(&a, t.b_hat, 4, 1.0) > 1e-5);
        // Stiffly accurate: b is the last row of A.
        assert_eq!(t.b, *t.a.last().unwrap());
        assert_eq!((t.order, t.embedded_order, t.stages()), (4, 3, 5));
        // L-stability: the stability function R(z) = 1 + z bᵀ(I − zA)⁻¹ 1 tends
        // to 0 as z → −∞ (and |R| ≤ 1 on the negative axis).
        let r = |z: f64| {
            let s = t.stages();
            let mut u = vec![0.0; s]; // u = (I − zA)⁻¹ 1 by forward substitution
            for i in 0..s {
                let acc: f64 = (0..i).map(|j| a[i][j] * u[j]).sum();
                u[i] = (1.0 + z * acc) / (1.0 - z * a[i][i]);
            }
            1.0 + z * t.b.iter().zip(&u).map(|(b, u)| b * u).sum::<f64>()
        };
        assert!(r(-1e8).abs() < 1e-6);
        for k in 0..60 {
            let z = -(10f64.powf(k as f64 / 6.0 - 3.0));
            assert!(r(z).abs() <= 1.0 + 1e-12, "|R({z})| = {}", r(z).abs());
        }
    }
}
