//! The scalar parameters a grid may vary or a file records per case: one table,
//! one source of truth for names, units, descriptions and where each lives in
//! [`CaseParams`].

use super::units::Dimension;
use crate::bearing::{Defect, Harmonic, RaceWaviness};
use crate::mechanism::{CaseParams, Housing, SpeedProfile};

/// One scalar case parameter.
#[derive(Clone, Copy)]
pub struct ParamDef {
    /// Name in grid files and study files.
    pub name: &'static str,
    /// Name of the field in validation errors of [`CaseParams::validate`].
    pub field: &'static str,
    /// Physical dimension (decides accepted units; values are stored in its base unit).
    pub dimension: Dimension,
    /// Whether only whole numbers are allowed.
    pub integer: bool,
    /// Description for files.
    pub long_name: &'static str,
    get: fn(&CaseParams) -> f64,
    set: fn(&mut CaseParams, f64),
}

impl ParamDef {
    /// The value in `case`, in the base unit of [`ParamDef::dimension`].
    pub fn get(&self, case: &CaseParams) -> f64 {
        (self.get)(case)
    }

    /// Sets the value (base unit) in `case`.
    pub fn set(&self, case: &mut CaseParams, value: f64) {
        (self.set)(case, value)
    }
}

impl std::fmt::Debug for ParamDef {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// The first harmonic of a race, created (zero amplitude, 35 waves) if absent.
fn first(w: &mut RaceWaviness) -> &mut Harmonic {
    if w.harmonics.is_empty() {
        w.harmonics.push(Harmonic {
            number: 35,
            amplitude: 0.0,
            phase: 0.0,
        });
    }
    &mut w.harmonics[0]
}

fn first_value(w: &RaceWaviness, f: fn(&Harmonic) -> f64) -> f64 {
    w.harmonics.first().map(f).unwrap_or(0.0)
}

/// Both races' value if they agree, else NaN.
fn both(c: &CaseParams, f: fn(&Harmonic) -> f64) -> f64 {
    let (i, o) = (
        first_value(&c.bearing.inner_waviness, f),
        first_value(&c.bearing.outer_waviness, f),
    );
    if i == o {
        i
    } else {
        f64::NAN
    }
}

/// A field of the ramp profile, NaN for any other speed.
fn ramp(c: &CaseParams, f: fn(f64, f64, f64) -> f64) -> f64 {
    match c.speed {
        Some(SpeedProfile::Ramp { from, to, over }) => f(from, to, over),
        _ => f64::NAN,
    }
}

/// A field of the sine profile, NaN for any other speed.
fn sine(c: &CaseParams, f: fn(f64, f64, f64) -> f64) -> f64 {
    match c.speed {
        Some(SpeedProfile::Sine {
            mean,
            amplitude,
            frequency,
        }) => f(mean, amplitude, frequency),
        _ => f64::NAN,
    }
}

/// The speed profile (`ramp`, `sine`) whose field the parameter `name` is, if it is
/// one of the `speed_*` parameters.
pub fn speed_profile_field(name: &str) -> Option<&'static str> {
    match name {
        "speed_from" | "speed_to" | "speed_over" => Some("ramp"),
        "speed_mean" | "speed_amplitude" | "speed_frequency" => Some("sine"),
        _ => None,
    }
}

/// The ramp profile's fields, when the case has one (the study refuses a
/// `speed_from/to/over` axis for any other speed).
fn ramp_mut(c: &mut CaseParams) -> Option<(&mut f64, &mut f64, &mut f64)> {
    match &mut c.speed {
        Some(SpeedProfile::Ramp { from, to, over }) => Some((from, to, over)),
        _ => None,
    }
}

/// The sine profile's fields, when the case has one (the study refuses a
/// `speed_mean/amplitude/frequency` axis for any other speed).
fn sine_mut(c: &mut CaseParams) -> Option<(&mut f64, &mut f64, &mut f64)> {
    match &mut c.speed {
        Some(SpeedProfile::Sine {
            mean,
            amplitude,
            frequency,
        }) => Some((mean, amplitude, frequency)),
        _ => None,
    }
}

/// A field of the case's housing, NaN without one.
fn housing_value(c: &CaseParams, f: fn(&Housing) -> f64) -> f64 {
    c.housing.as_ref().map_or(f64::NAN, f)
}

/// The case's housing, created with [`Housing::default`] if absent (the study
/// refuses a housing axis while the effect is off).
fn housing_mut(c: &mut CaseParams) -> &mut Housing {
    c.housing.get_or_insert_with(Housing::default)
}

/// The case's first defect when its bearing has a defect, i.e. one of nonzero depth
/// (the `fault` label is not `none`); `None` for a healthy bearing: no defects, or
/// only zero-depth ones, which are no defect.
fn first_defect(c: &CaseParams) -> Option<&Defect> {
    if c.bearing.defects.iter().any(|d| d.depth > 0.0) {
        c.bearing.defects.first()
    } else {
        None
    }
}

/// A field of the case's first defect ([`first_defect`]); NaN for a healthy bearing,
/// whose defect parameters describe nothing.
fn first_defect_value(c: &CaseParams, f: fn(&Defect) -> f64) -> f64 {
    first_defect(c).map_or(f64::NAN, f)
}

/// The race of the case's first defect when its bearing has a defect of nonzero
/// depth, `none` for a healthy bearing: what files store as `defect_race`.
pub fn defect_race_name(c: &CaseParams) -> &'static str {
    first_defect(c).map_or("none", |d| d.race.name())
}

macro_rules! param {
    ($name:literal, $field:literal, $dim:ident, $int:literal, $long:literal, |$c:ident| $get:expr, |$s:ident, $v:ident| $set:expr) => {
        ParamDef {
            name: $name,
            field: $field,
            dimension: Dimension::$dim,
            integer: $int,
            long_name: $long,
            get: |$c: &CaseParams| $get,
            set: |$s: &mut CaseParams, $v: f64| $set,
        }
    };
}

/// Every scalar parameter, in file order. `waviness_*` set both races' first
/// harmonic; in files they hold the common value (NaN where the races differ).
/// `rpm` reads the speed of every constant-speed case (a `speed:` profile that never
/// changes included), NaN for a speed that varies; the `speed_*` of a profile are NaN
/// for any other speed.
/// `defect_*` act on the first defect (created, of zero depth, if absent); in files
/// they hold its values, NaN for a healthy bearing (no defect of nonzero depth).
/// `noise_realization` numbers the sensors' noise (docs/model.md §7.8).
/// `m_h`, `k_h` and `c_h` are the housing's, NaN in files for a case without one.
/// `journal_*` are the plain journal's (its clearance radial), NaN in files for a
/// ball-bearing case, whose own keys a plain-joint case stores as NaN
/// ([`stored_value`]).
pub const PARAMETERS: &[ParamDef] = &[
    param!(
        "ball_count",
        "bearing.ball_count",
        Dimensionless,
        true,
        "number of balls N_b",
        |c| c.bearing.ball_count as f64,
        |c, v| c.bearing.ball_count = v as usize
    ),
    param!(
        "rpm",
        "rpm",
        Speed,
        false,
        "crank speed",
        |c| c.constant_rpm().unwrap_or(f64::NAN),
        |c, v| c.rpm = v
    ),
    param!(
        "speed_from",
        "speed.from",
        Speed,
        false,
        "crank speed at t = 0 of a ramp",
        |c| ramp(c, |from, _, _| from),
        |c, v| if let Some((from, _, _)) = ramp_mut(c) {
            *from = v
        }
    ),
    param!(
        "speed_to",
        "speed.to",
        Speed,
        false,
        "crank speed at the end of a ramp",
        |c| ramp(c, |_, to, _| to),
        |c, v| if let Some((_, to, _)) = ramp_mut(c) {
            *to = v
        }
    ),
    param!(
        "speed_over",
        "speed.over",
        Time,
        false,
        "duration of a ramp",
        |c| ramp(c, |_, _, over| over),
        |c, v| if let Some((_, _, over)) = ramp_mut(c) {
            *over = v
        }
    ),
    param!(
        "speed_mean",
        "speed.mean",
        Speed,
        false,
        "mean crank speed of a sine",
        |c| sine(c, |mean, _, _| mean),
        |c, v| if let Some((mean, _, _)) = sine_mut(c) {
            *mean = v
        }
    ),
    param!(
        "speed_amplitude",
        "speed.amplitude",
        Speed,
        false,
        "crank speed amplitude of a sine",
        |c| sine(c, |_, amplitude, _| amplitude),
        |c, v| if let Some((_, amplitude, _)) = sine_mut(c) {
            *amplitude = v
        }
    ),
    param!(
        "speed_frequency",
        "speed.frequency",
        Frequency,
        false,
        "frequency of a sine's speed fluctuation",
        |c| sine(c, |_, _, frequency| frequency),
        |c, v| if let Some((_, _, frequency)) = sine_mut(c) {
            *frequency = v
        }
    ),
    param!(
        "clearance",
        "bearing.clearance",
        Length,
        false,
        "diametral clearance P_d (negative: preload)",
        |c| c.bearing.clearance,
        |c, v| c.bearing.clearance = v
    ),
    param!(
        "stiffness",
        "bearing.stiffness",
        Stiffness,
        false,
        "ball contact stiffness K in N/m^(3/2), as the force at 1 m of deflection",
        |c| c.bearing.stiffness,
        |c, v| c.bearing.stiffness = v
    ),
    param!(
        "damping",
        "bearing.damping",
        Damping,
        false,
        "ball contact damping C",
        |c| c.bearing.damping,
        |c, v| c.bearing.damping = v
    ),
    param!(
        "waviness_number",
        "bearing.inner_waviness.harmonics[0].number",
        Dimensionless,
        true,
        "waviness number of both races",
        |c| both(c, |h| h.number as f64),
        |c, v| {
            first(&mut c.bearing.inner_waviness).number = v as u32;
            first(&mut c.bearing.outer_waviness).number = v as u32;
        }
    ),
    param!(
        "waviness_amplitude",
        "bearing.inner_waviness.harmonics[0].amplitude",
        Length,
        false,
        "waviness amplitude of both races",
        |c| both(c, |h| h.amplitude),
        |c, v| {
            first(&mut c.bearing.inner_waviness).amplitude = v;
            first(&mut c.bearing.outer_waviness).amplitude = v;
        }
    ),
    param!(
        "waviness_phase",
        "bearing.inner_waviness.harmonics[0].phase",
        Angle,
        false,
        "waviness phase of both races",
        |c| both(c, |h| h.phase),
        |c, v| {
            first(&mut c.bearing.inner_waviness).phase = v;
            first(&mut c.bearing.outer_waviness).phase = v;
        }
    ),
    param!(
        "inner_waviness_number",
        "bearing.inner_waviness.harmonics[0].number",
        Dimensionless,
        true,
        "inner race waviness number N_i",
        |c| first_value(&c.bearing.inner_waviness, |h| h.number as f64),
        |c, v| first(&mut c.bearing.inner_waviness).number = v as u32
    ),
    param!(
        "inner_waviness_amplitude",
        "bearing.inner_waviness.harmonics[0].amplitude",
        Length,
        false,
        "inner race waviness amplitude",
        |c| first_value(&c.bearing.inner_waviness, |h| h.amplitude),
        |c, v| first(&mut c.bearing.inner_waviness).amplitude = v
    ),
    param!(
        "inner_waviness_phase",
        "bearing.inner_waviness.harmonics[0].phase",
        Angle,
        false,
        "inner race waviness phase",
        |c| first_value(&c.bearing.inner_waviness, |h| h.phase),
        |c, v| first(&mut c.bearing.inner_waviness).phase = v
    ),
    param!(
        "inner_waviness_offset",
        "bearing.inner_waviness.offset",
        Length,
        false,
        "inner race waviness offset Pi_T",
        |c| c.bearing.inner_waviness.offset,
        |c, v| c.bearing.inner_waviness.offset = v
    ),
    param!(
        "outer_waviness_number",
        "bearing.outer_waviness.harmonics[0].number",
        Dimensionless,
        true,
        "outer race waviness number N_o",
        |c| first_value(&c.bearing.outer_waviness, |h| h.number as f64),
        |c, v| first(&mut c.bearing.outer_waviness).number = v as u32
    ),
    param!(
        "outer_waviness_amplitude",
        "bearing.outer_waviness.harmonics[0].amplitude",
        Length,
        false,
        "outer race waviness amplitude",
        |c| first_value(&c.bearing.outer_waviness, |h| h.amplitude),
        |c, v| first(&mut c.bearing.outer_waviness).amplitude = v
    ),
    param!(
        "outer_waviness_phase",
        "bearing.outer_waviness.harmonics[0].phase",
        Angle,
        false,
        "outer race waviness phase",
        |c| first_value(&c.bearing.outer_waviness, |h| h.phase),
        |c, v| first(&mut c.bearing.outer_waviness).phase = v
    ),
    param!(
        "outer_waviness_offset",
        "bearing.outer_waviness.offset",
        Length,
        false,
        "outer race waviness offset Pi_T",
        |c| c.bearing.outer_waviness.offset,
        |c, v| c.bearing.outer_waviness.offset = v
    ),
    param!(
        "defect_angle",
        "bearing.defects[0].angle",
        Angle,
        false,
        "angle of the first defect in the frame of its race's body (ball: on ball 0)",
        |c| first_defect_value(c, |d| d.angle),
        |c, v| Defect::first(&mut c.bearing.defects).angle = v
    ),
    param!(
        "defect_width",
        "bearing.defects[0].width",
        Length,
        false,
        "width of the first defect along its surface",
        |c| first_defect_value(c, |d| d.width),
        |c, v| Defect::first(&mut c.bearing.defects).width = v
    ),
    param!(
        "defect_depth",
        "bearing.defects[0].depth",
        Length,
        false,
        "depth of the first defect",
        |c| first_defect_value(c, |d| d.depth),
        |c, v| Defect::first(&mut c.bearing.defects).depth = v
    ),
    param!(
        "m_h",
        "housing.m_h",
        Mass,
        false,
        "housing mass m_h",
        |c| housing_value(c, |h| h.mass),
        |c, v| housing_mut(c).mass = v
    ),
    param!(
        "k_h",
        "housing.k_h",
        SpringStiffness,
        false,
        "housing support stiffness k_h (x and y)",
        |c| housing_value(c, |h| h.stiffness),
        |c, v| housing_mut(c).stiffness = v
    ),
    param!(
        "c_h",
        "housing.c_h",
        Damping,
        false,
        "housing support damping c_h (x and y)",
        |c| housing_value(c, |h| h.damping),
        |c, v| housing_mut(c).damping = v
    ),
    param!(
        "inner_race_diameter",
        "bearing.inner_race_diameter",
        Length,
        false,
        "inner raceway diameter d_i",
        |c| c.bearing.inner_race_diameter,
        |c, v| c.bearing.inner_race_diameter = v
    ),
    param!(
        "outer_race_diameter",
        "bearing.outer_race_diameter",
        Length,
        false,
        "outer raceway diameter d_o",
        |c| c.bearing.outer_race_diameter,
        |c, v| c.bearing.outer_race_diameter = v
    ),
    param!(
        "journal_radius",
        "journal.radius",
        Length,
        false,
        "plain journal radius R_j",
        |c| c.journal.geometry.radius,
        |c, v| c.journal.geometry.radius = v
    ),
    param!(
        "journal_clearance",
        "journal.clearance",
        Length,
        false,
        "plain journal radial clearance c = R_b - R_j",
        |c| c.journal.geometry.clearance,
        |c, v| c.journal.geometry.clearance = v
    ),
    param!(
        "journal_length",
        "journal.length",
        Length,
        false,
        "plain journal bearing length L",
        |c| c.journal.geometry.length,
        |c, v| c.journal.geometry.length = v
    ),
    param!(
        "journal_friction_coefficient",
        "journal.friction.coefficient",
        Dimensionless,
        false,
        "plain journal friction coefficient mu",
        |c| c.journal.friction.coefficient,
        |c, v| c.journal.friction.coefficient = v
    ),
    param!(
        "journal_viscosity",
        "journal.viscosity",
        Viscosity,
        false,
        "lubricant dynamic viscosity of the lubricated journal",
        |c| c.journal.viscosity,
        |c, v| c.journal.viscosity = v
    ),
    param!(
        "crank_length",
        "mechanism.crank_length",
        Length,
        false,
        "crank length L2",
        |c| c.mechanism.crank_length,
        |c, v| c.mechanism.crank_length = v
    ),
    param!(
        "rod_length",
        "mechanism.rod_length",
        Length,
        false,
        "connecting rod length L3",
        |c| c.mechanism.rod_length,
        |c, v| c.mechanism.rod_length = v
    ),
    param!(
        "crank_mass",
        "mechanism.crank_mass",
        Mass,
        false,
        "crank mass m2",
        |c| c.mechanism.crank_mass,
        |c, v| c.mechanism.crank_mass = v
    ),
    param!(
        "crank_inertia",
        "mechanism.crank_inertia",
        Inertia,
        false,
        "crank moment of inertia J2",
        |c| c.mechanism.crank_inertia,
        |c, v| c.mechanism.crank_inertia = v
    ),
    param!(
        "rod_mass",
        "mechanism.rod_mass",
        Mass,
        false,
        "connecting rod mass m3",
        |c| c.mechanism.rod_mass,
        |c, v| c.mechanism.rod_mass = v
    ),
    param!(
        "rod_inertia",
        "mechanism.rod_inertia",
        Inertia,
        false,
        "connecting rod moment of inertia J3",
        |c| c.mechanism.rod_inertia,
        |c, v| c.mechanism.rod_inertia = v
    ),
    param!(
        "slider_mass",
        "mechanism.slider_mass",
        Mass,
        false,
        "slider mass m4",
        |c| c.mechanism.slider_mass,
        |c, v| c.mechanism.slider_mass = v
    ),
    param!(
        "slider_inertia",
        "mechanism.slider_inertia",
        Inertia,
        false,
        "slider moment of inertia J4",
        |c| c.mechanism.slider_inertia,
        |c, v| c.mechanism.slider_inertia = v
    ),
    param!(
        "noise_realization",
        "noise_realization",
        Dimensionless,
        true,
        "realisation of the sensors' noise, mixed into its seed",
        |c| c.noise_realization as f64,
        |c, v| c.noise_realization = v as u64
    ),
];

/// Whether `p` is one of the ball bearing's own parameters (balls, clearance,
/// stiffness, races, waviness, defects), which do not act on a plain journal; the
/// contact damping `damping` acts on both.
pub fn is_ball_parameter(p: &ParamDef) -> bool {
    p.field.starts_with("bearing.") && p.name != "damping"
}

/// Whether `p` is one of the plain journal's parameters (`journal_*`), which do not
/// act on a ball bearing.
pub fn is_journal_parameter(p: &ParamDef) -> bool {
    p.field.starts_with("journal.")
}

/// The value of `p` a file stores for `case`: [`ParamDef::get`], or NaN for a
/// parameter of the joint kind the case does not have (a ball bearing's keys in a
/// plain-joint case, a journal's in a ball-bearing case).
pub fn stored_value(p: &ParamDef, case: &CaseParams) -> f64 {
    let plain = case.joint.is_plain();
    if (plain && is_ball_parameter(p)) || (!plain && is_journal_parameter(p)) {
        f64::NAN
    } else {
        p.get(case)
    }
}

/// The value of grid axis `name` in `case`, as text: a scalar parameter's value in
/// its base unit, or the name of the location or of the first defect's race
/// ([`defect_race_name`]: `none` for a healthy bearing).
pub fn axis_value(name: &str, case: &CaseParams) -> String {
    match (lookup(name), name) {
        (Some(p), _) => format!("{}", p.get(case)),
        (None, "defect_race") => defect_race_name(case).to_string(),
        (None, "joint") => case.joint.to_string(),
        (None, _) => case.location.to_string(),
    }
}

/// The parameter called `name`.
pub fn lookup(name: &str) -> Option<&'static ParamDef> {
    PARAMETERS.iter().find(|p| p.name == name)
}
