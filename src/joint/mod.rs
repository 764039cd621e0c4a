//! Clearance revolute joints of docs/model.md §2.10: a journal (pin) of radius `R_j`
//! in a bushing (hole) of radius `R_b = R_j + c`, with the *radial* clearance `c`
//! (unlike the ball bearing's diametral `P_d`).
//!
//! - [`JournalGeometry::contact`]: the joint's kinematics from the eccentricity `e`
//!   (journal centre minus bushing centre), its rate and the two bodies' angular
//!   velocities: eccentricity, unit normal, penetration `δ = |e| − c`, approach
//!   speed and slip speed at the contact point.
//! - [`DryContact`]: the dry joint (Flores, Ambrósio, Claro & Lankarani 2007): the
//!   normal force by the bearing's damping laws ([`ContactLaw`], exponent 3/2, the
//!   onset speed latched as the balls' is) with the stiffness of the journal in its
//!   conforming bushing ([`cylinder_stiffness`]), and modified Coulomb friction with
//!   Ambrósio's velocity correction ([`Friction`]).
//! - [`Film`]: the lubricated joint's short-bearing (Ocvirk) force with squeeze and
//!   wedge terms and half-Sommerfeld cavitation at the moving boundaries where the
//!   pressure vanishes; [`LubricatedJoint`] adds the dry contact beyond a film
//!   limit.
//!
//! Forces are those on the journal, at the journal centre (N, global), with moments
//! about the journal's and the bushing's centres (N m, counter-clockwise positive);
//! the bushing receives the opposite force at its centre.
//!
//! [`ContactLaw`]: crate::bearing::ContactLaw

mod dry;
mod film;
#[cfg(test)]
mod tests;

pub use dry::{cylinder_stiffness, DryContact, Friction, Material};
pub use film::{Film, LubricatedJoint, FILM_LIMIT};

/// The sizes of a plain journal bearing (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JournalGeometry {
    /// Journal radius `R_j` (m), > 0.
    pub radius: f64,
    /// Radial clearance `c = R_b − R_j` (m), > 0: bushing radius minus journal radius.
    pub clearance: f64,
    /// Bearing length `L` (m) along the axis, > 0; read by the film only.
    pub length: f64,
}

/// The relative motion of journal and bushing.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointMotion {
    /// Eccentricity `e` (m, global): journal centre minus bushing centre.
    pub e: [f64; 2],
    /// Its rate `ė` (m/s, global).
    pub v: [f64; 2],
    /// Angular velocity `ω_j` of the journal's body (rad/s, counter-clockwise).
    pub journal_rate: f64,
    /// Angular velocity `ω_b` of the bushing's body (rad/s, counter-clockwise).
    pub bushing_rate: f64,
}

/// The joint's contact kinematics at one state (docs/model.md §2.10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactKinematics {
    /// `|e|` (m).
    pub eccentricity: f64,
    /// Unit normal `n = e/|e|` from the bushing centre toward the journal centre
    /// and the contact point; `(1, 0)` at `e = 0`.
    pub normal: [f64; 2],
    /// Unit tangent `t = ẑ × n = (−n_y, n_x)`.
    pub tangent: [f64; 2],
    /// Penetration `δ = |e| − c` (m); contact while it is > 0.
    pub penetration: f64,
    /// Approach speed `δ̇ = ė·n` (m/s), positive while the penetration grows.
    pub approach: f64,
    /// Tangential speed `ė·t` of the journal centre (m/s): `|e| φ̇`.
    pub orbit_speed: f64,
    /// Slip speed `v_t = ė·t + R_j ω_j − R_b ω_b` (m/s) of the journal's contact
    /// point relative to the bushing's, along `t`.
    pub slip: f64,
}

impl JournalGeometry {
    /// Bushing radius `R_b = R_j + c` (m).
    pub fn bushing_radius(&self) -> f64 {
        self.radius + self.clearance
    }

    /// The contact kinematics of `motion`: the contact points are `R_j n` from the
    /// journal centre and `R_b n` from the bushing centre, so the journal's point
    /// moves relative to the bushing's at `ė + (R_j ω_j − R_b ω_b) t`.
    pub fn contact(&self, motion: &JointMotion) -> ContactKinematics {
        let [ex, ey] = motion.e;
        let eccentricity = ex.hypot(ey);
        let normal = if eccentricity > 0.0 {
            [ex / eccentricity, ey / eccentricity]
        } else {
            [1.0, 0.0]
        };
        let tangent = [-normal[1], normal[0]];
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let orbit_speed = dot(motion.v, tangent);
        ContactKinematics {
            eccentricity,
            normal,
            tangent,
            penetration: eccentricity - self.clearance,
            approach: dot(motion.v, normal),
            orbit_speed,
            slip: orbit_speed + self.radius * motion.journal_rate
                - self.bushing_radius() * motion.bushing_rate,
        }
    }
}

/// What a clearance joint applies at one state.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct JointForce {
    /// Force on the journal (N, global), at its centre; the bushing receives its
    /// opposite at the bushing centre.
    pub force: [f64; 2],
    /// Moment on the journal about its centre (N m): `R_j F_t`.
    pub journal_moment: f64,
    /// Moment on the bushing about its centre (N m): `−R_b F_t`.
    pub bushing_moment: f64,
    /// Normal contact force `F_n ≥ 0` (N), pushing the journal toward the centre.
    pub normal: f64,
    /// Its elastic part `K δ^{3/2}` (N).
    pub elastic: f64,
    /// Friction force `F_t` on the journal along `t` (N).
    pub friction: f64,
    /// Rate of energy the contact's damping dissipates, `(F_n − K δ^{3/2}) δ̇` (W).
    pub damping_dissipation: f64,
    /// Rate of energy friction dissipates, `−F_t v_t ≥ 0` (W).
    pub friction_dissipation: f64,
    /// Power of the film's pressure force on the relative motion,
    /// `F_film·ė` (W); 0 for a dry joint.
    pub film_power: f64,
}
