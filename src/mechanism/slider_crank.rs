//! The slider-crank of MODEL.md §1 with the bearing at `crank_ground`, at
//! `crank_rod`, or nowhere (`ideal`).
//!
//! Bodies: crank (0), connecting rod (1), slider (2); coordinates
//! `q = (x2, y2, θ2, x3, y3, θ3, x4, y4, θ4)`. The crank pivot is the origin, the
//! slider runs on the x axis, and the crank is driven at `θ2 = ω t`.

use std::f64::consts::PI;
use std::fmt;
use std::str::FromStr;

use crate::bearing::{BallBearing, BearingParams, Mounting};
use crate::error::{ModelError, ParamError};
use crate::multibody::{Body, BodyRef, Constraint, System};

/// Standard gravity (m/s²), along −y when the effect is on.
pub const GRAVITY: f64 = 9.81;

const CRANK: BodyRef = BodyRef::Moving(0);
const ROD: BodyRef = BodyRef::Moving(1);
const SLIDER: BodyRef = BodyRef::Moving(2);
/// Index of the slider's x coordinate in `q`.
const SLIDER_X: usize = 6;

/// Where the bearing sits (a grid axis).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Location {
    /// No bearing: all joints ideal (the reference mechanism).
    Ideal,
    /// Bearing between crank and ground (paper Example 1).
    CrankGround,
    /// Bearing between crank and connecting rod (paper Example 2).
    CrankRod,
}

impl Location {
    /// Every location, in the order used for ids and files.
    pub const ALL: [Location; 3] = [Location::Ideal, Location::CrankGround, Location::CrankRod];

    /// The name used in grid files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            Location::Ideal => "ideal",
            Location::CrankGround => "crank_ground",
            Location::CrankRod => "crank_rod",
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Location {
    type Err = ParamError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Location::ALL
            .into_iter()
            .find(|l| l.name() == s)
            .ok_or_else(|| ParamError::new("location", s, "one of ideal, crank_ground, crank_rod"))
    }
}

/// Body parameters of the slider-crank (SI; defaults of MODEL.md §1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MechanismParams {
    /// Crank length `L2` (m).
    pub crank_length: f64,
    /// Connecting rod length `L3` (m).
    pub rod_length: f64,
    /// Crank mass `m2` (kg).
    pub crank_mass: f64,
    /// Crank moment of inertia `J2` about its centre of mass (kg m²).
    pub crank_inertia: f64,
    /// Rod mass `m3` (kg).
    pub rod_mass: f64,
    /// Rod moment of inertia `J3` (kg m²).
    pub rod_inertia: f64,
    /// Slider mass `m4` (kg).
    pub slider_mass: f64,
    /// Slider moment of inertia `J4` (kg m²); immaterial, θ4 is constrained.
    pub slider_inertia: f64,
}

impl Default for MechanismParams {
    fn default() -> Self {
        Self {
            crank_length: 0.05,
            rod_length: 0.12,
            crank_mass: 0.30,
            crank_inertia: 1.0e-4,
            rod_mass: 0.21,
            rod_inertia: 2.5e-4,
            slider_mass: 0.14,
            slider_inertia: 1.0e-4,
        }
    }
}

impl MechanismParams {
    /// Checks every field; the error names the field, its value and what is allowed.
    pub fn validate(&self) -> Result<(), ParamError> {
        let fields = [
            ("mechanism.crank_length", self.crank_length),
            ("mechanism.rod_length", self.rod_length),
            ("mechanism.crank_mass", self.crank_mass),
            ("mechanism.crank_inertia", self.crank_inertia),
            ("mechanism.rod_mass", self.rod_mass),
            ("mechanism.rod_inertia", self.rod_inertia),
            ("mechanism.slider_mass", self.slider_mass),
            ("mechanism.slider_inertia", self.slider_inertia),
        ];
        for (name, v) in fields {
            if !(v.is_finite() && v > 0.0) {
                return Err(ParamError::new(name, v, "finite and > 0"));
            }
        }
        if self.rod_length <= self.crank_length {
            return Err(ParamError::new(
                "mechanism.rod_length",
                self.rod_length,
                format!(
                    "greater than mechanism.crank_length = {} (else the crank cannot turn)",
                    self.crank_length
                ),
            ));
        }
        Ok(())
    }
}

/// Everything that defines one simulated case.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseParams {
    /// Body parameters.
    pub mechanism: MechanismParams,
    /// Bearing parameters (unused for [`Location::Ideal`]).
    pub bearing: BearingParams,
    /// Where the bearing sits.
    pub location: Location,
    /// Crank speed (rev/min, > 0).
    pub rpm: f64,
    /// Gravity along −y ([`GRAVITY`]) when true.
    pub gravity: bool,
}

impl Default for CaseParams {
    /// The paper's crank_ground case at 300 rpm with 9 balls and no waviness.
    fn default() -> Self {
        Self {
            mechanism: MechanismParams::default(),
            bearing: BearingParams::default(),
            location: Location::CrankGround,
            rpm: 300.0,
            gravity: false,
        }
    }
}

impl CaseParams {
    /// Crank speed ω (rad/s).
    pub fn omega(&self) -> f64 {
        2.0 * PI * self.rpm / 60.0
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), ParamError> {
        self.mechanism.validate()?;
        if self.location != Location::Ideal {
            self.bearing.validate()?;
            let slack = self.mechanism.rod_length - self.mechanism.crank_length;
            if self.bearing.clearance.abs() >= slack {
                return Err(ParamError::new(
                    "bearing.clearance",
                    self.bearing.clearance,
                    format!("|clearance| below rod_length - crank_length = {slack} m"),
                ));
            }
        }
        if !(self.rpm.is_finite() && self.rpm > 0.0) {
            return Err(ParamError::new("rpm", self.rpm, "finite and > 0 rev/min"));
        }
        Ok(())
    }
}

/// The outputs of MODEL.md §3 at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Sample {
    /// Slider acceleration ẍ4 (m/s²).
    pub slider_acceleration: f64,
    /// Torque the driver applies to the crank, `−λ_driver` (N m, counter-clockwise +).
    pub crank_moment: f64,
    /// Force transmitted at the crank–ground joint: on the ground from the crank
    /// (N, global); the bearing's `F` when the bearing is there.
    pub crank_ground_force: [f64; 2],
    /// Force transmitted at the crank–rod joint: on the crank from the rod (N,
    /// global); the bearing's `F` when the bearing is there.
    pub crank_rod_force: [f64; 2],
    /// Bearing eccentricity `e` (m, global; zero for the ideal mechanism).
    pub eccentricity: [f64; 2],
    /// Number of loaded balls (0 for the ideal mechanism).
    pub loaded_balls: usize,
}

impl Sample {
    /// The force at the joint a bearing at `location` occupies (or would occupy),
    /// so that bearing and ideal cases compare one to one. `None` for `Ideal`.
    pub fn joint_force(&self, location: Location) -> Option<[f64; 2]> {
        match location {
            Location::Ideal => None,
            Location::CrankGround => Some(self.crank_ground_force),
            Location::CrankRod => Some(self.crank_rod_force),
        }
    }
}

/// A slider-crank case ready to integrate: the system, its initial state and
/// where to read the outputs.
#[derive(Debug, Clone)]
pub struct SliderCrank {
    system: System<BallBearing>,
    location: Location,
    q0: Vec<f64>,
    qd0: Vec<f64>,
    driver_row: usize,
    /// Row of the remaining ideal revolute at crank–ground or crank–rod (if any).
    crank_ground_row: Option<usize>,
    crank_rod_row: Option<usize>,
}

impl SliderCrank {
    /// Builds the case; refuses invalid parameters with the field named.
    pub fn new(case: &CaseParams) -> Result<Self, ParamError> {
        case.validate()?;
        let mp = &case.mechanism;
        let (l2, l3) = (mp.crank_length, mp.rod_length);
        let bodies = vec![
            Body {
                mass: mp.crank_mass,
                inertia: mp.crank_inertia,
            },
            Body {
                mass: mp.rod_mass,
                inertia: mp.rod_inertia,
            },
            Body {
                mass: mp.slider_mass,
                inertia: mp.slider_inertia,
            },
        ];
        let crank_ground = Constraint::Revolute {
            i: BodyRef::Ground,
            s_i: [0.0, 0.0],
            j: CRANK,
            s_j: [-0.5 * l2, 0.0],
        };
        let crank_rod = Constraint::Revolute {
            i: CRANK,
            s_i: [0.5 * l2, 0.0],
            j: ROD,
            s_j: [-0.5 * l3, 0.0],
        };
        let common = [
            Constraint::Revolute {
                i: ROD,
                s_i: [0.5 * l3, 0.0],
                j: SLIDER,
                s_j: [0.0, 0.0],
            },
            Constraint::Translational {
                i: BodyRef::Ground,
                s_i: [0.0, 0.0],
                n_i: [0.0, 1.0],
                j: SLIDER,
                s_j: [0.0, 0.0],
                theta0: 0.0,
            },
            Constraint::Driver {
                body: CRANK,
                theta0: 0.0,
                omega: case.omega(),
            },
        ];
        let gravity = case.gravity.then_some(GRAVITY);

        // The ideal mechanism gives the initial positions and velocities (paper Table 3).
        let q_nominal = vec![
            0.5 * l2,
            0.0,
            0.0,
            l2 + 0.5 * l3,
            0.0,
            0.0,
            l2 + l3,
            0.0,
            0.0,
        ];
        let mut ideal_constraints = vec![crank_ground, crank_rod];
        ideal_constraints.extend(common);
        let mut ideal = System::new(
            bodies.clone(),
            ideal_constraints,
            Vec::new(),
            gravity,
            Vec::new(),
        )?;
        ideal.initial_state(&q_nominal, &[0.0; 9]);
        ideal
            .evaluate(0.0, &[], false)
            .map_err(|e| ParamError::new("mechanism", "initial configuration", e.to_string()))?;
        let (q0, qd0) = (ideal.q().to_vec(), ideal.qd().to_vec());

        let (kept, independent, bearing) = match case.location {
            Location::Ideal => {
                return Ok(Self::assemble(
                    ideal,
                    case.location,
                    q0,
                    qd0,
                    Some(0),
                    Some(1),
                ))
            }
            Location::CrankGround => {
                let mount = Mounting {
                    housing: BodyRef::Ground,
                    housing_point: [0.0, 0.0],
                    journal: CRANK,
                    journal_point: [-0.5 * l2, 0.0],
                    housing_theta0: 0.0,
                    journal_theta0: q0[2],
                };
                (
                    crank_rod,
                    vec![0, 1],
                    BallBearing::new(&case.bearing, mount)?,
                )
            }
            Location::CrankRod => {
                let mount = Mounting {
                    housing: CRANK,
                    housing_point: [0.5 * l2, 0.0],
                    journal: ROD,
                    journal_point: [-0.5 * l3, 0.0],
                    housing_theta0: q0[2],
                    journal_theta0: q0[5],
                };
                (
                    crank_ground,
                    vec![3, 4],
                    BallBearing::new(&case.bearing, mount)?,
                )
            }
        };
        let mut constraints = vec![kept];
        constraints.extend(common);
        let system = System::new(bodies, constraints, vec![bearing], gravity, independent)?;
        let (cg, cr) = match case.location {
            Location::CrankGround => (None, Some(0)),
            _ => (Some(0), None),
        };
        Ok(Self::assemble(system, case.location, q0, qd0, cg, cr))
    }

    fn assemble(
        system: System<BallBearing>,
        location: Location,
        q0: Vec<f64>,
        qd0: Vec<f64>,
        crank_ground: Option<usize>,
        crank_rod: Option<usize>,
    ) -> Self {
        let driver = system.constraint_row(if location == Location::Ideal { 4 } else { 3 });
        Self {
            crank_ground_row: crank_ground.map(|k| system.constraint_row(k)),
            crank_rod_row: crank_rod.map(|k| system.constraint_row(k)),
            driver_row: driver,
            system,
            location,
            q0,
            qd0,
        }
    }

    /// Turns the energy ledger of the underlying system on or off.
    #[must_use]
    pub fn with_energy_ledger(mut self, on: bool) -> Self {
        self.system = self.system.with_energy_ledger(on);
        self
    }

    /// Where the bearing sits.
    pub fn location(&self) -> Location {
        self.location
    }

    /// Initial positions `q(0)` of the ideal mechanism (m, rad).
    pub fn initial_positions(&self) -> &[f64] {
        &self.q0
    }

    /// The integrator's initial state: the independent coordinates and their rates
    /// from the ideal mechanism (zero eccentricity), plus the ledger if on.
    pub fn initial_state(&mut self) -> Vec<f64> {
        self.system.initial_state(&self.q0, &self.qd0)
    }

    /// The underlying multibody system (the ODE the integrators advance).
    pub fn system(&self) -> &System<BallBearing> {
        &self.system
    }

    /// Mutable access to the underlying system, e.g. to hand it to an integrator.
    pub fn system_mut(&mut self) -> &mut System<BallBearing> {
        &mut self.system
    }

    /// Evaluates the outputs of MODEL.md §3 at time `t` (s) and state `y`.
    pub fn sample(&mut self, t: f64, y: &[f64]) -> Result<Sample, ModelError> {
        self.system.evaluate(t, y, true)?;
        Ok(self.read_sample())
    }

    /// The outputs from the system's last evaluation with multipliers.
    pub fn read_sample(&self) -> Sample {
        let s = &self.system;
        let lambda = s.lambda();
        let joint = |row: Option<usize>| row.map(|r| [lambda[r], lambda[r + 1]]);
        let reaction = s
            .elements()
            .first()
            .map(|b| b.reaction())
            .unwrap_or_default();
        Sample {
            slider_acceleration: s.qdd()[SLIDER_X],
            crank_moment: -lambda[self.driver_row],
            crank_ground_force: joint(self.crank_ground_row).unwrap_or(reaction.force),
            crank_rod_force: joint(self.crank_rod_row).unwrap_or(reaction.force),
            eccentricity: reaction.eccentricity,
            loaded_balls: reaction.loaded_balls,
        }
    }
}

impl crate::solve::OdeSystem for SliderCrank {
    fn dim(&self) -> usize {
        self.system.dim()
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        self.system.rhs(t, y, dydt)
    }

    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        self.system.accept_step(t, y)
    }
}
