//! Samples: every output channel at a state, from the same solve as the right-hand
//! side.

use super::*;

impl SliderCrank {
    /// Evaluates the outputs of docs/model.md §5.2 at time `t` (s) and state `y`.
    /// The natural law applies (a ball is loaded when `δ > 0`) whatever regime an
    /// integrator holds.
    pub fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        if self.journal.is_some() {
            return self.journal_sample(t, y);
        }
        if self.drive.varies() {
            dispatch(self.isa, SampleTask::<true> { sys: self, t, y })
        } else {
            dispatch(self.isa, SampleTask::<false> { sys: self, t, y })
        }
    }

    /// [`SliderCrank::sample`] on lanes `V`.
    #[inline(always)]
    pub(super) fn sample_in<V: Lanes, const VARYING: bool>(
        &mut self,
        t: f64,
        y: &[f64],
    ) -> Result<Sample, ModelError> {
        let (motion, kin, sum, pdd) = self.solve::<V, VARYING, false>(t, y, false)?;
        let parts = SampleParts {
            kin,
            pdd,
            force: sum.force,
            loaded: sum.loaded,
        };
        let mut sample = self.outputs(parts, y, 0.0);
        let k = self.k;
        let acc = k.accelerations(&kin, pdd);
        sample.crank_moment = k.driver_torque::<VARYING>(&kin, &acc, motion.accel);
        Ok(sample)
    }

    /// The outputs of one solved state but the driver torque (set to 0): the joint
    /// forces from the bodies' balances, with the joint's moment `rod_moment` (N m)
    /// on the rod.
    #[inline(always)]
    pub(super) fn outputs(&self, parts: SampleParts, y: &[f64], rod_moment: f64) -> Sample {
        let SampleParts {
            kin,
            pdd,
            force: f,
            loaded,
        } = parts;
        let k = self.k;
        let Accelerations {
            theta_dd,
            rod_dd,
            slider_dd,
            crank_dd,
        } = k.accelerations(&kin, pdd);

        // Force R on the rod from the crank: the rod and slider's x balance, and the
        // rod's moment balance about its small end B (the slider's force has no arm;
        // a plain journal there adds its moment on the rod).
        let rx = k.m3 * rod_dd[0] + k.m4 * slider_dd;
        let p = [-0.5 * k.l3 * kin.c, -0.5 * k.l3 * kin.s]; // rod centre − B
        let d = [-k.l3 * kin.c, -k.l3 * kin.s]; // A − B
        let mut inertial = k.j3 * theta_dd + k.m3 * (p[0] * rod_dd[1] - p[1] * rod_dd[0]);
        if self.location == Location::RodSlider {
            inertial -= rod_moment;
        }
        let weight = -p[0] * k.m3 * k.g; // (r3 − B) × (0, −m3 g)
        let ry = (inertial - weight + d[1] * rx) / d[0];

        let on_crank_from_rod = match self.location {
            Location::CrankRod => f,
            _ => [-rx, -ry],
        };
        let on_ground_from_crank = match self.location {
            Location::CrankGround => f,
            _ => [
                on_crank_from_rod[0] - k.m2 * crank_dd[0],
                on_crank_from_rod[1] - k.m2 * (crank_dd[1] + k.g),
            ],
        };
        // On the rod from the slider: the rod's balance m3 r̈3 = R + S + m3 g.
        let on_rod_from_slider = match self.location {
            Location::RodSlider => f,
            _ => [k.m3 * rod_dd[0] - rx, k.m3 * (rod_dd[1] + k.g) - ry],
        };
        Sample {
            slider_acceleration: slider_dd,
            crank_moment: 0.0,
            crank_ground_force: on_ground_from_crank,
            crank_rod_force: on_crank_from_rod,
            rod_slider_force: on_rod_from_slider,
            eccentricity: if self.has_joint() {
                [y[0], y[1]]
            } else {
                [0.0; 2]
            },
            loaded_balls: loaded,
            housing_acceleration: match &self.housing {
                Some(h) => housing_acceleration(h, f, [y[4], y[5]], [y[6], y[7]]),
                None => [f64::NAN; 2],
            },
        }
    }
}

/// What [`SliderCrank::outputs`] takes of a solved state.
pub(super) struct SampleParts {
    pub(super) kin: Kinematics,
    /// The journal's `p̈` (m/s²).
    pub(super) pdd: [f64; 2],
    /// The force on the body `e` is measured from (N, global).
    pub(super) force: [f64; 2],
    /// Loaded balls, or 1 while a plain journal touches its bushing.
    pub(super) loaded: usize,
}

/// [`SliderCrank::sample`] as a [`LaneTask`], with the crank's acceleration terms
/// when `VARYING`.
pub(super) struct SampleTask<'a, const VARYING: bool> {
    pub(super) sys: &'a mut SliderCrank,
    pub(super) t: f64,
    pub(super) y: &'a [f64],
}

impl<const VARYING: bool> LaneTask for SampleTask<'_, VARYING> {
    type Output = Result<Sample, ModelError>;

    #[inline(always)]
    fn run<V: Lanes>(self) -> Self::Output {
        self.sys.sample_in::<V, VARYING>(self.t, self.y)
    }
}

/// The journal's and the housing's rotations since `t = 0` (rad) at crank angle
/// `crank` (rad): at crank_rod the journal turns with the rod (its angle from `kin`)
/// and the housing with the crank; at rod_slider the journal (the slider's pin)
/// stands still and the housing turns with the rod; elsewhere the journal turns with the crank and the
/// housing (ground) stands still. The rod angle is `asin(sin θ3)`: the branch has
/// `cos θ3 > 0`, so it equals `atan2(sin θ3, cos θ3)`, at a third of the cost.
pub(super) fn race_turns(location: Location, crank: f64, kin: &Kinematics) -> (f64, f64) {
    match location {
        Location::CrankRod => (kin.s.asin(), crank),
        Location::RodSlider => (0.0, kin.s.asin()),
        _ => (crank, 0.0),
    }
}
