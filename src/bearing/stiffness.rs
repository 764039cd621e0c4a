//! Ball–raceway contact stiffness from bearing geometry by Harris's method
//! (docs/model.md §2 "Stiffness from geometry"; Xu & Li 2014, eqs. 26–27; Harris &
//! Kotzalas, *Rolling Bearing Analysis*).
//!
//! For a radial deep-groove ball bearing (contact angle 0) with ball diameter `D`,
//! pitch diameter `d_m`, groove conformities `f = r_groove / D` and `γ = D / d_m`:
//!
//! - curvature sums `Σρ_i = (4 − 1/f_i + 2γ/(1−γ)) / D`, `Σρ_o = (4 − 1/f_o − 2γ/(1+γ)) / D`;
//! - curvature differences `F(ρ)_i = (1/f_i + 2γ/(1−γ)) / (D Σρ_i)`,
//!   `F(ρ)_o = (1/f_o − 2γ/(1+γ)) / (D Σρ_o)`;
//! - the contact ellipse's ellipticity `κ = a/b` solves
//!   `F(ρ) = [(κ²+1) E(m) − 2 K(m)] / [(κ²−1) E(m)]`, `m = 1 − 1/κ²`;
//! - the dimensionless deflection `δ* = (2K(m)/π) [π / (2κ² E(m))]^{1/3}`;
//! - the load–deflection constant `K_c = (2√2/3) (Σρ)^{−1/2} (δ*)^{−3/2} E/(1−ν²)`
//!   of each contact (`Q = K_c δ^{3/2}`), and the series combination
//!   `K = (K_i^{−2/3} + K_o^{−2/3})^{−3/2}` of inner and outer contact.
//!
//! The stiffness formula is Hertz's: for two bodies of one material
//! (`1/E* = 2(1−ν²)/E`) and semi-axes `a = κ b`, Hertz gives
//! `Σρ/2 = p₀ E(m) / (E* b)`, `p₀ = 3Q / (2π a b)` and `δ = p₀ b K(m) / E*`, so
//! `δ = δ* (Σρ/2) [3Q / (2 E* Σρ)]^{2/3}` with the `δ*` above; solved for `Q` this is
//! `Q = (2√2/3) (Σρ)^{−1/2} (δ*)^{−3/2} E/(1−ν²) δ^{3/2}` (units: `m^{1/2} · Pa = N/m^{3/2}`).
//!
//! `K(m)` and `E(m)` are the complete elliptic integrals in the parameter convention
//! (`m = k²`), computed by the arithmetic–geometric mean.

use crate::error::ParamError;
use std::f64::consts::{FRAC_PI_2, PI};

/// Complete elliptic integrals `(K(m), E(m))` for parameter `m = k²` given together
/// with its complement `m1 = 1 − m` (both passed so that neither loses precision when
/// it is small). Arithmetic–geometric mean with `c_{n+1} = c_n² / (4 a_{n+1})`, so no
/// difference of nearly equal numbers is formed.
fn agm_ke(m: f64, m1: f64) -> (f64, f64) {
    let mut a = 1.0_f64;
    let mut b = m1.sqrt();
    let mut c2 = m; // c_n²
    let mut weight = 0.5; // 2^{n-1}
    let mut sum = weight * c2; // Σ 2^{n-1} c_n²
    for _ in 0..64 {
        let a_next = 0.5 * (a + b);
        let b_next = (a * b).sqrt();
        let c = c2 / (4.0 * a_next);
        a = a_next;
        b = b_next;
        c2 = c * c;
        weight *= 2.0;
        sum += weight * c2;
        if c <= 0.5 * f64::EPSILON * a {
            break;
        }
    }
    let k = FRAC_PI_2 / a;
    (k, k * (1.0 - sum))
}

/// Complete elliptic integrals of the first and second kind, `(K(m), E(m))`
/// (dimensionless), for the parameter `m = k²` with `0 ≤ m < 1`, to full double
/// precision (the relative error of `E` grows like `K(m)` ulps as `m → 1`).
/// Returns `(NaN, NaN)` outside `[0, 1)`.
pub fn elliptic_ke(m: f64) -> (f64, f64) {
    if !(0.0..1.0).contains(&m) {
        return (f64::NAN, f64::NAN);
    }
    agm_ke(m, 1.0 - m)
}

/// Complete elliptic integral of the first kind `K(m) = ∫₀^{π/2} (1 − m sin²θ)^{−1/2} dθ`
/// (dimensionless), parameter `m = k²`, `0 ≤ m < 1`; NaN outside.
pub fn elliptic_k(m: f64) -> f64 {
    elliptic_ke(m).0
}

/// Complete elliptic integral of the second kind `E(m) = ∫₀^{π/2} (1 − m sin²θ)^{1/2} dθ`
/// (dimensionless), parameter `m = k²`, `0 ≤ m < 1`; NaN outside.
pub fn elliptic_e(m: f64) -> f64 {
    elliptic_ke(m).1
}

/// `(m, 1 − m)` for the ellipticity `κ ≥ 1`, each without cancellation.
fn parameter_of_ellipticity(kappa: f64) -> (f64, f64) {
    let m1 = 1.0 / (kappa * kappa);
    let m = (kappa - 1.0) * (kappa + 1.0) * m1;
    (m, m1)
}

/// The curvature difference `F(ρ) = [(κ²+1)E − 2K] / [(κ²−1)E]` of the contact whose
/// ellipse has `m = 1 − 1/κ²`. Written as `[(1+m1)E − 2 m1 K] / (m E)`; for `m ≤ 1/2`
/// the numerator (which is `O(m²)`) is summed from its hypergeometric series, whose
/// terms are all positive, so the point-contact limit `F → 0` keeps full precision.
fn curvature_difference_of(m: f64, m1: f64) -> f64 {
    let (k, e) = agm_ke(m, m1);
    if m > 0.5 {
        return ((1.0 + m1) * e - 2.0 * m1 * k) / (m * e);
    }
    // [(2−m)E − 2(1−m)K] / m = (π/2) Σ_{n≥2} g_n m^{n−1},
    // g_n = c_{n−1} · 3(n−1) / (n(2n−3)), c_n = [(1/2)_n / n!]².
    let mut c_prev = 0.25; // c_1
    let mut power = m; // m^{n-1}
    let mut sum = 0.0;
    for n in 2..200 {
        let nf = n as f64;
        let term = c_prev * 3.0 * (nf - 1.0) / (nf * (2.0 * nf - 3.0)) * power;
        sum += term;
        if term <= 0.25 * f64::EPSILON * sum {
            break;
        }
        let r = (2.0 * nf - 1.0) / (2.0 * nf);
        c_prev *= r * r;
        power *= m;
    }
    FRAC_PI_2 * sum / e
}

/// Ellipticity `κ = a/b ≥ 1` (dimensionless, major over minor semi-axis) of the Hertz
/// contact ellipse with curvature difference `F(ρ)` (dimensionless), found by
/// bisection on `ln κ` to within a few ulps. Only `|F(ρ)|` matters (its sign says
/// which principal direction holds the major axis); `F(ρ) = 0` gives `κ = 1`.
///
/// # Errors
/// `curvature_difference` if `|F(ρ)|` is not finite or not below 1.
pub fn ellipticity(curvature_difference: f64) -> Result<f64, ParamError> {
    let target = curvature_difference.abs();
    if !(target.is_finite() && target < 1.0) {
        return Err(ParamError::new(
            "curvature_difference",
            curvature_difference,
            "|F(rho)| must be finite and below 1",
        ));
    }
    if target == 0.0 {
        return Ok(1.0);
    }
    let f_of_t = |t: f64| curvature_difference_of(-(-2.0 * t).exp_m1(), (-2.0 * t).exp());
    // F(ln κ) rises monotonically from 0 (κ = 1) towards 1 (κ → ∞); F < 1 in double
    // precision is below 1 − 1.1e-16, reached by κ ≈ 1e9 (ln κ ≈ 21).
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    while f_of_t(hi) < target {
        lo = hi;
        hi *= 2.0;
        if hi > 64.0 {
            return Err(ParamError::new(
                "curvature_difference",
                curvature_difference,
                "|F(rho)| too close to 1 (ellipticity beyond e^64)",
            ));
        }
    }
    for _ in 0..2200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi || hi - lo <= 2.0 * f64::EPSILON * hi {
            break;
        }
        if f_of_t(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok((0.5 * (lo + hi)).exp())
}

/// Harris's dimensionless contact deflection `δ* = (2K(m)/π) [π / (2κ² E(m))]^{1/3}`
/// (dimensionless) for ellipticity `κ ≥ 1`, `m = 1 − 1/κ²`; `δ*(1) = 1`. NaN for
/// `κ < 1` or non-finite `κ`.
pub fn dimensionless_deflection(kappa: f64) -> f64 {
    if !(kappa >= 1.0 && kappa.is_finite()) {
        return f64::NAN;
    }
    let (m, m1) = parameter_of_ellipticity(kappa);
    let (k, e) = agm_ke(m, m1);
    2.0 * k / PI * (PI / (2.0 * kappa * kappa * e)).cbrt()
}

/// Geometry and material of a radial deep-groove ball bearing (contact angle 0),
/// balls and rings of one material. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGeometry {
    /// Ball diameter `D` (m).
    pub ball_diameter: f64,
    /// Pitch diameter `d_m` (m), the diameter of the circle through the ball centres.
    pub pitch_diameter: f64,
    /// Inner groove conformity `f_i = r_groove / D` (dimensionless, > 0.5).
    pub inner_conformity: f64,
    /// Outer groove conformity `f_o = r_groove / D` (dimensionless, > 0.5).
    pub outer_conformity: f64,
    /// Young's modulus `E` of balls and rings (Pa).
    pub youngs_modulus: f64,
    /// Poisson's ratio `ν` of balls and rings (dimensionless, in (−1, 0.5)).
    pub poisson_ratio: f64,
}

/// One ball–raceway contact by Harris's method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RacewayContact {
    /// Curvature sum `Σρ` (1/m).
    pub curvature_sum: f64,
    /// Curvature difference `F(ρ)` (dimensionless).
    pub curvature_difference: f64,
    /// Ellipticity `κ = a/b` of the contact ellipse (dimensionless, ≥ 1).
    pub ellipticity: f64,
    /// Dimensionless deflection `δ*` (dimensionless).
    pub dimensionless_deflection: f64,
    /// Load–deflection constant `K_c` in `Q = K_c δ^{3/2}` (N/m^1.5).
    pub stiffness: f64,
}

/// Hertz load–deflection constants of a ball bearing (`Q = K δ^{3/2}`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HarrisStiffness {
    /// Ball–inner-raceway constant `K_i` (N/m^1.5).
    pub inner: f64,
    /// Ball–outer-raceway constant `K_o` (N/m^1.5).
    pub outer: f64,
    /// Both contacts in series, `K = (K_i^{−2/3} + K_o^{−2/3})^{−3/2}` (N/m^1.5):
    /// the `K` of docs/model.md §2's ball force `F_r = K δ_r^{3/2}`.
    pub total: f64,
}

impl ContactGeometry {
    /// The SKF 98205 bearing of Xu & Li 2014 (Table 2): `D` = 8.70 mm,
    /// `d_m` = 37.90 mm, steel with `E` = 207 GPa and `ν` = 0.30, and groove
    /// conformities `f_i = f_o` = 0.52 (not given in the paper; docs/model.md §2).
    pub fn skf_98205() -> Self {
        Self {
            ball_diameter: 8.70e-3,
            pitch_diameter: 37.90e-3,
            inner_conformity: 0.52,
            outer_conformity: 0.52,
            youngs_modulus: 207e9,
            poisson_ratio: 0.30,
        }
    }

    /// Checks every field: all finite, diameters and modulus positive, pitch diameter
    /// above the ball diameter, conformities above 0.5 (groove radius larger than the
    /// ball radius), Poisson's ratio in (−1, 0.5).
    ///
    /// # Errors
    /// The first offending field, as `bearing.<field>`.
    pub fn validate(&self) -> Result<(), ParamError> {
        let fields = [
            ("bearing.ball_diameter", self.ball_diameter),
            ("bearing.pitch_diameter", self.pitch_diameter),
            ("bearing.inner_conformity", self.inner_conformity),
            ("bearing.outer_conformity", self.outer_conformity),
            ("bearing.youngs_modulus", self.youngs_modulus),
            ("bearing.poisson_ratio", self.poisson_ratio),
        ];
        for (name, v) in fields {
            if !v.is_finite() {
                return Err(ParamError::new(name, v, "must be finite"));
            }
        }
        if self.ball_diameter <= 0.0 {
            return Err(ParamError::new(
                "bearing.ball_diameter",
                self.ball_diameter,
                "must be > 0 m",
            ));
        }
        if self.pitch_diameter <= self.ball_diameter {
            return Err(ParamError::new(
                "bearing.pitch_diameter",
                self.pitch_diameter,
                format!("must exceed the ball diameter ({} m)", self.ball_diameter),
            ));
        }
        for (name, f) in [
            ("bearing.inner_conformity", self.inner_conformity),
            ("bearing.outer_conformity", self.outer_conformity),
        ] {
            if f <= 0.5 {
                return Err(ParamError::new(
                    name,
                    f,
                    "must be > 0.5 (groove radius larger than the ball radius)",
                ));
            }
        }
        if self.youngs_modulus <= 0.0 {
            return Err(ParamError::new(
                "bearing.youngs_modulus",
                self.youngs_modulus,
                "must be > 0 Pa",
            ));
        }
        if !(self.poisson_ratio > -1.0 && self.poisson_ratio < 0.5) {
            return Err(ParamError::new(
                "bearing.poisson_ratio",
                self.poisson_ratio,
                "must lie in (-1, 0.5)",
            ));
        }
        Ok(())
    }

    /// `γ = D / d_m` (dimensionless).
    fn gamma(&self) -> f64 {
        self.ball_diameter / self.pitch_diameter
    }

    /// Contact of a ball with a raceway whose rolling-direction term is `rolling`
    /// (`+2γ/(1−γ)` inner, `−2γ/(1+γ)` outer) and whose conformity is `f`.
    fn contact(&self, f: f64, rolling: f64, field: &str) -> Result<RacewayContact, ParamError> {
        self.validate()?;
        let d_sigma = 4.0 - 1.0 / f + rolling; // D Σρ
        let curvature_sum = d_sigma / self.ball_diameter;
        let curvature_difference = (1.0 / f + rolling) / d_sigma;
        let kappa = ellipticity(curvature_difference).map_err(|_| {
            ParamError::new(
                field,
                f,
                "too close to 0.5: the contact ellipse degenerates (|F(rho)| rounds to 1)",
            )
        })?;
        let delta_star = dimensionless_deflection(kappa);
        let nu = self.poisson_ratio;
        let stiffness =
            2.0 * std::f64::consts::SQRT_2 / 3.0 / curvature_sum.sqrt() / delta_star.powf(1.5)
                * self.youngs_modulus
                / (1.0 - nu * nu);
        Ok(RacewayContact {
            curvature_sum,
            curvature_difference,
            ellipticity: kappa,
            dimensionless_deflection: delta_star,
            stiffness,
        })
    }

    /// The ball–inner-raceway contact (Harris, contact angle 0).
    ///
    /// # Errors
    /// As [`ContactGeometry::validate`].
    pub fn inner_contact(&self) -> Result<RacewayContact, ParamError> {
        let g = self.gamma();
        self.contact(
            self.inner_conformity,
            2.0 * g / (1.0 - g),
            "bearing.inner_conformity",
        )
    }

    /// The ball–outer-raceway contact (Harris, contact angle 0).
    ///
    /// # Errors
    /// As [`ContactGeometry::validate`].
    pub fn outer_contact(&self) -> Result<RacewayContact, ParamError> {
        let g = self.gamma();
        self.contact(
            self.outer_conformity,
            -2.0 * g / (1.0 + g),
            "bearing.outer_conformity",
        )
    }

    /// Inner, outer and total load–deflection constants (N/m^1.5) by Harris's method
    /// (the paper's eqs. 26–27).
    ///
    /// # Errors
    /// As [`ContactGeometry::validate`].
    pub fn harris_stiffness(&self) -> Result<HarrisStiffness, ParamError> {
        let inner = self.inner_contact()?.stiffness;
        let outer = self.outer_contact()?.stiffness;
        let total = (inner.powf(-2.0 / 3.0) + outer.powf(-2.0 / 3.0)).powf(-1.5);
        Ok(HarrisStiffness {
            inner,
            outer,
            total,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        ((a - b) / b).abs()
    }

    #[test]
    fn stiffness_elliptic_known_values() {
        assert_eq!(elliptic_k(0.0), FRAC_PI_2);
        assert_eq!(elliptic_e(0.0), FRAC_PI_2);
        // Reference values from mpmath at 40 digits, for the exact double nearest m.
        let cases = [
            (0.1, 1.6124413487202194, 1.5307576368977631),
            (0.5, 1.854074677301372, 1.350643881047675),
            (0.9, 2.5780921133481733, 1.1047747327040733),
            (0.99, 3.695637362989874, 1.015993545025224),
            (0.999999, 8.294051463601063, 1.0000038970261722),
            (1e-8, 1.5707963307218875, 1.5707963228679058),
        ];
        for (m, k, e) in cases {
            let (kk, ee) = elliptic_ke(m);
            assert!(rel(kk, k) < 4e-16, "K({m}) = {kk}, want {k}");
            // E loses ~K(m) ulps near m = 1.
            assert!(rel(ee, e) < 4e-16 * k, "E({m}) = {ee}, want {e}");
        }
        assert!(elliptic_k(1.0).is_nan() && elliptic_e(-0.1).is_nan());
        assert!(elliptic_k(f64::NAN).is_nan());
    }

    #[test]
    fn stiffness_legendre_relation() {
        for m in [1e-6, 0.01, 0.2, 0.5, 0.7, 0.95, 0.9999] {
            let (k, e) = elliptic_ke(m);
            let (kp, ep) = elliptic_ke(1.0 - m);
            let lhs = e * kp + ep * k - k * kp;
            assert!(rel(lhs, FRAC_PI_2) < 2e-15, "m = {m}: {lhs}");
        }
    }

    #[test]
    fn stiffness_series_matches_direct_formula_at_switch() {
        for m in [0.3, 0.45, 0.5] {
            let (k, e) = elliptic_ke(m);
            let direct = ((2.0 - m) * e - 2.0 * (1.0 - m) * k) / (m * e);
            let series = curvature_difference_of(m, 1.0 - m);
            assert!(rel(series, direct) < 1e-14, "m = {m}: {series} vs {direct}");
        }
        // Leading terms of the series: F = 3m/8 + 3m²/16 + O(m³).
        let m = 1e-7;
        assert!(
            rel(
                curvature_difference_of(m, 1.0 - m),
                3.0 * m / 8.0 + 3.0 * m * m / 16.0
            ) < 1e-14
        );
    }

    #[test]
    fn stiffness_ellipticity_roundtrip_and_references() {
        // κ, F(ρ), δ* from mpmath at 30 digits.
        for (kappa, f, ds) in [
            (1.5, 0.295529644824748, 0.979845557968184),
            (3.0, 0.6824027531331432, 0.8678853321649274),
        ] {
            let k = ellipticity(f).unwrap();
            assert!(rel(k, kappa) < 1e-14, "κ = {k}, want {kappa}");
            assert!(rel(dimensionless_deflection(kappa), ds) < 1e-14);
        }
        for kappa in [1.0 + 1e-6, 1.01, 2.0, 9.5, 100.0] {
            let (m, m1) = parameter_of_ellipticity(kappa);
            let f = curvature_difference_of(m, m1);
            let back = ellipticity(f).unwrap();
            assert!(rel(back, kappa) < 1e-12, "κ = {kappa}: back {back}");
        }
        assert_eq!(ellipticity(0.0).unwrap(), 1.0);
        assert_eq!(dimensionless_deflection(1.0), 1.0);
        assert!(ellipticity(1.0).is_err());
        assert!(ellipticity(f64::NAN).is_err());
        assert_eq!(ellipticity(-0.5).unwrap(), ellipticity(0.5).unwrap());
    }

    #[test]
    fn stiffness_skf_98205_against_mpmath() {
        // mpmath, 30 digits, same formulas.
        let g = ContactGeometry::skf_98205();
        let i = g.inner_contact().unwrap();
        let o = g.outer_contact().unwrap();
        assert!(rel(i.curvature_sum, 307.2199411358599) < 1e-14);
        assert!(rel(i.curvature_difference, 0.9424403705893948) < 1e-14);
        assert!(rel(i.ellipticity, 9.531857921421663) < 1e-12);
        assert!(rel(i.dimensionless_deflection, 0.5971218163816585) < 1e-12);
        assert!(rel(i.stiffness, 26517561386.694756) < 1e-12);
        assert!(rel(o.curvature_sum, 195.80833551530608) < 1e-14);
        assert!(rel(o.curvature_difference, 0.9096899224806201) < 1e-14);
        assert!(rel(o.ellipticity, 7.170029800589983) < 1e-12);
        assert!(rel(o.dimensionless_deflection, 0.6641410056989061) < 1e-12);
        assert!(rel(o.stiffness, 28316962186.007412) < 1e-12);
    }
}
