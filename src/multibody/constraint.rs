//! Kinematic constraints: revolute and translational joints, and a rheonomic driver.
//!
//! Each constraint contributes rows to `Φ(q, t) = 0`. For each row it provides the
//! residual `Φ`, the Jacobian `Φq`, the explicit time derivative `Φt` and the
//! acceleration right-hand side `γ = −(Φq q̇)_q q̇ − 2 Φqt q̇ − Φtt`, so that
//! `Φq q̈ = γ` along any motion that satisfies the constraint.

use super::body::{BodyRef, Pose};
use crate::speed::CrankDrive;

/// One joint or driver.
#[derive(Debug, Clone, PartialEq)]
pub enum Constraint {
    /// Ideal revolute joint (2 rows): the point `s_j` of body `j` coincides with
    /// the point `s_i` of body `i`, `r_j + A_j s_j − r_i − A_i s_i = 0` (m).
    Revolute {
        /// First body (for a bearing location: the housing).
        i: BodyRef,
        /// Joint point on `i`, body frame (m).
        s_i: [f64; 2],
        /// Second body (for a bearing location: the journal).
        j: BodyRef,
        /// Joint point on `j`, body frame (m).
        s_j: [f64; 2],
    },
    /// Ideal translational joint (2 rows): body `j` keeps its orientation relative
    /// to `i` (`θ_j − θ_i − θ_0 = 0`) and its point `s_j` stays on the line through
    /// `s_i` of body `i` with unit normal `n_i` (body frame of `i`):
    /// `(A_i n_i)·(r_j + A_j s_j − r_i − A_i s_i) = 0` (m).
    Translational {
        /// Guide body.
        i: BodyRef,
        /// A point of the guide line, body frame of `i` (m).
        s_i: [f64; 2],
        /// Unit normal of the guide line, body frame of `i`.
        n_i: [f64; 2],
        /// Sliding body.
        j: BodyRef,
        /// The sliding point, body frame of `j` (m).
        s_j: [f64; 2],
        /// Relative angle `θ_j − θ_i` held (rad).
        theta0: f64,
    },
    /// Rheonomic driver (1 row): `θ_body − θ_0 − θ(t) = 0` (rad), with `θ(t)` the
    /// drive's angle (`ω t` at constant speed).
    Driver {
        /// The driven body (never the ground).
        body: BodyRef,
        /// Angle at `t = 0` (rad).
        theta0: f64,
        /// The prescribed motion `θ(t)`, `θ̇(t)`, `θ̈(t)`.
        drive: CrankDrive,
    },
}

/// The rows of one constraint: slices into the system's arrays.
pub(crate) struct Rows<'a> {
    /// Residuals `Φ`.
    pub phi: &'a mut [f64],
    /// Jacobian rows `Φq`, row-major with `n` columns (already zeroed).
    pub jac: &'a mut [f64],
    /// Number of generalised coordinates.
    pub n: usize,
}

impl Rows<'_> {
    fn add(&mut self, row: usize, body: BodyRef, dx: f64, dy: f64, dtheta: f64) {
        if let Some(o) = body.offset() {
            let r = &mut self.jac[row * self.n..(row + 1) * self.n];
            r[o] += dx;
            r[o + 1] += dy;
            r[o + 2] += dtheta;
        }
    }
}

impl Constraint {
    /// Number of equations this constraint adds.
    pub fn rows(&self) -> usize {
        match self {
            Constraint::Revolute { .. } | Constraint::Translational { .. } => 2,
            Constraint::Driver { .. } => 1,
        }
    }

    /// Writes `Φ` and `Φq` at positions `q` and time `t` (s).
    pub(crate) fn position(&self, t: f64, q: &[f64], out: &mut Rows<'_>) {
        match *self {
            Constraint::Driver {
                body,
                theta0,
                ref drive,
            } => {
                let p = Pose::at(body, q);
                out.phi[0] = p.theta - theta0 - drive.motion(t).angle;
                out.add(0, body, 0.0, 0.0, 1.0);
            }
            Constraint::Revolute { i, s_i, j, s_j } => {
                let (pi, pj) = (Pose::at(i, q), Pose::at(j, q));
                let (ai, aj) = (pi.rotate(s_i), pj.rotate(s_j));
                out.phi[0] = pj.r[0] + aj[0] - pi.r[0] - ai[0];
                out.phi[1] = pj.r[1] + aj[1] - pi.r[1] - ai[1];
                // d(A s)/dθ = (−(A s)_y, (A s)_x)
                out.add(0, j, 1.0, 0.0, -aj[1]);
                out.add(1, j, 0.0, 1.0, aj[0]);
                out.add(0, i, -1.0, 0.0, ai[1]);
                out.add(1, i, 0.0, -1.0, -ai[0]);
            }
            Constraint::Translational {
                i,
                s_i,
                n_i,
                j,
                s_j,
                theta0,
            } => {
                let (pi, pj) = (Pose::at(i, q), Pose::at(j, q));
                let (ai, aj, n) = (pi.rotate(s_i), pj.rotate(s_j), pi.rotate(n_i));
                let d = [
                    pj.r[0] + aj[0] - pi.r[0] - ai[0],
                    pj.r[1] + aj[1] - pi.r[1] - ai[1],
                ];
                out.phi[0] = pj.theta - pi.theta - theta0;
                out.add(0, j, 0.0, 0.0, 1.0);
                out.add(0, i, 0.0, 0.0, -1.0);
                out.phi[1] = n[0] * d[0] + n[1] * d[1];
                // ∂/∂θ_j: n·(B_j s_j); ∂/∂θ_i: (B_i n_i)·d − n·(B_i s_i), with B s = (−(As)_y, (As)_x).
                let dn_d = -n[1] * d[0] + n[0] * d[1];
                out.add(1, j, n[0], n[1], -n[0] * aj[1] + n[1] * aj[0]);
                out.add(1, i, -n[0], -n[1], dn_d + n[0] * ai[1] - n[1] * ai[0]);
            }
        }
    }

    /// Writes `Φt` at time `t` (s), the explicit time derivative of `Φ` (rad/s for
    /// the driver, `−θ̇(t)`, else 0).
    pub(crate) fn time_derivative(&self, t: f64, phit: &mut [f64]) {
        match self {
            Constraint::Driver { drive, .. } => phit[0] = -drive.motion(t).rate,
            _ => phit.iter_mut().for_each(|p| *p = 0.0),
        }
    }

    /// Writes `γ` at time `t` (s) for positions `q` and velocities `qd`.
    pub(crate) fn gamma(&self, t: f64, q: &[f64], qd: &[f64], gamma: &mut [f64]) {
        match *self {
            Constraint::Revolute { i, s_i, j, s_j } => {
                let (pi, pj) = (Pose::of(i, q, qd), Pose::of(j, q, qd));
                let (ai, aj) = (pi.rotate(s_i), pj.rotate(s_j));
                let (wi2, wj2) = (pi.omega * pi.omega, pj.omega * pj.omega);
                gamma[0] = aj[0] * wj2 - ai[0] * wi2;
                gamma[1] = aj[1] * wj2 - ai[1] * wi2;
            }
            Constraint::Translational {
                i,
                s_i,
                n_i,
                j,
                s_j,
                ..
            } => {
                let (pi, pj) = (Pose::of(i, q, qd), Pose::of(j, q, qd));
                let (ai, aj, n) = (pi.rotate(s_i), pj.rotate(s_j), pi.rotate(n_i));
                let d = [
                    pj.r[0] + aj[0] - pi.r[0] - ai[0],
                    pj.r[1] + aj[1] - pi.r[1] - ai[1],
                ];
                let (vi, vj) = (pi.point_velocity(s_i), pj.point_velocity(s_j));
                let dd = [vj[0] - vi[0], vj[1] - vi[1]];
                let bn = [-n[1], n[0]];
                let (wi, wj) = (pi.omega, pj.omega);
                gamma[0] = 0.0;
                gamma[1] = wi * wi * (n[0] * d[0] + n[1] * d[1])
                    - 2.0 * wi * (bn[0] * dd[0] + bn[1] * dd[1])
                    + wj * wj * (n[0] * aj[0] + n[1] * aj[1])
                    - wi * wi * (n[0] * ai[0] + n[1] * ai[1]);
            }
            // Φtt = −θ̈(t), so γ = θ̈(t).
            Constraint::Driver { ref drive, .. } => gamma[0] = drive.motion(t).accel,
        }
    }
}
