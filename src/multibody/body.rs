//! Rigid bodies, body references and planar point kinematics.

/// One moving rigid body. Its coordinates are `(x, y, θ)` of its centre of mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Mass (kg).
    pub mass: f64,
    /// Moment of inertia about the centre of mass (kg m²).
    pub inertia: f64,
}

/// Refers to the ground (fixed, at the origin, θ = 0) or to a moving body by index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BodyRef {
    /// The fixed ground frame.
    Ground,
    /// Moving body `k` (its coordinates are `q[3k..3k+3]`).
    Moving(usize),
}

impl BodyRef {
    /// Index in `q` of this body's first coordinate `x`, or `None` for the ground.
    pub fn offset(self) -> Option<usize> {
        match self {
            BodyRef::Ground => None,
            BodyRef::Moving(k) => Some(3 * k),
        }
    }
}

/// Position, orientation and rates of one body at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Pose {
    /// Centre of mass (m).
    pub r: [f64; 2],
    /// Orientation (rad).
    pub theta: f64,
    /// Velocity of the centre of mass (m/s).
    pub v: [f64; 2],
    /// Angular velocity (rad/s).
    pub omega: f64,
}

impl Pose {
    /// The pose of `body` in the generalised coordinates `q` and velocities `qd`.
    pub fn of(body: BodyRef, q: &[f64], qd: &[f64]) -> Self {
        match body.offset() {
            None => Pose::default(),
            Some(o) => Pose {
                r: [q[o], q[o + 1]],
                theta: q[o + 2],
                v: [qd[o], qd[o + 1]],
                omega: qd[o + 2],
            },
        }
    }

    /// The position and orientation of `body` in `q`, with zero rates.
    pub fn at(body: BodyRef, q: &[f64]) -> Self {
        match body.offset() {
            None => Pose::default(),
            Some(o) => Pose {
                r: [q[o], q[o + 1]],
                theta: q[o + 2],
                ..Pose::default()
            },
        }
    }

    /// A body-fixed vector `s` (body frame, m) expressed in the global frame: `A(θ) s`.
    pub fn rotate(&self, s: [f64; 2]) -> [f64; 2] {
        rotate(self.theta, s)
    }

    /// Global position (m) of the body point at local coordinates `s`.
    pub fn point(&self, s: [f64; 2]) -> [f64; 2] {
        let a = self.rotate(s);
        [self.r[0] + a[0], self.r[1] + a[1]]
    }

    /// Global velocity (m/s) of the body point at local coordinates `s`.
    pub fn point_velocity(&self, s: [f64; 2]) -> [f64; 2] {
        let a = self.rotate(s);
        [self.v[0] - self.omega * a[1], self.v[1] + self.omega * a[0]]
    }
}

/// Rotates `s` by `theta` (rad).
pub fn rotate(theta: f64, s: [f64; 2]) -> [f64; 2] {
    let (sin, cos) = theta.sin_cos();
    [cos * s[0] - sin * s[1], sin * s[0] + cos * s[1]]
}

/// Adds a force `f` (N, global frame) acting at the global point `p` (m) on `body`
/// to the generalised forces: `f` on `(x, y)` and its moment about the centre of
/// mass `(p − r) × f` (N m) on `θ`. Forces on the ground are dropped.
pub fn add_point_force(forces: &mut [f64], body: BodyRef, pose: &Pose, p: [f64; 2], f: [f64; 2]) {
    if let Some(o) = body.offset() {
        forces[o] += f[0];
        forces[o + 1] += f[1];
        forces[o + 2] += (p[0] - pose.r[0]) * f[1] - (p[1] - pose.r[1]) * f[0];
    }
}
