//! A general planar multibody core: rigid bodies in Cartesian coordinates, ideal
//! joints, a rheonomic driver, gravity and force elements between bodies.
//!
//! # Formulation and constraint drift
//!
//! Each moving body has coordinates `(x, y, θ)`; `q` stacks them. The constraints
//! `Φ(q, t) = 0` are enforced by **coordinate partitioning** (Wehage & Haug 1982):
//! the caller names `n − m` *independent* coordinates `z` (for a bearing case, the
//! journal's position); the integrator only sees `y = (z, ż)`. At every evaluation
//! the *dependent* coordinates `u` are recomputed from `z` and `t` by Newton's method
//! on `Φ(u; z, t) = 0` until the update is below 1e-10 (so the residual is at
//! round-off, ~1e-16 m), and `u̇` from the velocity equation `Φu u̇ = −Φz ż − Φt`.
//! Positions and velocities therefore satisfy the constraints to round-off at every
//! step: there is no drift to control, and no Baumgarte parameters to tune. The
//! accelerations follow from the index-1 system of docs/model.md §1 reduced to the
//! independent coordinates, `(Bᵀ M B) z̈ = Bᵀ (Q − M c)` with `q̈ = B z̈ + c`;
//! the multipliers from `Φuᵀ λ = (Q − M q̈)_u`. The drift actually left is
//! measured by [`System::position_residual`] and [`System::velocity_residual`] and
//! tested over 20 revolutions.
//!
//! # Energy ledger
//!
//! With [`System::with_energy_ledger`], three quadratures ride along in the state:
//! the work of the rheonomic constraints (`∫ λᵀΦt dt`, the driver's work), the
//! explicit-time term `∫ ∂V/∂t dt` of the force elements, and the energy they
//! dissipate, so that docs/model.md §4.4's balance can be checked to integration accuracy.

mod body;
mod constraint;
mod force;

pub use body::{add_point_force, rotate, Body, BodyRef, Pose};
pub use constraint::Constraint;
pub use force::{ElementEnergy, ForceElement};

use crate::error::{ModelError, ParamError};
use crate::numeric::linalg::Lu;
use crate::solve::OdeSystem;
use constraint::Rows;

/// Newton stops once its update is below this (m or rad); the error left is then
/// of the order of its square.
const NEWTON_STEP_TOL: f64 = 1e-10;
/// Newton iterations allowed per evaluation before giving up.
const NEWTON_MAX_ITER: usize = 25;
/// Number of energy-ledger quadratures appended to the state.
pub const LEDGER_LEN: usize = 3;

/// The energy ledger's quadratures, read from the end of a state vector.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Ledger {
    /// Work done by rheonomic constraints (drivers) on the bodies (J).
    pub driver_work: f64,
    /// `∫ ∂V/∂t dt` of the force elements (J).
    pub explicit_potential_work: f64,
    /// Energy dissipated by the force elements (J).
    pub dissipated: f64,
}

/// A planar multibody system with force elements of type `F`.
#[derive(Debug, Clone)]
pub struct System<F> {
    bodies: Vec<Body>,
    constraints: Vec<Constraint>,
    row_start: Vec<usize>,
    elements: Vec<F>,
    gravity: Option<f64>,
    independent: Vec<usize>,
    dependent: Vec<usize>,
    ledger: bool,
    ws: Workspace,
}

/// Buffers reused by every evaluation (allocated once).
#[derive(Debug, Clone)]
struct Workspace {
    q: Vec<f64>,
    /// Positions at the last accepted step: Newton's starting guess for every
    /// evaluation, so that a wild trial stage (of a step that will be rejected)
    /// can neither poison the next guess nor move Newton onto another branch of
    /// the constraints (e.g. the mirrored rod).
    q_anchor: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    phi: Vec<f64>,
    phit: Vec<f64>,
    gamma: Vec<f64>,
    jac: Vec<f64>,
    jac_u: Vec<f64>,
    lu: Lu,
    /// `B_u = −Φu⁻¹ Φz`, one column of length `m` per independent coordinate.
    b_u: Vec<f64>,
    c_u: Vec<f64>,
    forces: Vec<f64>,
    reduced: Vec<f64>,
    reduced_lu: Lu,
    reduced_rhs: Vec<f64>,
    scratch_m: Vec<f64>,
    scratch_z: Vec<f64>,
}

impl Workspace {
    /// Zeroed buffers for `n` coordinates, `m` constraint equations and `nz`
    /// independent coordinates.
    fn new(n: usize, m: usize, nz: usize) -> Self {
        Self {
            q: vec![0.0; n],
            q_anchor: vec![0.0; n],
            qd: vec![0.0; n],
            qdd: vec![0.0; n],
            lambda: vec![0.0; m],
            phi: vec![0.0; m],
            phit: vec![0.0; m],
            gamma: vec![0.0; m],
            jac: vec![0.0; m * n],
            jac_u: vec![0.0; m * m],
            lu: Lu::new(m),
            b_u: vec![0.0; m * nz],
            c_u: vec![0.0; m],
            forces: vec![0.0; n],
            reduced: vec![0.0; nz * nz],
            reduced_lu: Lu::new(nz),
            reduced_rhs: vec![0.0; nz],
            scratch_m: vec![0.0; m],
            scratch_z: vec![0.0; nz],
        }
    }
}

/// Refuses a body whose mass (kg) or inertia (kg m²) is not finite and positive, and
/// a non-finite gravity (m/s²).
fn check_bodies(bodies: &[Body], gravity: Option<f64>) -> Result<(), ParamError> {
    for (k, b) in bodies.iter().enumerate() {
        if !(b.mass.is_finite() && b.mass > 0.0) {
            return Err(ParamError::new(
                format!("bodies[{k}].mass"),
                b.mass,
                "finite and > 0 kg",
            ));
        }
        if !(b.inertia.is_finite() && b.inertia > 0.0) {
            return Err(ParamError::new(
                format!("bodies[{k}].inertia"),
                b.inertia,
                "finite and > 0 kg m^2",
            ));
        }
    }
    if let Some(g) = gravity {
        if !g.is_finite() {
            return Err(ParamError::new(
                "gravity",
                g,
                "a finite acceleration in m/s^2",
            ));
        }
    }
    Ok(())
}

/// The first row of each constraint in `Φ`, and the dependent coordinates: those
/// of `q` not in `independent`, which must name `3 × bodies − constraint rows`
/// distinct coordinates.
fn partition(
    bodies: &[Body],
    constraints: &[Constraint],
    independent: &[usize],
) -> Result<(Vec<usize>, Vec<usize>), ParamError> {
    let n = 3 * bodies.len();
    let mut row_start = Vec::with_capacity(constraints.len());
    let mut m = 0;
    for c in constraints {
        row_start.push(m);
        m += c.rows();
    }
    if m > n || independent.len() != n - m {
        return Err(ParamError::new(
            "independent",
            format!("{} coordinates", independent.len()),
            format!(
                "exactly {} (3 x {} bodies - {m} constraint equations)",
                n.saturating_sub(m),
                bodies.len()
            ),
        ));
    }
    let mut is_indep = vec![false; n];
    for &k in independent {
        if k >= n || is_indep[k] {
            return Err(ParamError::new(
                "independent",
                k,
                format!("distinct coordinate indices below {n}"),
            ));
        }
        is_indep[k] = true;
    }
    let dependent = (0..n).filter(|&k| !is_indep[k]).collect();
    Ok((row_start, dependent))
}

/// The generalised mass of coordinate `k` of `q`: its body's inertia (kg m²) for an
/// angle, its mass (kg) for a position.
#[inline]
fn generalised_mass(bodies: &[Body], k: usize) -> f64 {
    let b = &bodies[k / 3];
    if k % 3 == 2 {
        b.inertia
    } else {
        b.mass
    }
}

impl<F: ForceElement> System<F> {
    /// Assembles a system. `independent` lists the indices in `q` of the
    /// coordinates the integrator advances (`3 × bodies − constraint rows` of them);
    /// `gravity` is the acceleration along −y (m/s²) when the effect is on.
    pub fn new(
        bodies: Vec<Body>,
        constraints: Vec<Constraint>,
        elements: Vec<F>,
        gravity: Option<f64>,
        independent: Vec<usize>,
    ) -> Result<Self, ParamError> {
        check_bodies(&bodies, gravity)?;
        let (row_start, dependent) = partition(&bodies, &constraints, &independent)?;
        let ws = Workspace::new(3 * bodies.len(), dependent.len(), independent.len());
        Ok(Self {
            bodies,
            constraints,
            row_start,
            elements,
            gravity,
            independent,
            dependent,
            ledger: false,
            ws,
        })
    }

    /// Turns the energy ledger (three extra quadrature states) on or off.
    #[must_use]
    pub fn with_energy_ledger(mut self, on: bool) -> Self {
        self.ledger = on;
        self
    }

    /// Degrees of freedom: the number of independent coordinates.
    pub fn dof(&self) -> usize {
        self.independent.len()
    }

    /// Number of generalised coordinates `3 × bodies`.
    pub fn coordinates(&self) -> usize {
        3 * self.bodies.len()
    }

    /// First row of constraint `k` in `Φ` and `λ`.
    pub fn constraint_row(&self, k: usize) -> usize {
        self.row_start[k]
    }

    /// The force elements (with whatever they kept from the last evaluation).
    pub fn elements(&self) -> &[F] {
        &self.elements
    }

    /// The integrator state for positions `q0` and velocities `qd0` (which must be
    /// consistent with the constraints at the start time); also seeds Newton's
    /// first guess for the dependent coordinates.
    pub fn initial_state(&mut self, q0: &[f64], qd0: &[f64]) -> Vec<f64> {
        self.ws.q.copy_from_slice(q0);
        self.ws.q_anchor.copy_from_slice(q0);
        self.ws.qd.copy_from_slice(qd0);
        let mut y: Vec<f64> = self.independent.iter().map(|&k| q0[k]).collect();
        y.extend(self.independent.iter().map(|&k| qd0[k]));
        if self.ledger {
            y.extend([0.0; LEDGER_LEN]);
        }
        y
    }

    /// Reads the ledger from a state vector (zeros when the ledger is off).
    pub fn ledger(&self, y: &[f64]) -> Ledger {
        if !self.ledger {
            return Ledger::default();
        }
        let l = &y[2 * self.dof()..];
        Ledger {
            driver_work: l[0],
            explicit_potential_work: l[1],
            dissipated: l[2],
        }
    }

    /// Positions (m, rad) from the last evaluation.
    pub fn q(&self) -> &[f64] {
        &self.ws.q
    }

    /// Velocities (m/s, rad/s) from the last evaluation.
    pub fn qd(&self) -> &[f64] {
        &self.ws.qd
    }

    /// Accelerations (m/s², rad/s²) from the last evaluation.
    pub fn qdd(&self) -> &[f64] {
        &self.ws.qdd
    }

    /// Lagrange multipliers from the last evaluation that asked for them. The
    /// constraint force on the bodies is `−Φqᵀ λ`.
    pub fn lambda(&self) -> &[f64] {
        &self.ws.lambda
    }

    /// Evaluates the system at time `t` (s) and state `y`: positions, velocities
    /// and accelerations of every body, and the multipliers when `multipliers`.
    pub fn evaluate(&mut self, t: f64, y: &[f64], multipliers: bool) -> Result<(), ModelError> {
        let nz = self.dof();
        self.ws.q.copy_from_slice(&self.ws.q_anchor);
        for (a, &k) in self.independent.iter().enumerate() {
            self.ws.q[k] = y[a];
            self.ws.qd[k] = y[nz + a];
        }
        self.solve_positions(t)?;
        if nz == 0 {
            // A fully constrained system has no trial states: every evaluation is real.
            self.ws.q_anchor.copy_from_slice(&self.ws.q);
        }
        self.solve_velocities(t);
        self.solve_accelerations(t)?;
        if multipliers {
            self.solve_multipliers();
        }
        Ok(())
    }

    /// Kinetic energy at the last evaluation (J).
    pub fn kinetic_energy(&self) -> f64 {
        let qd = &self.ws.qd;
        self.bodies
            .iter()
            .enumerate()
            .map(|(k, b)| {
                0.5 * b.mass * (qd[3 * k] * qd[3 * k] + qd[3 * k + 1] * qd[3 * k + 1])
                    + 0.5 * b.inertia * qd[3 * k + 2] * qd[3 * k + 2]
            })
            .sum()
    }

    /// Potential energy at the last evaluation: gravity plus the force elements' (J).
    pub fn potential_energy(&self, t: f64) -> f64 {
        let gravity: f64 = match self.gravity {
            Some(g) => self
                .bodies
                .iter()
                .enumerate()
                .map(|(k, b)| b.mass * g * self.ws.q[3 * k + 1])
                .sum(),
            None => 0.0,
        };
        gravity
            + self
                .elements
                .iter()
                .map(|e| e.energy(t, &self.ws.q, &self.ws.qd).potential)
                .sum::<f64>()
    }

    /// Max-norm of `Φ(q, t)` at the last evaluation, recomputed from scratch (m or rad).
    pub fn position_residual(&mut self, t: f64) -> f64 {
        self.assemble_positions(t);
        max_abs(&self.ws.phi)
    }

    /// Max-norm of `Φq q̇ + Φt` at the last evaluation (m/s or rad/s).
    pub fn velocity_residual(&mut self, t: f64) -> f64 {
        self.assemble_positions(t);
        let ws = &mut self.ws;
        let n = ws.q.len();
        for (k, c) in self.constraints.iter().enumerate() {
            let r0 = self.row_start[k];
            c.time_derivative(t, &mut ws.phit[r0..r0 + c.rows()]);
        }
        (0..ws.phi.len())
            .map(|r| {
                let row = &ws.jac[r * n..(r + 1) * n];
                (row.iter().zip(&ws.qd).map(|(a, b)| a * b).sum::<f64>() + ws.phit[r]).abs()
            })
            .fold(0.0, f64::max)
    }

    fn assemble_positions(&mut self, t: f64) {
        let ws = &mut self.ws;
        let n = ws.q.len();
        ws.jac.iter_mut().for_each(|v| *v = 0.0);
        for (k, c) in self.constraints.iter().enumerate() {
            let (r0, r1) = (self.row_start[k], self.row_start[k] + c.rows());
            let mut rows = Rows {
                phi: &mut ws.phi[r0..r1],
                jac: &mut ws.jac[r0 * n..r1 * n],
                n,
            };
            c.position(t, &ws.q, &mut rows);
        }
    }

    /// Newton on the dependent coordinates; leaves `Φu` factored at the solution.
    fn solve_positions(&mut self, t: f64) -> Result<(), ModelError> {
        let m = self.dependent.len();
        let mut converged = false;
        for iteration in 0..NEWTON_MAX_ITER {
            self.assemble_positions(t);
            let ws = &mut self.ws;
            let n = ws.q.len();
            for r in 0..m {
                for (c, &k) in self.dependent.iter().enumerate() {
                    ws.jac_u[r * m + c] = ws.jac[r * n + k];
                }
            }
            ws.lu
                .factor(&ws.jac_u)
                .map_err(|_| ModelError::SingularConstraints)?;
            if converged {
                return Ok(());
            }
            for (d, p) in ws.c_u.iter_mut().zip(&ws.phi) {
                *d = -p;
            }
            ws.lu.solve_in_place(&mut ws.c_u, &mut ws.scratch_m);
            let mut step = 0.0f64;
            for (&k, d) in self.dependent.iter().zip(&ws.c_u) {
                ws.q[k] += d;
                step = step.max(d.abs());
            }
            if !step.is_finite() {
                return Err(ModelError::NonFinite {
                    what: "position (Newton update)",
                });
            }
            converged = step <= NEWTON_STEP_TOL;
            if iteration + 1 == NEWTON_MAX_ITER {
                break;
            }
        }
        Err(ModelError::ConstraintsNotConverged {
            iterations: NEWTON_MAX_ITER,
            residual: max_abs(&self.ws.phi),
        })
    }

    /// `Φu u̇ = −Φz ż − Φt` at time `t` (s), with `Φu` factored by [`Self::solve_positions`].
    fn solve_velocities(&mut self, t: f64) {
        let ws = &mut self.ws;
        let n = ws.q.len();
        for (k, c) in self.constraints.iter().enumerate() {
            let r0 = self.row_start[k];
            c.time_derivative(t, &mut ws.phit[r0..r0 + c.rows()]);
        }
        for r in 0..self.dependent.len() {
            let row = &ws.jac[r * n..(r + 1) * n];
            ws.c_u[r] = -ws.phit[r]
                - self
                    .independent
                    .iter()
                    .map(|&k| row[k] * ws.qd[k])
                    .sum::<f64>();
        }
        ws.lu.solve_in_place(&mut ws.c_u, &mut ws.scratch_m);
        for (&k, v) in self.dependent.iter().zip(&ws.c_u) {
            ws.qd[k] = *v;
        }
    }

    /// Applied forces, then `q̈` from the reduced equations.
    fn solve_accelerations(&mut self, t: f64) -> Result<(), ModelError> {
        let (m, nz) = (self.dependent.len(), self.independent.len());
        self.applied_forces(t);
        self.transfer(t);
        self.reduced_equations();
        let ws = &mut self.ws;
        if nz > 0 {
            ws.reduced_lu
                .factor(&ws.reduced)
                .map_err(|_| ModelError::SingularConstraints)?;
            ws.reduced_lu
                .solve_in_place(&mut ws.reduced_rhs, &mut ws.scratch_z);
        }
        for (a, &k) in self.independent.iter().enumerate() {
            ws.qdd[k] = ws.reduced_rhs[a];
        }
        for (r, &k) in self.dependent.iter().enumerate() {
            ws.qdd[k] = ws.c_u[r]
                + (0..nz)
                    .map(|a| ws.b_u[a * m + r] * ws.reduced_rhs[a])
                    .sum::<f64>();
        }
        if ws.qdd.iter().any(|v| !v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "acceleration",
            });
        }
        Ok(())
    }

    /// The applied forces `Q` at time `t` (s) into `ws.forces` (N, N m): gravity and
    /// the force elements.
    #[inline]
    fn applied_forces(&mut self, t: f64) {
        let ws = &mut self.ws;
        ws.forces.iter_mut().for_each(|f| *f = 0.0);
        if let Some(g) = self.gravity {
            for (k, b) in self.bodies.iter().enumerate() {
                ws.forces[3 * k + 1] -= b.mass * g;
            }
        }
        for e in &mut self.elements {
            e.add_forces(t, &ws.q, &ws.qd, &mut ws.forces);
        }
    }

    /// The dependent accelerations in terms of the independent ones at time `t` (s),
    /// `ü = B_u z̈ + c_u`: `B_u = −Φu⁻¹ Φz` (dimensionless or m/rad) into `ws.b_u`
    /// and `c_u = Φu⁻¹ γ` (m/s², rad/s²) into `ws.c_u`, with `Φu` factored.
    #[inline]
    fn transfer(&mut self, t: f64) {
        let m = self.dependent.len();
        let ws = &mut self.ws;
        let n = ws.q.len();
        for (k, c) in self.constraints.iter().enumerate() {
            let r0 = self.row_start[k];
            c.gamma(t, &ws.q, &ws.qd, &mut ws.gamma[r0..r0 + c.rows()]);
        }
        for (a, &kz) in self.independent.iter().enumerate() {
            let col = &mut ws.b_u[a * m..(a + 1) * m];
            for (r, c) in col.iter_mut().enumerate() {
                *c = -ws.jac[r * n + kz];
            }
            ws.lu.solve_in_place(col, &mut ws.scratch_m);
        }
        ws.c_u.copy_from_slice(&ws.gamma);
        ws.lu.solve_in_place(&mut ws.c_u, &mut ws.scratch_m);
    }

    /// The reduced mass matrix `Bᵀ M B` into `ws.reduced` and the right-hand side
    /// `Bᵀ (Q − M c)` into `ws.reduced_rhs` (N, N m), from [`Self::transfer`]'s
    /// `B_u`, `c_u` and the applied forces.
    #[inline]
    fn reduced_equations(&mut self) {
        let (m, nz) = (self.dependent.len(), self.independent.len());
        let ws = &mut self.ws;
        let mass = |k: usize| generalised_mass(&self.bodies, k);
        for a in 0..nz {
            let ba = &ws.b_u[a * m..(a + 1) * m];
            for b in 0..nz {
                let bb = &ws.b_u[b * m..(b + 1) * m];
                let mut s: f64 = self
                    .dependent
                    .iter()
                    .enumerate()
                    .map(|(r, &k)| mass(k) * ba[r] * bb[r])
                    .sum();
                if a == b {
                    s += mass(self.independent[a]);
                }
                ws.reduced[a * nz + b] = s;
            }
            ws.reduced_rhs[a] = ws.forces[self.independent[a]]
                + self
                    .dependent
                    .iter()
                    .enumerate()
                    .map(|(r, &k)| ba[r] * (ws.forces[k] - mass(k) * ws.c_u[r]))
                    .sum::<f64>();
        }
    }

    /// `Φuᵀ λ = (Q − M q̈)_u`.
    fn solve_multipliers(&mut self) {
        let ws = &mut self.ws;
        for (r, &k) in self.dependent.iter().enumerate() {
            ws.lambda[r] = ws.forces[k] - generalised_mass(&self.bodies, k) * ws.qdd[k];
        }
        ws.lu
            .solve_transpose_in_place(&mut ws.lambda, &mut ws.scratch_m);
    }
}

impl<F: ForceElement> OdeSystem for System<F> {
    fn dim(&self) -> usize {
        2 * self.dof() + if self.ledger { LEDGER_LEN } else { 0 }
    }

    fn rhs(&mut self, t: f64, y: &[f64], dydt: &mut [f64]) -> Result<(), ModelError> {
        self.evaluate(t, y, self.ledger)?;
        let nz = self.dof();
        for (a, &k) in self.independent.iter().enumerate() {
            dydt[a] = self.ws.qd[k];
            dydt[nz + a] = self.ws.qdd[k];
        }
        if self.ledger {
            let ws = &self.ws;
            let driver_power: f64 = ws.lambda.iter().zip(&ws.phit).map(|(l, p)| l * p).sum();
            let (mut rate, mut dissipation) = (0.0, 0.0);
            for e in &self.elements {
                let en = e.energy(t, &ws.q, &ws.qd);
                rate += en.potential_rate;
                dissipation += en.dissipation;
            }
            dydt[2 * nz] = driver_power;
            dydt[2 * nz + 1] = rate;
            dydt[2 * nz + 2] = dissipation;
        }
        Ok(())
    }

    /// Re-anchors Newton's starting guess at the accepted state's positions.
    fn accept_step(&mut self, t: f64, y: &[f64]) -> Result<(), ModelError> {
        self.ws.q.copy_from_slice(&self.ws.q_anchor);
        for (a, &k) in self.independent.iter().enumerate() {
            self.ws.q[k] = y[a];
        }
        self.solve_positions(t)?;
        self.ws.q_anchor.copy_from_slice(&self.ws.q);
        Ok(())
    }
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |a, b| a.max(b.abs()))
}
