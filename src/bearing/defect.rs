//! Localized defects (spalls) on the outer race, the inner race and a ball
//! (docs/model.md §2.9): where each defect sits relative to each ball, and by how
//! much it lowers that ball's deflection.
//!
//! A defect of width `b` and depth `h` lowers the deflection of a ball of radius
//! `R_b` over it by at most `h_eff = min(h, R_b − √(R_b² − (b/2)²))`, the depth the
//! ball can reach. A *flat* profile lowers it by `h_eff` over the whole width; a
//! *rounded* one lets the ball's centre follow the circle of radius `R_b` about the
//! edge it rolls over, so the lowering `R_b − √(R_b² − d²)` at a distance `d` past
//! the edge rises smoothly to `h_eff`.
//!
//! Each defect becomes one or two `Track`s, a place where it meets balls: a race
//! defect one (every ball rolls over it), a ball defect two (ball 0's defect meets
//! the outer race, then the inner race). Along a track a ball is in one of three
//! `Zone`s (outside, on the rounded ramp, on the floor); the zone is what an
//! integrator holds fixed across a step, and its edges are switches located like
//! contact onsets.

use std::f64::consts::{PI, TAU};
use std::fmt;
use std::str::FromStr;

use crate::error::ParamError;

use super::kernel::{ContactState, LANES};
use crate::numeric::simd::{F64x4, Lanes};

/// Which body's surface carries a defect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum DefectRace {
    /// The outer raceway, fixed in the housing.
    Outer,
    /// The inner raceway, fixed on the journal.
    Inner,
    /// Ball 0 (the ball at the cage angle), turning with its spin.
    Ball,
}

impl DefectRace {
    /// Every race, in the order of names in files.
    pub const ALL: [DefectRace; 3] = [DefectRace::Outer, DefectRace::Inner, DefectRace::Ball];

    /// The name used in grid files and outputs.
    pub fn name(self) -> &'static str {
        match self {
            DefectRace::Outer => "outer",
            DefectRace::Inner => "inner",
            DefectRace::Ball => "ball",
        }
    }
}

impl fmt::Display for DefectRace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DefectRace {
    type Err = ParamError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        DefectRace::ALL
            .into_iter()
            .find(|r| r.name() == s)
            .ok_or_else(|| ParamError::new("defect_race", s, "one of outer, inner, ball"))
    }
}

/// The shape of a defect's entry and exit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DefectProfile {
    /// The lowering jumps to `h_eff` at the edge and stays there over the width.
    #[default]
    Flat,
    /// The ball's centre follows the circle of radius `R_b` about the edge: the
    /// lowering `R_b − √(R_b² − d²)` at `d` past the edge, capped at `h_eff`.
    Rounded,
}

impl DefectProfile {
    /// The name used in grid files.
    pub fn name(self) -> &'static str {
        match self {
            DefectProfile::Flat => "flat",
            DefectProfile::Rounded => "rounded",
        }
    }
}

/// One localized defect (docs/model.md §2.9).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defect {
    /// The surface carrying it.
    pub race: DefectRace,
    /// Where its centre sits (rad), in the frame of the body carrying the race (at
    /// `t = 0` measured from the global x axis); for a ball defect, its angle on
    /// ball 0 from the outward radial direction at `t = 0`.
    pub angle: f64,
    /// Width along the surface at its radius (m, > 0); at or above the
    /// circumference it covers the whole surface.
    pub width: f64,
    /// Depth `h` (m, ≥ 0); a zero-depth defect changes nothing and is not simulated.
    pub depth: f64,
    /// Entry and exit shape.
    pub profile: DefectProfile,
}

impl Default for Defect {
    /// A flat outer-race defect at 0 rad, 1 mm wide, of zero depth (no effect).
    fn default() -> Self {
        Self {
            race: DefectRace::Outer,
            angle: 0.0,
            width: 1e-3,
            depth: 0.0,
            profile: DefectProfile::Flat,
        }
    }
}

impl Defect {
    /// The first defect of `list`, created ([`Defect::default`], of zero depth) if
    /// absent: what the `defect_*` grid axes act on.
    pub fn first(list: &mut Vec<Defect>) -> &mut Defect {
        if list.is_empty() {
            list.push(Defect::default());
        }
        &mut list[0]
    }

    /// How deep a ball of `ball_diameter` (m) can dip into a defect of this width
    /// (m): `R − √(R² − a²)`, `R` the ball's radius and `a` half the width (at most
    /// `R`), docs/model.md §2.9.
    pub fn geometric_depth(&self, ball_diameter: f64) -> f64 {
        let ball_radius = 0.5 * ball_diameter;
        let reach = (0.5 * self.width).min(ball_radius);
        // R − √(R² − a²) = a² / (R + √(R² − a²)), without cancellation.
        reach * reach / (ball_radius + (ball_radius * ball_radius - reach * reach).sqrt())
    }

    /// The effective depth `h_eff = min(h, R − √(R² − a²))` (m): the most the defect
    /// lowers a ball's deflection (docs/model.md §2.9).
    pub fn effective_depth(&self, ball_diameter: f64) -> f64 {
        self.depth.max(0.0).min(self.geometric_depth(ball_diameter))
    }

    /// Checks every field; `prefix` (e.g. `bearing.defects[0]`) names it in errors.
    pub fn validate(&self, prefix: &str) -> Result<(), ParamError> {
        if !self.angle.is_finite() {
            return Err(ParamError::new(
                format!("{prefix}.angle"),
                self.angle,
                "a finite angle in rad",
            ));
        }
        if !(self.width.is_finite() && self.width > 0.0) {
            return Err(ParamError::new(
                format!("{prefix}.width"),
                self.width,
                "finite and > 0 m",
            ));
        }
        if !(self.depth.is_finite() && self.depth >= 0.0) {
            return Err(ParamError::new(
                format!("{prefix}.depth"),
                self.depth,
                "finite and >= 0 m",
            ));
        }
        Ok(())
    }
}

/// The `fault` label of a defect list: the races with a defect of nonzero depth,
/// in the order outer, inner, ball, joined by `+`; `none` without any.
pub fn fault_label(defects: &[Defect]) -> String {
    let races: Vec<&str> = DefectRace::ALL
        .into_iter()
        .filter(|r| defects.iter().any(|d| d.race == *r && d.depth > 0.0))
        .map(DefectRace::name)
        .collect();
    if races.is_empty() {
        "none".to_string()
    } else {
        races.join("+")
    }
}

/// Where a ball is along a [`Track`]; held fixed over an integrator step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Zone {
    /// Off the defect: no lowering.
    #[default]
    Outside,
    /// On a rounded edge: lowering `R_b − √(R_b² − d²)`.
    Ramp,
    /// On the floor: lowering `h_eff`.
    Floor,
}

/// One place where a defect meets balls. Ball `r` (0-based, base angle `α_r`) sits
/// at the track angle `x = wrap(ratio ψ) + start_r`, wrapped to `[−π, π)` (with `ψ`
/// the ball's angle on the inner race `ψ_in` or the outer race `ψ_out`, and
/// `start_r = per_ball α_r − centre` wrapped there too), at the arc position
/// `s = radius x` (m) from the defect's centre. Per ball the position is two
/// additions and at most one turn of wrapping, on [`LANES`] balls at a time.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Track {
    /// Whether `ψ` is `ψ_in` (else `ψ_out`); the slope `∂δ/∂ψ` goes to that race.
    pub inner: bool,
    ratio: f64,
    /// `start_r` of each ball that meets it (rad, in `[−π, π)`), [`LANES`] per
    /// vector; `per_ball` is 1 on a race, 0 on a ball (whose track does not depend on
    /// the ball's place). Lanes of balls that do not meet it hold 0.
    start: Vec<F64x4>,
    /// All bits set in the lanes of balls that meet it, else 0.
    meets: Vec<F64x4>,
    /// Arc length per radian of the surface (m): its radius.
    radius: f64,
    /// Number of balls that meet it: all, or 1 (ball 0) for a ball defect.
    pub balls: usize,
    /// Half width `b/2` (m).
    half_width: f64,
    /// Whether the defect covers the whole surface (no edges).
    whole: bool,
    rounded: bool,
    /// Ball radius `R_b` (m).
    ball_radius: f64,
    /// `h_eff` (m).
    floor: f64,
    /// Distance past the edge where a rounded ramp reaches the floor,
    /// `√(h_eff (2 R_b − h_eff))` (m) when the depth limits the ball, `+∞` when the
    /// width does (the ramp reaches the floor only at the centre).
    ramp_end: f64,
}

/// The zones of [`LANES`] balls on a track as two lane masks (all bits set where
/// true): on the ramp, on the floor; neither is outside.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct ZoneMasks {
    pub ramp: F64x4,
    pub floor: F64x4,
}

impl ZoneMasks {
    /// The zone of lane `l`.
    pub fn zone(&self, l: usize) -> Zone {
        if self.floor.0[l].to_bits() != 0 {
            Zone::Floor
        } else if self.ramp.0[l].to_bits() != 0 {
            Zone::Ramp
        } else {
            Zone::Outside
        }
    }
}

/// `x` (rad, in `[−2π, 2π)`) wrapped to `[−π, π]` by at most one turn.
#[inline(always)]
fn wrap_once<V: Lanes>(x: V) -> V {
    let x = V::splat(-PI).simd_gt(x).bitselect(x + V::splat(TAU), x);
    x.simd_gt(V::splat(PI)).bitselect(x - V::splat(TAU), x)
}

/// `x` (rad, any finite angle) wrapped to `[−π, π)`: `x − 2π floor(x/2π + 1/2)`, the
/// floor by truncation (no libm call; the angles stay far inside the `i64` range).
#[inline(always)]
fn wrap(x: f64) -> f64 {
    let q = x * (1.0 / TAU) + 0.5;
    let t = q as i64 as f64;
    let turns = if t > q { t - 1.0 } else { t };
    x - TAU * turns
}

impl Track {
    /// The tracks of `defect` for a bearing of `balls` balls with raceway diameters
    /// `d_i`, `d_o` (m) and balls of diameter `ball_diameter` (m). Ball spin: the
    /// ball turns relative to the cage by `β = (d_i / D) ψ_in`, `D = (d_o − d_i)/2`
    /// (rolling without slip on both races, docs/model.md §2.9).
    pub fn of(
        defect: &Defect,
        balls: usize,
        (d_i, d_o): (f64, f64),
        ball_diameter: f64,
    ) -> Vec<Track> {
        let ball_radius = 0.5 * ball_diameter;
        let geometric = defect.geometric_depth(ball_diameter);
        let floor = defect.effective_depth(ball_diameter);
        // Where the depth, not the width, limits the ball, a rounded ramp reaches
        // the floor at d*; else only at the centre, where both edges hold the ball:
        // the whole defect is ramp (its value at the centre is the floor).
        let ramp_end = if defect.depth < geometric {
            (floor * (2.0 * ball_radius - floor)).sqrt()
        } else {
            f64::INFINITY
        };
        let track =
            |inner: bool, ratio: f64, per_ball: f64, centre: f64, radius: f64, balls: usize| {
                let chunks = balls.div_ceil(LANES);
                let mut start = vec![F64x4::ZERO; chunks];
                let mut meets = vec![F64x4::ZERO; chunks];
                for r in 0..balls {
                    start[r / LANES].0[r % LANES] =
                        wrap(per_ball * TAU * r as f64 / balls as f64 - centre);
                    meets[r / LANES].0[r % LANES] = f64::from_bits(u64::MAX);
                }
                Track {
                    inner,
                    ratio,
                    start,
                    meets,
                    radius,
                    balls,
                    half_width: 0.5 * defect.width,
                    whole: defect.width >= TAU * radius,
                    rounded: defect.profile == DefectProfile::Rounded,
                    ball_radius,
                    floor,
                    ramp_end,
                }
            };
        let a = defect.angle;
        match defect.race {
            DefectRace::Outer => vec![track(false, 1.0, 1.0, a, 0.5 * d_o, balls)],
            DefectRace::Inner => vec![track(true, 1.0, 1.0, a, 0.5 * d_i, balls)],
            DefectRace::Ball => {
                // The defect at β + angle from the outward radial direction faces
                // the outer race at 0 and the inner race at π.
                let spin = d_i / (0.5 * (d_o - d_i));
                vec![
                    track(true, spin, 0.0, -a, ball_radius, 1),
                    track(true, spin, 0.0, PI - a, ball_radius, 1),
                ]
            }
        }
    }

    /// `wrap(ratio ψ)` (rad) at state `s`: the track angle of a ball with `start_r = 0`.
    #[inline(always)]
    pub fn base_angle(&self, s: &ContactState) -> f64 {
        let psi = if self.inner { s.psi_in } else { s.psi_out };
        wrap(self.ratio * psi)
    }

    /// Arc position `s` (m) of ball `r` (0-based, below [`Track::balls`]) from the
    /// defect's centre, in `[−π radius, π radius]`, for [`Track::base_angle`] `base`:
    /// lane `r` of [`Track::positions`], computed alone.
    pub fn position(&self, r: usize, base: f64) -> f64 {
        let x = wrap_once(F64x4::splat(base + self.start[r / LANES].0[r % LANES]));
        self.radius * x.0[0]
    }

    /// Number of ball vectors ([`LANES`] balls each) the track spans.
    pub fn chunks(&self) -> usize {
        self.start.len()
    }

    /// Arc positions (m) of ball vector `i` for [`Track::base_angle`] `base`.
    #[inline(always)]
    pub fn positions<V: Lanes>(&self, i: usize, base: f64) -> V {
        V::splat(self.radius) * wrap_once(V::splat(base) + V::load(&self.start[i]))
    }

    /// The zones balls at positions `pos` (m) are in, as lane masks.
    #[inline(always)]
    pub fn zone_masks<V: Lanes>(&self, pos: V) -> (V, V) {
        if self.whole {
            return (V::zero(), V::splat(f64::from_bits(u64::MAX)));
        }
        let inside = V::splat(self.half_width) - pos.abs();
        let on = inside.simd_gt(V::zero());
        if !self.rounded {
            return (V::zero(), on);
        }
        let ramp = on & V::splat(self.ramp_end).simd_gt(inside);
        (ramp, ramp.bitselect(V::zero(), on))
    }

    /// The lowerings (m) of ball vector `i` at positions `pos` (m) in zones
    /// `(ramp, floor)`, 0 for balls that do not meet the track, and their margins
    /// ([`Track::margin`], `+∞` for balls that do not meet it).
    #[inline(always)]
    pub fn lowerings<V: Lanes>(&self, i: usize, pos: V, (ramp, floor): (V, V)) -> (V, V) {
        let meets = V::load(&self.meets[i]);
        let mut lowering = floor & V::splat(self.floor);
        if self.whole {
            return (lowering & meets, V::splat(f64::INFINITY));
        }
        let inside = V::splat(self.half_width) - pos.abs();
        let mut margin = floor.bitselect(inside, -inside);
        if self.rounded {
            let ramp_end = V::splat(self.ramp_end);
            let on_ramp = (ramp & meets).to_array();
            if on_ramp.iter().any(|m| m.to_bits() != 0) {
                // Rare (balls on a rounded edge): the ramp's curve lane by lane.
                let p = pos.to_array();
                let mut curve = [0.0; LANES];
                for l in 0..LANES {
                    if on_ramp[l].to_bits() != 0 {
                        curve[l] = self.lowering(Zone::Ramp, p[l]).0;
                    }
                }
                lowering = ramp.bitselect(V::load(&F64x4(curve)), lowering);
            }
            margin = ramp.bitselect(
                inside.fast_min(ramp_end - inside),
                floor.bitselect(inside - ramp_end, -inside),
            );
        }
        (
            lowering & meets,
            meets.bitselect(margin, V::splat(f64::INFINITY)),
        )
    }

    /// `ds/dψ` (m/rad).
    pub fn arc_rate(&self) -> f64 {
        self.radius * self.ratio
    }

    /// The zone a ball at arc position `pos` (m) is in.
    #[inline(always)]
    pub fn zone(&self, pos: f64) -> Zone {
        if self.whole {
            return Zone::Floor;
        }
        let inside = self.half_width - pos.abs();
        if inside <= 0.0 {
            Zone::Outside
        } else if self.rounded && inside < self.ramp_end {
            Zone::Ramp
        } else {
            Zone::Floor
        }
    }

    /// The lowering of the deflection (m) of a ball at `pos` (m) in `zone`, and its
    /// derivative along the track (m/m). Continued smoothly past the zone's ends:
    /// the ramp's `d²/(R_b + √(R_b² − d²))` is even in `d` (with `d²` capped at `R_b²`).
    #[inline(always)]
    pub fn lowering(&self, zone: Zone, pos: f64) -> (f64, f64) {
        match zone {
            Zone::Outside => (0.0, 0.0),
            Zone::Floor => (self.floor, 0.0),
            Zone::Ramp => {
                let r = self.ball_radius;
                let d = self.half_width - pos.abs();
                if d * d >= r * r {
                    return (r, 0.0);
                }
                let root = (r * r - d * d).sqrt();
                // d/dpos of R − √(R² − d²) with dd/dpos = −sign(pos).
                (d * d / (r + root), -pos.signum() * d / root)
            }
        }
    }
}

/// The tracks of a bearing's defects of nonzero depth; `None` without any, so a
/// case without defects builds no defect code into its kernel (docs/model.md §2.9).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Defects {
    pub tracks: Vec<Track>,
}

impl Defects {
    /// The tracks of `params`' defects of nonzero depth, or `None`.
    pub fn of(params: &super::BearingParams) -> Option<Self> {
        let tracks: Vec<Track> = params
            .defects
            .iter()
            .filter(|d| d.depth > 0.0)
            .flat_map(|d| {
                Track::of(
                    d,
                    params.ball_count,
                    (params.inner_race_diameter, params.outer_race_diameter),
                    params.ball_diameter,
                )
            })
            .collect();
        (!tracks.is_empty()).then_some(Self { tracks })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(profile: DefectProfile, width: f64, depth: f64) -> Track {
        let d = Defect {
            race: DefectRace::Outer,
            angle: 0.0,
            width,
            depth,
            profile,
        };
        Track::of(&d, 9, (29.2e-3, 46.6e-3), 8.7e-3).remove(0)
    }

    /// The margin of ball 0 at `pos` (m) held in `zone`, from the lanes.
    fn margin(t: &Track, zone: Zone, pos: f64) -> f64 {
        let mask = |on: bool| F64x4::splat(if on { f64::from_bits(u64::MAX) } else { 0.0 });
        let zones = (mask(zone == Zone::Ramp), mask(zone == Zone::Floor));
        t.lowerings::<F64x4>(0, F64x4::splat(pos), zones).1 .0[0]
    }

    #[test]
    fn lanes_agree_with_the_ball_by_ball_zones_and_lowerings() {
        for profile in [DefectProfile::Flat, DefectProfile::Rounded] {
            let t = track(profile, 1e-3, 20e-6);
            for k in 0..2000 {
                let base = -PI + TAU * k as f64 / 2000.0;
                for i in 0..t.chunks() {
                    let pos = t.positions::<F64x4>(i, base);
                    let zones = t.zone_masks(pos);
                    let (low, _) = t.lowerings(i, pos, zones);
                    let masks = ZoneMasks {
                        ramp: zones.0,
                        floor: zones.1,
                    };
                    for l in 0..LANES {
                        let r = i * LANES + l;
                        if r >= t.balls {
                            assert_eq!(low.0[l], 0.0);
                            continue;
                        }
                        let p = t.position(r, base);
                        assert_eq!(p, pos.0[l]);
                        assert_eq!(masks.zone(l), t.zone(p));
                        assert_eq!(low.0[l], t.lowering(t.zone(p), p).0);
                    }
                }
            }
        }
    }

    #[test]
    fn effective_depth_is_what_the_ball_reaches() {
        let r: f64 = 4.35e-3;
        // 1 mm wide: the ball reaches R − √(R² − 0.25 mm²) ≈ 28.8 µm; a 20 µm deep
        // spall is deeper than that is not, so 20 µm; a 40 µm one is capped.
        let reach = r - (r * r - 0.5e-3f64.powi(2)).sqrt();
        assert!((reach - 28.84e-6).abs() < 0.01e-6, "{reach}");
        let shallow = track(DefectProfile::Flat, 1e-3, 20e-6);
        assert_eq!(shallow.lowering(Zone::Floor, 0.0).0, 20e-6);
        let deep = track(DefectProfile::Flat, 1e-3, 40e-6);
        assert!((deep.lowering(Zone::Floor, 0.0).0 - reach).abs() < 1e-18);
    }

    #[test]
    fn rounded_ramp_is_continuous_and_meets_the_floor() {
        let t = track(DefectProfile::Rounded, 1e-3, 20e-6);
        let edge = 0.5e-3;
        // At the edge the ramp starts from 0 with zero slope.
        let (h, slope) = t.lowering(Zone::Ramp, edge);
        assert!(h.abs() < 1e-20 && slope.abs() < 1e-12);
        // Where the natural zone turns to the floor, the ramp has reached it.
        let pos = edge - t.ramp_end;
        assert!((t.lowering(Zone::Ramp, pos).0 - t.lowering(Zone::Floor, pos).0).abs() < 1e-15);
        assert_eq!(t.zone(pos - 1e-9), Zone::Floor);
        assert_eq!(t.zone(pos + 1e-9), Zone::Ramp);
        assert_eq!(t.zone(edge + 1e-9), Zone::Outside);
        // The slope is the derivative of the lowering.
        let (x, dx) = (0.45e-3, 1e-9);
        let numeric =
            (t.lowering(Zone::Ramp, x + dx).0 - t.lowering(Zone::Ramp, x - dx).0) / (2.0 * dx);
        assert!((numeric - t.lowering(Zone::Ramp, x).1).abs() < 1e-6 * numeric.abs());
    }

    #[test]
    fn a_rounded_defect_narrower_than_its_depth_is_all_ramp() {
        // 0.5 mm wide, 20 µm deep: the ball reaches 7.2 µm, at the centre only.
        let t = track(DefectProfile::Rounded, 0.5e-3, 20e-6);
        assert_eq!(t.zone(0.0), Zone::Ramp);
        assert_eq!(margin(&t, Zone::Ramp, 0.0), 0.25e-3);
        let (centre, slope) = t.lowering(Zone::Ramp, 0.0);
        assert!((centre - t.lowering(Zone::Floor, 0.0).0).abs() < 1e-20);
        assert!(
            slope.abs() < 0.1 && (7.17e-6..7.2e-6).contains(&centre),
            "{centre} {slope}"
        );
    }

    #[test]
    fn margins_are_positive_inside_the_zone_and_change_sign_at_its_ends() {
        for profile in [DefectProfile::Flat, DefectProfile::Rounded] {
            let t = track(profile, 1e-3, 20e-6);
            for pos in [-2e-3, -0.49e-3, -0.2e-3, 0.0, 0.3e-3, 0.499e-3, 0.6e-3] {
                let z = t.zone(pos);
                assert!(margin(&t, z, pos) >= 0.0, "{profile:?} at {pos}: {z:?}");
                for other in [Zone::Outside, Zone::Ramp, Zone::Floor] {
                    if other != z && (profile == DefectProfile::Rounded || other != Zone::Ramp) {
                        assert!(
                            margin(&t, other, pos) <= 0.0,
                            "{profile:?} {other:?} at {pos}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_defect_as_wide_as_the_race_covers_it() {
        let t = track(DefectProfile::Flat, TAU * 23.3e-3, 20e-6);
        for pos in [-70e-3, 0.0, 70e-3] {
            assert_eq!(t.zone(pos), Zone::Floor);
            assert_eq!(margin(&t, Zone::Floor, pos), f64::INFINITY);
        }
        assert_eq!(t.lowering(Zone::Floor, 1.0).0, 20e-6);
    }

    #[test]
    fn fault_labels_name_the_races_with_depth() {
        let d = |race, depth| Defect {
            race,
            depth,
            ..Defect::default()
        };
        assert_eq!(fault_label(&[]), "none");
        assert_eq!(fault_label(&[d(DefectRace::Outer, 0.0)]), "none");
        assert_eq!(
            fault_label(&[d(DefectRace::Ball, 1e-6), d(DefectRace::Outer, 1e-6)]),
            "outer+ball"
        );
    }

    #[test]
    fn refusals_name_the_field() {
        let bad = [
            Defect {
                width: 0.0,
                ..Defect::default()
            },
            Defect {
                depth: -1e-6,
                ..Defect::default()
            },
            Defect {
                angle: f64::NAN,
                ..Defect::default()
            },
        ];
        let fields: Vec<String> = bad
            .iter()
            .map(|d| d.validate("bearing.defects[0]").unwrap_err().field)
            .collect();
        assert_eq!(
            fields,
            [
                "bearing.defects[0].width",
                "bearing.defects[0].depth",
                "bearing.defects[0].angle"
            ]
        );
    }
}
