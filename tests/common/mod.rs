//! Closed forms shared by the physics tests.
#![allow(dead_code)]

pub mod hard;

/// Closed-form kinematics of the ideal slider-crank at crank angle `th` (rad) and
/// constant speed `w` (rad/s): positions, velocities and accelerations of the
/// crank, rod and slider centres of mass, and the rod's angle, rate and
/// acceleration. Derived by hand in the test, independent of the engine.
pub struct IdealKinematics {
    /// `[x2, y2, x3, y3, x4]` (m).
    pub pos: [f64; 5],
    /// Their time derivatives (m/s).
    pub vel: [f64; 5],
    /// Their second time derivatives (m/s²).
    pub acc: [f64; 5],
    /// Rod angle θ3 (rad), rate (rad/s), acceleration (rad/s²).
    pub rod: [f64; 3],
}

pub fn ideal_kinematics(r: f64, l: f64, th: f64, w: f64) -> IdealKinematics {
    let (s, c) = th.sin_cos();
    let big_s = (l * l - r * r * s * s).sqrt();
    // d/dθ and d²/dθ² of S = sqrt(l² − r² sin²θ).
    let s1 = -r * r * s * c / big_s;
    let s2 = -r * r * (2.0 * th).cos() / big_s - r.powi(4) * s * s * c * c / big_s.powi(3);
    let th3 = (-r * s / l).asin();
    let th3_1 = -r * c / big_s;
    let th3_2 = r * s / big_s - r.powi(3) * s * c * c / big_s.powi(3);
    let pos = [
        0.5 * r * c,
        0.5 * r * s,
        r * c + 0.5 * big_s,
        0.5 * r * s,
        r * c + big_s,
    ];
    let d1 = [
        -0.5 * r * s,
        0.5 * r * c,
        -r * s + 0.5 * s1,
        0.5 * r * c,
        -r * s + s1,
    ];
    let d2 = [
        -0.5 * r * c,
        -0.5 * r * s,
        -r * c + 0.5 * s2,
        -0.5 * r * s,
        -r * c + s2,
    ];
    IdealKinematics {
        pos,
        vel: d1.map(|d| d * w),
        acc: d2.map(|d| d * w * w),
        rod: [th3, th3_1 * w, th3_2 * w * w],
    }
}
