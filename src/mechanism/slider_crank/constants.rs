//! The constants of one case, computed once when the model is built: masses,
//! lengths, inertias, gravity terms, the housing's, and the ideal mechanism's.

use super::*;

/// Mechanism constants of the reduced equations (SI).
#[derive(Debug, Clone, Copy)]
pub(super) struct Constants {
    pub(super) l2: f64,
    pub(super) l3: f64,
    /// `1/L3` (1/m).
    pub(super) inv_l3: f64,
    pub(super) m2: f64,
    /// Crank inertia (kg m²): only in the kinetic energy (§3.8), never in `ë`.
    pub(super) j2: f64,
    pub(super) m3: f64,
    pub(super) j3: f64,
    pub(super) m4: f64,
    /// Crank speed ω (rad/s) of a constant-speed case (unused when the speed varies).
    pub(super) omega: f64,
    /// `c_g`: 1 when the crank translates with `e` (crank_ground), else 0.
    pub(super) crank_moves: f64,
    /// `a`: 1 when the rod's big end translates with `e` (crank_ground, crank_rod),
    /// 0 when only its small end does (rod_slider): the rod centre's
    /// `∂x/∂e_x` (–).
    pub(super) rod_x: f64,
    /// The rod centre's `∂y/∂e_y = a − 1/2` (–).
    pub(super) rod_y: f64,
    /// `m3 (a − 1/2)` (kg): the rod's share of the `e_y` equation's gravity and
    /// inertia.
    pub(super) m3_y: f64,
    /// `m3 a + m4` (kg): the bodies translating with the big end along x.
    pub(super) m_big: f64,
    /// `m3/2 + m4` (kg): the rod and slider's weight on `tan θ3 · Ä_x` in the `e_y`
    /// equation.
    pub(super) m_t: f64,
    /// Gravity (m/s²) along −y, 0 when off.
    pub(super) g: f64,
    /// The reduced mass matrix `M̄ = [[m11, m_h t], [m_h t, m22]]`, `t = tan θ3`,
    /// by its parts (kg): `m11 = m2 c_g + m3 a + m4`, `m_h = m3 a/2 + m4`, and
    /// `m22 = m22_0 + (j3/L3² + m_q sin²θ3)/cos²θ3` with `m22_0 = m2 c_g + m3/4`,
    /// `m_q = m3/4 + m4`, `j3/L3²` as `j3_l3`.
    pub(super) m11: f64,
    pub(super) m_h: f64,
    pub(super) m22_0: f64,
    pub(super) m_q: f64,
    pub(super) j3_l3: f64,
    /// `det M̄ cos²θ3 = p0 + p1 sin²θ3` (kg²).
    pub(super) p0: f64,
    pub(super) p1: f64,
}

impl Constants {
    /// The constants of mechanism `mp` with the joint at `location`, constant crank
    /// speed `omega` (rad/s; any value when the speed varies) and gravity `g` (m/s², 0
    /// when off).
    pub(super) fn new(
        mp: &crate::mechanism::MechanismParams,
        location: Location,
        omega: f64,
        g: f64,
    ) -> Self {
        let inv_l3 = 1.0 / mp.rod_length;
        let (m2, m3, j3, m4) = (mp.crank_mass, mp.rod_mass, mp.rod_inertia, mp.slider_mass);
        let crank_moves = if location == Location::CrankGround {
            1.0
        } else {
            0.0
        };
        let rod_x = if location == Location::RodSlider {
            0.0
        } else {
            1.0
        };
        let m11 = m2 * crank_moves + m3 * rod_x + m4;
        let m_h = 0.5 * m3 * rod_x + m4;
        let m22_0 = m2 * crank_moves + 0.25 * m3;
        let m_q = 0.25 * m3 + m4;
        let j3_l3 = j3 * inv_l3 * inv_l3;
        Self {
            l2: mp.crank_length,
            l3: mp.rod_length,
            inv_l3,
            m2,
            j2: mp.crank_inertia,
            m3,
            j3,
            m4,
            omega,
            crank_moves,
            rod_x,
            rod_y: rod_x - 0.5,
            m3_y: (rod_x - 0.5) * m3,
            m_big: m3 * rod_x + m4,
            m_t: 0.5 * m3 + m4,
            g,
            m11,
            m_h,
            m22_0,
            m_q,
            j3_l3,
            p0: m11 * (m22_0 + j3_l3),
            p1: m11 * (m_q - m22_0) - m_h * m_h,
        }
    }

    /// Kinematics at crank angle `θ2` given as `(sin, cos)`, crank rate and
    /// acceleration `m` (the acceleration only when `VARYING`), eccentricity `e` (m)
    /// and its rate `ed` (m/s).
    #[inline(always)]
    pub(super) fn kinematics<const VARYING: bool>(
        &self,
        (uy, ux): (f64, f64),
        m: &CrankMotion,
        e: [f64; 2],
        ed: [f64; 2],
    ) -> Result<Kinematics, ModelError> {
        let k = self;
        let w2 = m.rate * m.rate;
        let s = -(e[1] + k.l2 * uy) * k.inv_l3;
        let s2 = s * s;
        let c2 = 1.0 - s2;
        if c2.is_nan() {
            return Err(ModelError::NonFinite {
                what: "eccentricity",
            });
        }
        if c2 <= 1e-12 {
            return Err(ModelError::SingularConstraints);
        }
        // The divisions and the square root depend on s alone and run side by side:
        // 1/c = c · (1/c²), M̄⁻¹ = adj(M̄) cos²θ3 / (p0 + p1 s²), and every term
        // below that needs only 1/c² (k_θ², the whirl, tan θ3 times the along-rod
        // part) takes it instead of 1/c.
        let c = c2.sqrt();
        let inv_c2 = 1.0 / c2;
        let inv_p = 1.0 / (k.p0 + k.p1 * s2);
        let inv_c = c * inv_c2;
        // θ̇3 = k_θ Ȧ_y with k_θ = ∂θ3/∂A_y = −1/(L3 c); the whirl L3 θ̇3².
        let rate = ed[1] + k.l2 * m.rate * ux;
        let whirl = k.inv_l3 * inv_c2 * (rate * rate);
        // At ë = 0, with Ä = −L2 θ̇2² u + L2 θ̈2 u⊥ (§3.1): θ̈3 = k_θ (Ä_y − s whirl),
        // and along the rod −L3 (s θ̈3 + c θ̇3²) = (s Ä_y − whirl)/c.
        let mut big_end_y = -k.l2 * w2 * uy;
        let mut big_end_x = -k.l2 * w2 * ux;
        if VARYING {
            big_end_y += k.l2 * m.accel * ux;
            big_end_x -= k.l2 * m.accel * uy;
        }
        let (normal, along_c) = (big_end_y - s * whirl, s * big_end_y - whirl);
        let along = along_c * inv_c;
        Ok(Kinematics {
            u: [ux, uy],
            s,
            c,
            tan: s * inv_c,
            k_theta: -k.inv_l3 * inv_c,
            theta_dd0: -k.inv_l3 * inv_c * normal,
            rod_dd0: [big_end_x + 0.5 * along, 0.5 * big_end_y],
            slider_dd0: big_end_x + along,
            crank_dd0: [0.5 * big_end_x, 0.5 * big_end_y],
            big_end_x,
            along,
            j3_theta_dd0: k.j3_l3 * inv_c2 * normal,
            tan_along: s * along_c * inv_c2,
            inv_mass: [
                (k.m22_0 * c2 + k.j3_l3 + k.m_q * s2) * inv_p,
                -k.m_h * s * c * inv_p,
                k.m11 * c2 * inv_p,
            ],
        })
    }

    /// `ë` (m/s²) from the reduced equations for bearing force `f` on the housing (N).
    #[inline(always)]
    pub(super) fn eccentricity_acceleration(&self, kin: &Kinematics, f: [f64; 2]) -> [f64; 2] {
        let k = self;
        let cg = k.crank_moves;
        // The generalised forces without the bearing's, which comes last (it waits
        // for the ball loop): the journal receives −F; gravity's part is constant.
        // The rod's and slider's terms are gathered by what they multiply.
        let qx = -(k.m2 * cg * kin.crank_dd0[0]) - k.m_big * kin.big_end_x - k.m_h * kin.along;
        let qy = -(k.g * (k.m2 * cg + k.m3_y))
            - k.m2 * cg * kin.crank_dd0[1]
            - kin.j3_theta_dd0
            - k.m3_y * kin.rod_dd0[1]
            - k.m_t * kin.tan * kin.big_end_x
            - k.m_q * kin.tan_along;
        let (bx, by) = (qx - f[0], qy - f[1]);
        let [i11, i12, i22] = kin.inv_mass;
        [i11 * bx + i12 * by, i12 * bx + i22 * by]
    }

    /// The bodies' accelerations for `ë = edd` (m/s²) (§3.2).
    #[inline(always)]
    pub(super) fn accelerations(&self, kin: &Kinematics, edd: [f64; 2]) -> Accelerations {
        let (tan, cg) = (kin.tan, self.crank_moves);
        Accelerations {
            theta_dd: kin.k_theta * edd[1] + kin.theta_dd0,
            rod_dd: [
                self.rod_x * edd[0] + 0.5 * tan * edd[1] + kin.rod_dd0[0],
                self.rod_y * edd[1] + kin.rod_dd0[1],
            ],
            slider_dd: edd[0] + tan * edd[1] + kin.slider_dd0,
            crank_dd: [
                cg * edd[0] + kin.crank_dd0[0],
                cg * edd[1] + kin.crank_dd0[1],
            ],
        }
    }

    /// Driver torque (N m, §3.4): d'Alembert over a virtual δθ2 at fixed e, under
    /// which the big end moves by L2 u⊥ δθ2 and the bearing force does no work; with
    /// `VARYING`, the crank's own `J2 θ̈2` for crank acceleration `accel` (rad/s²).
    #[inline(always)]
    pub(super) fn driver_torque<const VARYING: bool>(
        &self,
        kin: &Kinematics,
        acc: &Accelerations,
        accel: f64,
    ) -> f64 {
        let k = self;
        let (u, tan) = (kin.u, kin.tan);
        let Accelerations {
            theta_dd,
            rod_dd,
            slider_dd,
            crank_dd,
        } = *acc;
        let da = [-k.l2 * u[1], k.l2 * u[0]];
        let torque = k.m2 * (crank_dd[0] * 0.5 * da[0] + (crank_dd[1] + k.g) * 0.5 * da[1])
            + k.j3 * theta_dd * kin.k_theta * da[1]
            + k.m3 * (rod_dd[0] * (da[0] + 0.5 * tan * da[1]) + (rod_dd[1] + k.g) * 0.5 * da[1])
            + k.m4 * slider_dd * (da[0] + tan * da[1]);
        if VARYING {
            torque + k.j2 * accel
        } else {
            torque
        }
    }

    /// Kinetic and gravitational potential energy (J) at eccentricity `e` (m), its
    /// rate `ed` (m/s), crank rate `w` (rad/s) and crank angle given as `u = (cos, sin)`
    /// (§3.8), from the body velocities of §3.1: `Ȧ = ė + L2 ω u⊥`, `θ̇3 = k_θ Ȧ_y`,
    /// `ẋ4 = Ȧ_x + tan θ3 Ȧ_y`,
    /// `ṙ3 = (a ė_x + L2 ω u⊥_x + tan θ3 Ȧ_y/2, (a − 1/2) ė_y + L2 ω u⊥_y/2)`,
    /// `ṙ2 = c_g ė + (L2/2) ω u⊥`.
    pub(super) fn body_energies(
        &self,
        kin: &Kinematics,
        w: f64,
        e: [f64; 2],
        ed: [f64; 2],
    ) -> (f64, f64) {
        let k = self;
        let (u, cg) = (kin.u, k.crank_moves);
        let tip = [-k.l2 * w * u[1], k.l2 * w * u[0]];
        let big_end = [ed[0] + tip[0], ed[1] + tip[1]];
        let rod_rate = kin.k_theta * big_end[1];
        let slider = big_end[0] + kin.tan * big_end[1];
        // The rod centre: `a ė + L2 ω u⊥` plus half the rod's turn about its big end.
        let rod = [
            k.rod_x * ed[0] + tip[0] + 0.5 * kin.tan * big_end[1],
            k.rod_y * ed[1] + 0.5 * tip[1],
        ];
        let crank = [cg * ed[0] + 0.5 * tip[0], cg * ed[1] + 0.5 * tip[1]];
        let square = |v: [f64; 2]| v[0] * v[0] + v[1] * v[1];
        let kinetic = 0.5
            * (k.m2 * square(crank)
                + k.j2 * w * w
                + k.m3 * square(rod)
                + k.j3 * rod_rate * rod_rate
                + k.m4 * slider * slider);
        // Heights: crank centre c_g e_y + (L2/2) sin θ2, rod centre A_y/2; the
        // slider stays on the guide.
        let rod_y = k.rod_y * e[1] + 0.5 * k.l2 * u[1];
        let gravity = k.g * (k.m2 * (cg * e[1] + 0.5 * k.l2 * u[1]) + k.m3 * rod_y);
        (kinetic, gravity)
    }
}
