//! The slider-crank of docs/model.md §1 with the bearing at `crank_ground`, at
//! `crank_rod`, or nowhere (`ideal`).
//!
//! Bodies: crank (0), connecting rod (1), slider (2); coordinates
//! `q = (x2, y2, θ2, x3, y3, θ3, x4, y4, θ4)`. The crank pivot is the origin, the
//! slider runs on the x axis, and the crank is driven at `θ2(t)` (docs/model.md §1.5).

use super::{CaseParams, Location, MechanismParams, Sample, GRAVITY};
use crate::bearing::{BallBearing, Mounting};
use crate::error::{ModelError, ParamError};
use crate::multibody::{Body, BodyRef, Constraint, System};

const CRANK: BodyRef = BodyRef::Moving(0);
const ROD: BodyRef = BodyRef::Moving(1);
const SLIDER: BodyRef = BodyRef::Moving(2);
/// Index of the slider's x coordinate in `q`.
const SLIDER_X: usize = 6;

/// A slider-crank case ready to integrate: the system, its initial state and
/// where to read the outputs.
#[derive(Debug, Clone)]
pub struct CartesianSliderCrank {
    system: System<BallBearing>,
    location: Location,
    q0: Vec<f64>,
    qd0: Vec<f64>,
    driver_row: usize,
    /// Row of the remaining ideal revolute at crank–ground or crank–rod (if any).
    crank_ground_row: Option<usize>,
    crank_rod_row: Option<usize>,
}

/// The crank, the connecting rod and the slider with their masses (kg) and
/// inertias about their centres (kg m²).
fn bodies(mp: &MechanismParams) -> Vec<Body> {
    vec![
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
    ]
}

/// The joints of the slider-crank: the two revolutes a bearing can take the place
/// of, and the rod–slider revolute, the slider's guide and the crank's driver that
/// every case has.
struct Joints {
    crank_ground: Constraint,
    crank_rod: Constraint,
    common: [Constraint; 3],
}

impl Joints {
    /// The joints of `case`'s mechanism, at the bodies' ends (lengths in m).
    fn of(case: &CaseParams) -> Self {
        let (l2, l3) = (case.mechanism.crank_length, case.mechanism.rod_length);
        Self {
            crank_ground: Constraint::Revolute {
                i: BodyRef::Ground,
                s_i: [0.0, 0.0],
                j: CRANK,
                s_j: [-0.5 * l2, 0.0],
            },
            crank_rod: Constraint::Revolute {
                i: CRANK,
                s_i: [0.5 * l2, 0.0],
                j: ROD,
                s_j: [-0.5 * l3, 0.0],
            },
            common: [
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
                    drive: case.drive(),
                },
            ],
        }
    }
}

/// The ideal mechanism (every joint in `constraints` ideal, gravity in m/s²)
/// evaluated at `t = 0`: its positions (m, rad) and velocities (m/s, rad/s) there
/// start every case (paper Table 3). They are the in-line configuration of crank
/// length `l2` and rod length `l3` (m), made consistent with the constraints.
fn ideal_mechanism(
    bodies: &[Body],
    constraints: Vec<Constraint>,
    gravity: Option<f64>,
    (l2, l3): (f64, f64),
) -> Result<System<BallBearing>, ParamError> {
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
    let mut ideal = System::new(
        bodies.to_vec(),
        constraints,
        Vec::new(),
        gravity,
        Vec::new(),
    )?;
    ideal.initial_state(&q_nominal, &[0.0; 9]);
    ideal
        .evaluate(0.0, &[], false)
        .map_err(|e| ParamError::new("mechanism", "initial configuration", e.to_string()))?;
    Ok(ideal)
}

/// Refuses what only the production model simulates: a housing, rod_slider and
/// plain journals.
fn refuse_production_only(case: &CaseParams) -> Result<(), ParamError> {
    if case.housing.is_some() && case.location != Location::Ideal {
        return Err(ParamError::new(
            "effects",
            "housing",
            "without housing in the Cartesian reference model (only the production \
             model simulates the housing)",
        ));
    }
    if case.location == Location::RodSlider || case.joint.is_plain() {
        return Err(ParamError::new(
            "location",
            format!("{} with joint {}", case.location, case.joint),
            "a ball bearing at crank_ground or crank_rod in the Cartesian reference \
             model (only the production model simulates rod_slider and plain journals)",
        ));
    }
    Ok(())
}

impl CartesianSliderCrank {
    /// Builds the case; refuses invalid parameters with the field named, and a
    /// bearing case with a housing (docs/model.md §3.9), at rod_slider or with a
    /// plain journal, which only the production [`super::SliderCrank`] simulates.
    pub fn new(case: &CaseParams) -> Result<Self, ParamError> {
        case.validate()?;
        refuse_production_only(case)?;
        let mp = &case.mechanism;
        let (l2, l3) = (mp.crank_length, mp.rod_length);
        let bodies = bodies(mp);
        let Joints {
            crank_ground,
            crank_rod,
            common,
        } = Joints::of(case);
        let gravity = case.gravity.then_some(GRAVITY);
        let mut ideal_constraints = vec![crank_ground.clone(), crank_rod.clone()];
        ideal_constraints.extend(common.clone());
        let ideal = ideal_mechanism(&bodies, ideal_constraints, gravity, (l2, l3))?;
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
            Location::CrankRod | Location::RodSlider => {
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

    /// The integrator's initial state: the independent coordinates and their rates
    /// from the ideal mechanism (zero eccentricity, unless
    /// [`CartesianSliderCrank::with_initial_eccentricity`] moved the journal), plus
    /// the ledger if on.
    pub fn initial_state(&mut self) -> Vec<f64> {
        self.system.initial_state(&self.q0, &self.qd0)
    }

    /// Starts the journal at eccentricity `e` (m) from the housing, at the ideal
    /// mechanism's velocities: a replicate's perturbed initial state (docs/model.md
    /// §9.5). The journal body's independent coordinates are displaced, exactly for
    /// the in-line configuration of `t = 0` (crank angle 0): moving the crank's
    /// centre by `e` moves its journal by `e`; moving the rod's centre by
    /// `(e_x − (l3/2)(1 − cos φ), e_y/2)` turns the rod about the slider pin by
    /// `sin φ = −e_y/l3` and moves its journal by `e`. The independent rates stay
    /// the ideal mechanism's: the crank's journal starts at rest relative to the
    /// housing, the rod's with a relative velocity of order `|e| ω`. No effect on
    /// the ideal mechanism.
    #[must_use]
    pub fn with_initial_eccentricity(mut self, e: [f64; 2]) -> Self {
        let (x, shift) = match self.location {
            Location::Ideal => return self,
            Location::CrankGround => (0, e),
            Location::CrankRod | Location::RodSlider => {
                // Slider pin minus rod centre: l3/2 in line.
                let half = self.q0[6] - self.q0[3];
                let cos = (1.0 - (0.5 * e[1] / half).powi(2)).sqrt();
                (3, [e[0] - half * (1.0 - cos), 0.5 * e[1]])
            }
        };
        self.q0[x] += shift[0];
        self.q0[x + 1] += shift[1];
        self
    }

    /// The underlying multibody system (the ODE the integrators advance).
    pub fn system(&self) -> &System<BallBearing> {
        &self.system
    }

    /// Mutable access to the underlying system, e.g. to hand it to an integrator.
    pub fn system_mut(&mut self) -> &mut System<BallBearing> {
        &mut self.system
    }

    /// Evaluates the outputs of docs/model.md §5.2 at time `t` (s) and state `y`.
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
            rod_slider_force: [f64::NAN; 2],
            eccentricity: reaction.eccentricity,
            loaded_balls: reaction.loaded_balls,
            housing_acceleration: [f64::NAN; 2],
        }
    }
}

impl crate::solve::OdeSystem for CartesianSliderCrank {
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
