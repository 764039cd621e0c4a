//! The clearance joint's force laws against references independent of the code:
//! closed forms of the Hertz impact and of the short bearing, a fixed-step RK4 of
//! the impact's scalar equation, and a brute-force quadrature of the film pressure.

use std::f64::consts::PI;

use super::*;
use crate::bearing::{DampingModel, LawSetup, RestitutionLaw};

/// The example joint: R_j = 9.5 mm, c = 0.5 mm (radial), L = 40 mm.
const GEOMETRY: JournalGeometry = JournalGeometry {
    radius: 9.5e-3,
    clearance: 0.5e-3,
    length: 40e-3,
};

const STEEL: Material = Material {
    youngs_modulus: 207e9,
    poisson_ratio: 0.3,
};

const NO_FRICTION: Friction = Friction {
    coefficient: 0.0,
    stick_speed: 0.0,
    slip_speed: 0.0,
};

/// Steel on steel at [`GEOMETRY`]: `K = (4/3) E/(2(1 − ν²)) √(R_b R_j/c)`, with
/// `R_b R_j/c` = 10 mm × 9.5 mm / 0.5 mm = 0.19 m, written out.
const STIFFNESS: f64 = 4.0 / 3.0 * 207e9 / (2.0 * 0.91) * 0.435_889_894_354_067_4;

fn dry(model: DampingModel, damping: f64, friction: Friction) -> DryContact {
    DryContact::new(GEOMETRY, STIFFNESS, LawSetup::of(model, damping), friction)
}

fn restitution(law: RestitutionLaw, e: f64) -> DampingModel {
    DampingModel::Restitution {
        law,
        restitution: e,
    }
}

/// Motion at eccentricity `r` (m) along the angle `angle`, moving at `v` (global).
fn at(r: f64, angle: f64, v: [f64; 2], journal_rate: f64, bushing_rate: f64) -> JointMotion {
    JointMotion {
        e: [r * angle.cos(), r * angle.sin()],
        v,
        journal_rate,
        bushing_rate,
    }
}

/// The stiffness formula with its inputs, and symmetric in the two materials.
#[test]
fn journal_stiffness_is_the_conforming_cylinders_hertz_constant() {
    let k = cylinder_stiffness(&GEOMETRY, STEEL, STEEL);
    println!("K = {k:.6e} N/m^1.5");
    assert!((k - STIFFNESS).abs() < 1e-14 * STIFFNESS);
    assert!((k - 6.6102e10).abs() < 1e-4 * k);
    let bronze = Material {
        youngs_modulus: 110e9,
        poisson_ratio: 0.34,
    };
    let (a, b) = (
        cylinder_stiffness(&GEOMETRY, STEEL, bronze),
        cylinder_stiffness(&GEOMETRY, bronze, STEEL),
    );
    assert!(a < k && (a - b).abs() < 1e-15 * a);
}

/// Contact-time scale `(m²/(K² v0))^{1/5}` (s) and the undamped largest penetration
/// `(5 m v0²/(4K))^{2/5}` (m).
fn scales(m: f64, v0: f64) -> (f64, f64) {
    let k = STIFFNESS;
    (
        (m * m / (k * k * v0)).powf(0.2),
        (1.25 * m * v0 * v0 / k).powf(0.4),
    )
}

/// One RK4 step of `ẏ = f(y)`.
fn rk4<const N: usize>(y: [f64; N], h: f64, f: impl Fn(&[f64; N]) -> [f64; N]) -> [f64; N] {
    let add = |a: &[f64; N], k: &[f64; N], s: f64| std::array::from_fn(|i| a[i] + s * k[i]);
    let k1 = f(&y);
    let k2 = f(&add(&y, &k1, 0.5 * h));
    let k3 = f(&add(&y, &k2, 0.5 * h));
    let k4 = f(&add(&y, &k3, h));
    std::array::from_fn(|i| y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// A free journal of mass `m` (the bushing fixed) flying at `v0` along the angle 0.7
/// rad into the wall from 1 % of δ_max away, RK4 with `tc/10⁵` steps, the onset
/// latched at step ends. Returns the largest penetration (m) and the restitution
/// `−δ̇_out/v0` once the journal has left the wall.
fn journal_impact(joint: &mut DryContact, m: f64, v0: f64) -> (f64, f64) {
    let (tc, dmax) = scales(m, v0);
    let (angle, h) = (0.7f64, tc / 1e5);
    let (n, c) = ([angle.cos(), angle.sin()], GEOMETRY.clearance);
    let r0 = c - 0.01 * dmax;
    let mut y = [r0 * n[0], r0 * n[1], v0 * n[0], v0 * n[1]];
    let motion = |y: &[f64; 4]| JointMotion {
        e: [y[0], y[1]],
        v: [y[2], y[3]],
        ..JointMotion::default()
    };
    let mut deepest = f64::NEG_INFINITY;
    let mut touched = false;
    loop {
        let f = |y: &[f64; 4]| {
            let force = joint.force(&motion(y)).force;
            [y[2], y[3], force[0] / m, force[1] / m]
        };
        y = rk4(y, h, f);
        joint.latch(&motion(&y));
        let k = GEOMETRY.contact(&motion(&y));
        deepest = deepest.max(k.penetration);
        touched |= k.penetration > 0.0;
        if touched && k.penetration < 0.0 {
            return (deepest, -k.approach / v0);
        }
    }
}

/// The independent reference: `m ẍ = −max(K x^{3/2} (1 + χ ẋ/v0), 0)` from `(0, v0)`
/// by RK4 with `tc/4·10⁵` steps until `x < 0`, the exit speed interpolated linearly
/// in `x`; returns `−ẋ_out/v0`.
fn reference_restitution(chi: f64, m: f64, v0: f64) -> f64 {
    let (tc, _) = scales(m, v0);
    let h = tc / 4e5;
    let f = |y: &[f64; 2]| {
        let x = y[0].max(0.0);
        let force = (STIFFNESS * x * x.sqrt() * (1.0 + chi / v0 * y[1])).max(0.0);
        [y[1], -force / m]
    };
    let mut y = [0.0, v0];
    loop {
        let next = rk4(y, h, f);
        if next[0] < 0.0 && y[1] < 0.0 {
            let w = y[0] / (y[0] - next[0]);
            return -(y[1] + w * (next[1] - y[1])) / v0;
        }
        y = next;
    }
}

/// Undamped, the journal reaches the Hertz penetration `(5 m v0²/(4K))^{2/5}` to
/// 1e-6 and leaves at its impact speed (to 1e-6); with the restitution laws its
/// exit speed is the independent RK4's to 1e-6, Flores's law within 0.035 of its
/// nominal `e` (the tolerance of tests/contact_laws.rs), Lankarani–Nikravesh's the
/// 0.847 of docs/model.md §2.5's table at `e` = 0.8; at two masses and speeds.
#[test]
fn journal_impact_matches_hertz_and_the_restitution_laws() {
    for (m, v0) in [(0.21, 0.5), (0.14, 2.0)] {
        let (_, dmax) = scales(m, v0);
        let mut joint = dry(DampingModel::CompressionOnly, 0.0, NO_FRICTION);
        let (deepest, e_eff) = journal_impact(&mut joint, m, v0);
        let rel = (deepest - dmax).abs() / dmax;
        println!(
            "undamped m {m} v0 {v0}: δ_max {deepest:.6e} vs {dmax:.6e} ({rel:.1e}), e {e_eff:.9}"
        );
        assert!(rel < 1e-6 && (e_eff - 1.0).abs() < 1e-6);
        for (law, e) in [
            (RestitutionLaw::LankaraniNikravesh, 0.8),
            (RestitutionLaw::Flores, 0.8),
            (RestitutionLaw::Flores, 0.5),
            (RestitutionLaw::HuntCrossley, 0.9),
        ] {
            let mut joint = dry(restitution(law, e), 0.0, NO_FRICTION);
            let (_, e_eff) = journal_impact(&mut joint, m, v0);
            let reference = reference_restitution(law.chi(e), m, v0);
            println!(
                "{} e {e}: e_eff {e_eff:.9}, reference {reference:.9}",
                law.name()
            );
            assert!((e_eff - reference).abs() < 1e-6);
            match law {
                RestitutionLaw::Flores => assert!((e_eff - e).abs() < 0.035),
                RestitutionLaw::LankaraniNikravesh => assert!((e_eff - 0.847).abs() < 5e-4),
                _ => assert!(e_eff > e && e_eff < 1.0),
            }
        }
    }
}

const FRICTION: Friction = Friction {
    coefficient: 0.01,
    stick_speed: 1e-4,
    slip_speed: 1e-3,
};

/// A journal pressed 2 µm into the wall and spinning while the bushing turns the
/// other way: integrated over 0.3 s (trapezoids over 3000 steps), the friction
/// dissipation rate gives `μ F_n |v_t| t` with `F_n = K δ^{3/2}` and
/// `v_t = R_j ω_j − R_b ω_b` (to 1e-12), and the forces and moments the joint applies
/// to both bodies take from the motion exactly the dissipated power (to 1e-12).
#[test]
fn sliding_journal_dissipates_mu_fn_vt() {
    let joint = dry(DampingModel::CompressionOnly, 0.0, FRICTION);
    let (delta, omega_j, omega_b) = (2e-6, 30.0, -4.0);
    let motion = at(GEOMETRY.clearance + delta, 2.0, [0.0; 2], omega_j, omega_b);
    let fn_ = STIFFNESS * delta.powf(1.5);
    let vt = GEOMETRY.radius * omega_j - (GEOMETRY.radius + GEOMETRY.clearance) * omega_b;
    let (t_end, steps) = (0.3, 3000);
    let h = t_end / steps as f64;
    let dissipated: f64 = (0..steps)
        .map(|_| 0.5 * h * 2.0 * joint.force(&motion).friction_dissipation)
        .sum();
    let expected = FRICTION.coefficient * fn_ * vt.abs() * t_end;
    println!("friction dissipated {dissipated:.9e} J, μ F_n |v_t| t = {expected:.9e} J");
    assert!((dissipated - expected).abs() < 1e-12 * expected);
    let f = joint.force(&motion);
    let power = f.journal_moment * omega_j + f.bushing_moment * omega_b;
    assert!((power + f.friction_dissipation).abs() < 1e-12 * f.friction_dissipation);
    assert!((f.friction + FRICTION.coefficient * fn_ * vt.signum()).abs() < 1e-12 * fn_);
}

/// No friction up to the stick speed, the linear ramp between, full friction from
/// the slip speed on, opposing the slip (values written out).
#[test]
fn friction_ramps_between_stick_and_slip_speed() {
    let normal = 50.0;
    for (slip, expected) in [
        (0.0, 0.0),
        (5e-5, 0.0),
        (-1e-4, 0.0),
        (2.8e-4, -0.01 * 50.0 * 0.2),
        (-5.5e-4, 0.01 * 50.0 * 0.5),
        (1e-3, -0.5),
        (-0.3, 0.5),
    ] {
        let f = FRICTION.force(normal, slip);
        println!("v_t {slip:e} m/s: F_t {f:.6} N");
        assert!((f - expected).abs() < 1e-12, "{slip}: {f} vs {expected}");
    }
}

/// At oblique states in contact (both bodies turning, the journal orbiting and
/// approaching or leaving), every law: the power of the joint's force and moments on
/// both bodies is `−K δ^{3/2} δ̇` minus the damping and friction dissipation (to
/// 1e-12 of the largest term), and both dissipation rates are ≥ 0.
#[test]
fn joint_power_is_elastic_minus_dissipation() {
    let models = [
        (DampingModel::CompressionOnly, 300.0),
        (DampingModel::TwoSided, 300.0),
        (DampingModel::HuntCrossleyAlpha { alpha: 0.4 }, 0.0),
    ];
    for (model, damping) in models {
        let joint = dry(model, damping, FRICTION);
        for (angle, v, wj, wb) in [
            (0.3, [0.02, -0.05], 12.0, 3.0),
            (2.5, [-0.01, 0.03], -40.0, 7.0),
            (-1.2, [0.0, 0.0], 0.0, 0.0),
        ] {
            let m = at(GEOMETRY.clearance + 3e-6, angle, v, wj, wb);
            let k = GEOMETRY.contact(&m);
            let f = joint.force(&m);
            let power = f.force[0] * m.v[0]
                + f.force[1] * m.v[1]
                + f.journal_moment * wj
                + f.bushing_moment * wb;
            let expected = -f.elastic * k.approach - f.damping_dissipation - f.friction_dissipation;
            let scale = (f.elastic * k.approach).abs() + f.friction_dissipation + 1e-30;
            assert!((power - expected).abs() < 1e-12 * scale, "{model:?}");
            assert!(f.damping_dissipation >= 0.0 && f.friction_dissipation >= 0.0);
        }
    }
}

/// Zero force wherever `δ ≤ 0` (the centre included); at `δ → 0⁺` the force of the
/// undamped and hysteresis laws tends to 0 like `K δ^{3/2}`, while compression-only
/// and two-sided damping start at `C δ̇` on an approach (their jump, docs/model.md
/// §2.5).
#[test]
fn dry_force_vanishes_out_of_contact_and_is_continuous_at_the_wall() {
    let v = [0.3, 0.1];
    let models = [
        (DampingModel::CompressionOnly, 0.0),
        (DampingModel::HuntCrossleyAlpha { alpha: 0.5 }, 0.0),
        (restitution(RestitutionLaw::LankaraniNikravesh, 0.8), 0.0),
        (restitution(RestitutionLaw::Flores, 0.6), 0.0),
    ];
    for (model, damping) in models {
        let mut joint = dry(model, damping, FRICTION);
        for r in [0.0, 0.3e-3, GEOMETRY.clearance * (1.0 - 1e-12)] {
            assert_eq!(joint.force(&at(r, 0.4, v, 5.0, 0.0)), JointForce::default());
        }
        let touching = at(GEOMETRY.clearance + 1e-12, 0.4, v, 5.0, 0.0);
        joint.latch(&touching);
        let f = joint.force(&touching);
        // K δ^{3/2} (1 + c δ̇) with c δ̇ ≤ χ ≈ 1.07 here.
        let bound = 3.0 * STIFFNESS * 1e-18;
        println!(
            "{model:?}: |F| at δ = 1e-12 m: {:.3e} N",
            f.force[0].hypot(f.force[1])
        );
        assert!(f.normal <= bound && f.force[0].hypot(f.force[1]) <= 1.01 * bound);
    }
    for model in [DampingModel::CompressionOnly, DampingModel::TwoSided] {
        let joint = dry(model, 300.0, NO_FRICTION);
        let touching = at(GEOMETRY.clearance + 1e-12, 0.0, [0.3, 0.1], 0.0, 0.0);
        let f = joint.force(&touching);
        assert!((f.normal - 300.0 * 0.3).abs() < 1e-6);
    }
}

fn film() -> Film {
    Film::new(GEOMETRY, 0.4, FILM_LIMIT)
}

/// `μ_v R L³/c²` (N s) of [`film`].
fn film_scale() -> f64 {
    0.4 * GEOMETRY.radius * GEOMETRY.length.powi(3) / GEOMETRY.clearance.powi(2)
}

/// The short-bearing load capacity at eccentricity ratio `eps` and journal speed
/// `omega` (closed form, half-Sommerfeld):
/// `W = (μ_v ω R L³/(4c²)) ε/(1−ε²)² √(π²(1−ε²) + 16ε²)`.
fn load_capacity(eps: f64, omega: f64) -> f64 {
    let w = 1.0 - eps * eps;
    film_scale() * omega / 4.0 * eps / (w * w) * (PI * PI * w + 16.0 * eps * eps).sqrt()
}

/// The equilibrium eccentricity under the external load `load` (N, on the journal)
/// by Newton's method on `F_film(e) + W = 0` with a central-difference Jacobian,
/// each step cut back to stay inside 0.99 c; from `e = c/2` along the load.
fn equilibrium(film: &Film, load: [f64; 2], journal_rate: f64, bushing_rate: f64) -> [f64; 2] {
    let c = GEOMETRY.clearance;
    let w = load[0].hypot(load[1]);
    let residual = |e: [f64; 2]| {
        let m = JointMotion {
            e,
            v: [0.0; 2],
            journal_rate,
            bushing_rate,
        };
        let f = film.force(&m).force;
        [f[0] + load[0], f[1] + load[1]]
    };
    let mut e = [0.5 * c * load[0] / w, 0.5 * c * load[1] / w];
    for _ in 0..100 {
        let r = residual(e);
        if r[0].hypot(r[1]) < 1e-13 * w {
            return e;
        }
        let d = 1e-7 * c;
        let col = |i: usize| {
            let (mut a, mut b) = (e, e);
            a[i] += d;
            b[i] -= d;
            let (ra, rb) = (residual(a), residual(b));
            [(ra[0] - rb[0]) / (2.0 * d), (ra[1] - rb[1]) / (2.0 * d)]
        };
        let (j0, j1) = (col(0), col(1));
        let det = j0[0] * j1[1] - j1[0] * j0[1];
        let mut step = [
            (j1[1] * r[0] - j1[0] * r[1]) / det,
            (j0[0] * r[1] - j0[1] * r[0]) / det,
        ];
        while (e[0] - step[0]).hypot(e[1] - step[1]) > 0.99 * c {
            step = [0.5 * step[0], 0.5 * step[1]];
        }
        e = [e[0] - step[0], e[1] - step[1]];
    }
    panic!("no equilibrium for the load {load:?}");
}

/// Under a steady load at a steady speed the journal rests at the short bearing's
/// eccentricity ratio (its load capacity inverted, to 1e-9) and attitude angle
/// `tan φ = π √(1−ε²)/(4ε)` measured from the load line in the direction of
/// rotation (to 1e-9 rad), for ε from 0.1 to 0.9, the load in two directions, the
/// journal or the bushing turning (only `ω̄ = (ω_j + ω_b)/2` counts), and turning
/// clockwise (the attitude angle then counts clockwise).
#[test]
fn steady_load_settles_at_the_short_bearing_eccentricity_and_attitude() {
    let film = film();
    let omega = 2.0 * PI * 5000.0 / 60.0;
    for eps in [0.1, 0.3, 0.5, 0.7, 0.8, 0.9] {
        let w = load_capacity(eps, omega);
        for (dir, wj, wb) in [
            (-PI / 2.0, omega, 0.0),
            (0.4, omega, 0.0),
            (-PI / 2.0, 0.0, omega),
            (-PI / 2.0, -omega, 0.0),
        ] {
            let load = [w * dir.cos(), w * dir.sin()];
            let e = equilibrium(&film, load, wj, wb);
            let ratio = e[0].hypot(e[1]) / GEOMETRY.clearance;
            // From the load direction to e, counter-clockwise, then in the sense of ω̄.
            let unit = [dir.cos(), dir.sin()];
            let ccw = (unit[0] * e[1] - unit[1] * e[0]).atan2(unit[0] * e[0] + unit[1] * e[1]);
            let attitude = ccw * (wj + wb).signum();
            let expected = (PI * (1.0 - eps * eps).sqrt() / (4.0 * eps)).atan();
            println!(
                "ε {eps}: W {w:.3} N along {dir:.2} rad, ω_j {wj:.1} ω_b {wb:.1}: ε off by \
                 {:.1e}, φ {:.6}° off by {:.1e} rad",
                ratio - eps,
                attitude.to_degrees(),
                attitude - expected
            );
            assert!((ratio - eps).abs() < 1e-9);
            assert!((attitude - expected).abs() < 1e-9);
        }
    }
}

/// Pure squeeze (no rotation): the radial force on a journal at eccentricity ratio
/// ε moving along the line of centres at `ε̇` is the short bearing's squeeze closed
/// form over the half film around the thinning gap,
/// `F_r = −(μ_v R L³ ε̇/c²) [(1+2ε²)(π/2 ± asin ε) ± 3ε√(1−ε²)]/(1−ε²)^{5/2}`
/// (+ approaching, − leaving), with no tangential force (to 1e-12); at the centre
/// the film is the isotropic damper `F = −(π μ_v R L³/(2c³)) ė` for any rotation.
#[test]
fn squeeze_film_matches_the_closed_form() {
    let film = film();
    let c = GEOMETRY.clearance;
    for eps in [0.1, 0.5, 0.8, 0.9] {
        for rate in [30.0, -30.0] {
            let angle = 1.1f64;
            let n = [angle.cos(), angle.sin()];
            let m = at(eps * c, angle, [rate * c * n[0], rate * c * n[1]], 0.0, 0.0);
            let f = film.force(&m).force;
            let radial = f[0] * n[0] + f[1] * n[1];
            let tangential = -f[0] * n[1] + f[1] * n[0];
            let s = rate.signum();
            let root = (1.0 - eps * eps).sqrt();
            let bracket =
                (1.0 + 2.0 * eps * eps) * (PI / 2.0 + s * eps.asin()) + s * 3.0 * eps * root;
            let expected = -film_scale() * rate * bracket / root.powi(5);
            println!("ε {eps} ε̇ {rate}: F_r {radial:.9e} N, closed form {expected:.9e} N");
            assert!((radial - expected).abs() < 1e-12 * expected.abs());
            assert!(tangential.abs() < 1e-12 * expected.abs());
        }
    }
    for wj in [0.0, 300.0] {
        let v = [0.02, -0.05];
        let f = film.force(&at(0.0, 0.0, v, wj, 0.0)).force;
        let k = PI * film_scale() / (2.0 * c);
        assert!((f[0] + k * v[0]).abs() < 1e-12 * k * 0.05);
        assert!((f[1] + k * v[1]).abs() < 1e-12 * k * 0.05);
    }
}

/// The film force against a brute-force quadrature of the short-bearing pressure
/// written here from Reynolds's equation: the pressure integrated over the length,
/// `−μ_v L³ G(θ)/(c² (1 + ε cos θ)³)`, kept where positive, over 400 000 midpoints of
/// the whole circle (so the cavitation boundaries are found by the sign, not by
/// `θ₁`), at states mixing wedge, whirl and squeeze; to 1e-7 of the force.
#[test]
fn film_force_matches_a_quadrature_of_the_pressure() {
    let film = film();
    let (c, big_r, l) = (GEOMETRY.clearance, GEOMETRY.radius, GEOMETRY.length);
    for (eps, angle, v, wj, wb) in [
        (0.3, 0.2, [0.01, 0.02], 500.0, 0.0),
        (0.6, 2.9, [-0.03, 0.01], 200.0, -60.0),
        (0.85, -1.3, [0.002, -0.004], -300.0, 40.0),
        (0.9, 0.7, [0.0, 0.0], 0.0, 523.0),
        (0.5, 4.0, [0.05, 0.05], 0.0, 0.0),
    ] {
        let m = at(eps * c, angle, v, wj, wb);
        let n = [f64::cos(angle), f64::sin(angle)];
        let t = [-n[1], n[0]];
        let eps_dot = (v[0] * n[0] + v[1] * n[1]) / c;
        let phi_dot = (v[0] * t[0] + v[1] * t[1]) / (eps * c);
        let mean = 0.5 * (wj + wb);
        let points = 400_000;
        let h = 2.0 * PI / points as f64;
        let (mut fr, mut ft) = (0.0, 0.0);
        for i in 0..points {
            let th = (i as f64 + 0.5) * h;
            let g = -eps * (mean - phi_dot) * th.sin() + eps_dot * th.cos();
            let p = (-0.4 * l.powi(3) * g / (c * c * (1.0 + eps * th.cos()).powi(3))).max(0.0);
            fr += p * th.cos() * big_r * h;
            ft += p * th.sin() * big_r * h;
        }
        let expected = [fr * n[0] + ft * t[0], fr * n[1] + ft * t[1]];
        let f = film.force(&m).force;
        let size = expected[0].hypot(expected[1]);
        let err = (f[0] - expected[0]).hypot(f[1] - expected[1]) / size;
        println!("ε {eps}: |F| {size:.6e} N, relative difference {err:.1e}");
        assert!(err < 1e-7);
    }
}

/// The lubricated joint's force has no jump: across the film limit (the film held at
/// `ε_f`) and at the wall, where the dry contact (Lankarani–Nikravesh) adds a force
/// that starts at 0; the force and the film power change by less than 1e-6 of
/// their size over 1e-12 m.
#[test]
fn lubricated_force_is_continuous_at_the_film_limit_and_the_wall() {
    let law = LawSetup::of(restitution(RestitutionLaw::LankaraniNikravesh, 0.8), 0.0);
    let dry = DryContact::new(GEOMETRY, STIFFNESS, law, FRICTION);
    let mut joint = LubricatedJoint::new(film(), dry);
    let c = GEOMETRY.clearance;
    let v = [0.004, 0.01];
    for r in [FILM_LIMIT * c, c] {
        let below = at(r - 1e-12, 0.9, v, 300.0, 0.0);
        let above = at(r + 1e-12, 0.9, v, 300.0, 0.0);
        joint.latch(&below);
        let a = joint.force(&below);
        joint.latch(&above);
        let b = joint.force(&above);
        let size = a.force[0].hypot(a.force[1]);
        let jump = (a.force[0] - b.force[0]).hypot(a.force[1] - b.force[1]);
        println!("at |e| = {r:.6e} m: |F| {size:.6e} N, change {jump:.1e} N");
        assert!(jump < 1e-6 * size);
        assert!((a.film_power - b.film_power).abs() < 1e-6 * a.film_power.abs());
    }
    // Past the limit the film force is that of ε_f; the dry force comes on top.
    let deep = at(c + 1e-6, 0.9, v, 300.0, 0.0);
    let film_only = film().force(&deep).force;
    let total = joint.force(&deep);
    assert!(total.normal > 0.0);
    let n = [f64::cos(0.9), f64::sin(0.9)];
    let t = [-n[1], n[0]];
    for i in 0..2 {
        let dry_part = -total.normal * n[i] + total.friction * t[i];
        assert!((total.force[i] - dry_part - film_only[i]).abs() < 1e-9 * total.normal);
    }
    // Moving along the line of centres (no whirl), the held film is the film at ε_f.
    let vr = [0.01 * n[0], 0.01 * n[1]];
    let held = film().force(&at(FILM_LIMIT * c, 0.9, vr, 300.0, 0.0)).force;
    let past = film().force(&at(c + 1e-6, 0.9, vr, 300.0, 0.0)).force;
    let size = held[0].hypot(held[1]);
    assert!((held[0] - past[0]).hypot(held[1] - past[1]) < 1e-12 * size);
}
