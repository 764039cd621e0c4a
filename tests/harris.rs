//! Harris's ball–raceway stiffness (docs/model.md §2) against the paper's value, the
//! Brewe–Hamrock approximations, Hertz theory in Johnson's form, and its limits.

use studyrun::bearing::stiffness::{
    dimensionless_deflection, elliptic_ke, ellipticity, ContactGeometry,
};

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

#[test]
fn skf_98205_total_stiffness_matches_paper() {
    let g = ContactGeometry::skf_98205();
    let k = g.harris_stiffness().unwrap();
    let i = g.inner_contact().unwrap();
    let o = g.outer_contact().unwrap();
    println!(
        "inner: sum rho = {:.6} 1/m, F = {:.6}, kappa = {:.6}, delta* = {:.6}, K_i = {:.6e} N/m^1.5",
        i.curvature_sum, i.curvature_difference, i.ellipticity, i.dimensionless_deflection, k.inner
    );
    println!(
        "outer: sum rho = {:.6} 1/m, F = {:.6}, kappa = {:.6}, delta* = {:.6}, K_o = {:.6e} N/m^1.5",
        o.curvature_sum, o.curvature_difference, o.ellipticity, o.dimensionless_deflection, k.outer
    );
    println!(
        "total K = {:.6e} N/m^1.5 (paper 9.57e9, {:+.2} %)",
        k.total,
        100.0 * (k.total / 9.57e9 - 1.0)
    );
    assert_eq!(i.stiffness, k.inner);
    assert_eq!(o.stiffness, k.outer);
    assert!(rel(k.total, 9.57e9) < 0.02, "K = {:e}", k.total);
    // docs/model.md: "≈ 9.7e9, within 1.5 % of the paper's 9.57e9".
    assert!(rel(k.total, 9.7e9) < 0.01, "K = {:e}", k.total);
    assert!(rel(k.total, 9.57e9) < 0.015, "K = {:e}", k.total);
    // Series of two springs Q = K δ^{3/2}: the deflections add at equal load.
    let q = 500.0;
    let d = |kk: f64| (q / kk).powf(2.0 / 3.0);
    assert!(rel(d(k.inner) + d(k.outer), d(k.total)) < 1e-14);
    assert!(k.total < k.inner.min(k.outer));
}

/// Principal radii of curvature of the ball–race gap, computed from the geometry
/// directly (not through Harris's γ formulas): `(1/R_rolling, 1/R_transverse)`.
fn relative_curvatures(g: &ContactGeometry, inner: bool) -> (f64, f64) {
    let r_ball = g.ball_diameter / 2.0;
    let (race_rolling, groove) = if inner {
        // Inner raceway: convex, radius (d_m − D)/2 in the rolling plane.
        (
            2.0 / (g.pitch_diameter - g.ball_diameter),
            g.inner_conformity * g.ball_diameter,
        )
    } else {
        // Outer raceway: concave, radius (d_m + D)/2.
        (
            -2.0 / (g.pitch_diameter + g.ball_diameter),
            g.outer_conformity * g.ball_diameter,
        )
    };
    (1.0 / r_ball + race_rolling, 1.0 / r_ball - 1.0 / groove)
}

#[test]
fn curvatures_and_hertz_solution_agree_with_johnson() {
    // Hertz's solution for an elliptical contact in Johnson's form (Contact
    // Mechanics §3.5): with e² = m = 1 − b²/a², p0 = 3Q/(2πab),
    //   A = (p0/E*) b/(e²a²) [K − E],  B = (p0/E*) b/(e²a²) [(a²/b²)E − K],
    //   δ = (p0 b/E*) K,   1/E* = 2(1 − ν²)/E (same material).
    for geometry in [
        ContactGeometry::skf_98205(),
        ContactGeometry {
            inner_conformity: 0.505,
            outer_conformity: 0.53,
            ..ContactGeometry::skf_98205()
        },
    ] {
        let e_star = geometry.youngs_modulus / (2.0 * (1.0 - geometry.poisson_ratio.powi(2)));
        for inner in [true, false] {
            let c = if inner {
                geometry.inner_contact().unwrap()
            } else {
                geometry.outer_contact().unwrap()
            };
            let (rho_x, rho_y) = relative_curvatures(&geometry, inner);
            // A = smaller half-curvature (major axis a along it), B = larger.
            let (a_half, b_half) = (0.5 * rho_x.min(rho_y), 0.5 * rho_x.max(rho_y));
            assert!(rel(c.curvature_sum, 2.0 * (a_half + b_half)) < 1e-14);
            assert!(
                rel(
                    c.curvature_difference,
                    (b_half - a_half) / (b_half + a_half)
                ) < 1e-14
            );

            let kappa = c.ellipticity;
            let (m_k, m_e) = elliptic_ke(1.0 - 1.0 / (kappa * kappa));
            // B/A from Hertz's two equations, with the computed κ.
            let ratio = (kappa * kappa * m_e - m_k) / (m_k - m_e);
            assert!(
                rel(ratio, b_half / a_half) < 1e-11,
                "B/A {ratio} vs {}",
                b_half / a_half
            );

            // Load Q → semi-axis b (from A + B = p0 E/(E* b)) → δ; must satisfy
            // Q = K_c δ^{3/2} with Harris's K_c.
            for q in [10.0, 1000.0, 1e5] {
                let b = (3.0 * q * m_e / (std::f64::consts::PI * kappa * e_star * c.curvature_sum))
                    .cbrt();
                let a = kappa * b;
                let p0 = 3.0 * q / (2.0 * std::f64::consts::PI * a * b);
                let delta = p0 * b * m_k / e_star;
                // The A equation, independently.
                let e2 = 1.0 - 1.0 / (kappa * kappa);
                let a_check = p0 / e_star * b / (e2 * a * a) * (m_k - m_e);
                assert!(rel(a_check, a_half) < 1e-11);
                let q_harris = c.stiffness * delta.powf(1.5);
                assert!(rel(q_harris, q) < 1e-12, "Q {q_harris} vs {q}");
            }
        }
    }
}

#[test]
fn ellipticity_and_deflection_match_brewe_hamrock() {
    // Brewe & Hamrock (1977) / Hamrock & Brewe (1983) curve fits for α = R_y/R_x:
    // κ ≈ 1.0339 α^0.6360, E ≈ 1.0003 + 0.5968/α, K ≈ 1.5277 + 0.6023 ln α,
    // curve fits good to a few per cent. Checked with mpmath, the κ fit is within 3 %
    // up to α ≈ 45 and drifts beyond (3.1 % at α = 50, 6.3 % at 100), so the range
    // here stops at 40; the SKF 98205 contacts have α ≈ 21 (outer) and 34 (inner).
    let mut alphas = vec![1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 40.0];
    let g = ContactGeometry::skf_98205();
    for inner in [true, false] {
        let (rx, ry) = relative_curvatures(&g, inner);
        alphas.push(rx.max(ry) / rx.min(ry));
    }
    for alpha in alphas {
        let f = (alpha - 1.0) / (alpha + 1.0);
        let kappa = ellipticity(f).unwrap();
        let (k, e) = elliptic_ke(1.0 - 1.0 / (kappa * kappa));
        let kappa_bh = 1.0339 * alpha.powf(0.6360);
        let e_bh = 1.0003 + 0.5968 / alpha;
        let k_bh = 1.5277 + 0.6023 * alpha.ln();
        let ds = dimensionless_deflection(kappa);
        let ds_bh = 2.0 * k_bh / std::f64::consts::PI
            * (std::f64::consts::PI / (2.0 * kappa_bh * kappa_bh * e_bh)).cbrt();
        println!(
            "alpha {alpha:8.3}: kappa {kappa:.5} (BH {kappa_bh:.5}), delta* {ds:.5} (BH {ds_bh:.5})"
        );
        assert!(
            rel(kappa, kappa_bh) < 0.03,
            "alpha {alpha}: κ {kappa} vs {kappa_bh}"
        );
        assert!(rel(e, e_bh) < 0.03, "alpha {alpha}: E {e} vs {e_bh}");
        assert!(rel(k, k_bh) < 0.03, "alpha {alpha}: K {k} vs {k_bh}");
        assert!(rel(ds, ds_bh) < 0.03, "alpha {alpha}: δ* {ds} vs {ds_bh}");
    }
}

#[test]
fn closer_conformity_is_stiffer() {
    let with = |f: f64| ContactGeometry {
        inner_conformity: f,
        outer_conformity: f,
        ..ContactGeometry::skf_98205()
    };
    let fs = [0.505, 0.51, 0.515, 0.52, 0.525, 0.53];
    let ks: Vec<_> = fs
        .iter()
        .map(|&f| with(f).harris_stiffness().unwrap())
        .collect();
    for (w, f) in ks.windows(2).zip(fs.windows(2)) {
        assert!(
            w[0].total > w[1].total,
            "f {} → {}: {:e} !> {:e}",
            f[0],
            f[1],
            w[0].total,
            w[1].total
        );
        assert!(w[0].inner > w[1].inner && w[0].outer > w[1].outer);
    }
    let first = ks.first().unwrap().total;
    let last = ks.last().unwrap().total;
    println!("K(f = 0.505) = {first:.4e}, K(f = 0.53) = {last:.4e}");
    // Closer conformity: longer, narrower ellipse.
    assert!(
        with(0.505).inner_contact().unwrap().ellipticity
            > with(0.53).inner_contact().unwrap().ellipticity
    );
}

#[test]
fn equal_curvatures_give_a_circular_contact() {
    assert_eq!(ellipticity(0.0).unwrap(), 1.0);
    assert_eq!(dimensionless_deflection(1.0), 1.0);
    // Near the limit F(ρ) = 3m/8 + O(m²), m = 1 − 1/κ², so κ − 1 ≈ 4F/3.
    for f in [1e-12, 1e-9, 1e-6, 1e-4] {
        let kappa = ellipticity(f).unwrap();
        assert!(kappa > 1.0);
        // Tolerance: the next order, plus κ's own rounding (one ulp of 1 over κ − 1).
        let tol = 3.0 * f + 2.0 * f64::EPSILON / (4.0 * f / 3.0);
        assert!(
            rel(kappa - 1.0, 4.0 * f / 3.0) < tol,
            "F {f}: κ − 1 = {}",
            kappa - 1.0
        );
        let ds = dimensionless_deflection(kappa);
        assert!((ds - 1.0).abs() < 10.0 * f, "F {f}: δ* = {ds}");
    }
    // δ* falls monotonically as the ellipse elongates.
    let mut prev = 1.0;
    for f in [0.1, 0.3, 0.5, 0.7, 0.9, 0.95, 0.99] {
        let ds = dimensionless_deflection(ellipticity(f).unwrap());
        assert!(ds < prev);
        prev = ds;
    }
}

#[test]
fn invalid_geometry_is_refused_naming_the_field() {
    let ok = ContactGeometry::skf_98205();
    assert!(ok.validate().is_ok());
    type Edit = fn(&mut ContactGeometry);
    let cases: &[(&str, Edit)] = &[
        ("bearing.ball_diameter", |g| g.ball_diameter = f64::NAN),
        ("bearing.ball_diameter", |g| g.ball_diameter = 0.0),
        ("bearing.ball_diameter", |g| g.ball_diameter = -1e-3),
        ("bearing.pitch_diameter", |g| {
            g.pitch_diameter = f64::INFINITY
        }),
        ("bearing.pitch_diameter", |g| g.pitch_diameter = -0.03),
        ("bearing.pitch_diameter", |g| {
            g.pitch_diameter = g.ball_diameter
        }),
        ("bearing.inner_conformity", |g| g.inner_conformity = 0.5),
        ("bearing.inner_conformity", |g| g.inner_conformity = 0.3),
        ("bearing.inner_conformity", |g| {
            g.inner_conformity = f64::NAN
        }),
        ("bearing.outer_conformity", |g| g.outer_conformity = 0.49),
        ("bearing.outer_conformity", |g| {
            g.outer_conformity = f64::NEG_INFINITY
        }),
        ("bearing.youngs_modulus", |g| g.youngs_modulus = 0.0),
        ("bearing.youngs_modulus", |g| g.youngs_modulus = -2e11),
        ("bearing.youngs_modulus", |g| {
            g.youngs_modulus = f64::INFINITY
        }),
        ("bearing.poisson_ratio", |g| g.poisson_ratio = 0.5),
        ("bearing.poisson_ratio", |g| g.poisson_ratio = -1.0),
        ("bearing.poisson_ratio", |g| g.poisson_ratio = f64::NAN),
    ];
    for (field, edit) in cases {
        let mut g = ok;
        edit(&mut g);
        let err = g.validate().expect_err(field);
        assert_eq!(err.field, *field, "{err}");
        assert!(!err.allowed.is_empty());
        let err2 = g.harris_stiffness().expect_err(field);
        assert_eq!(err2, err);
        println!("{err}");
    }
    // Valid edge: a conformity barely above 0.5 still works and is very stiff.
    let tight = ContactGeometry {
        inner_conformity: 0.5 + 1e-6,
        outer_conformity: 0.5 + 1e-6,
        ..ok
    };
    let k = tight.harris_stiffness().unwrap();
    assert!(k.total.is_finite() && k.total > ok.harris_stiffness().unwrap().total);
    // |F(ρ)| must be below 1.
    assert_eq!(ellipticity(1.0).unwrap_err().field, "curvature_difference");
    assert_eq!(
        ellipticity(f64::NAN).unwrap_err().field,
        "curvature_difference"
    );
}
