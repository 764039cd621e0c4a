#!/usr/bin/env python3
"""Independent SciPy baseline for studyrun: one paper case in minimal coordinates.

Case (docs/model.md, paper Example 1): bearing at crank_ground, 300 rpm, 9 balls,
waviness N = 35, 4 um on both races, diametral clearance P_d = 40 um,
K = 9.57e9 N/m^1.5, C = 300 N s/m compression-only damping, no gravity,
0.4 s simulated, outputs at 50 kHz (20 001 samples). Integrator: SciPy
``solve_ivp(method="LSODA", rtol=1e-8, atol=1e-12, dense_output=True)``.

Formulation: Lagrange's equations (virtual power) in minimal coordinates with
closed-form kinematics -- no constraint equations, no DAE, no drift.

* Generalised coordinates ``p = (ex, ey, th)``: ``(ex, ey)`` is the crank pivot
  (= the journal centre; the housing is the ground at the origin, so this is the
  bearing eccentricity e), ``th`` is the crank angle theta2. ``th`` is prescribed,
  ``th = w t``, so the state is ``(ex, ey, vx, vy)`` (2 DOF).
* Kinematics in closed form (slider on the x axis, slider to the right of the
  crank pin, theta3 in (-pi/2, pi/2)):
      crank CoM  r2 = e + a (cos th, sin th),        a = L2/2
      crank pin  A  = e + L2 (cos th, sin th)
      W = sqrt(L3^2 - Ay^2) = L3 cos th3,  sin th3 = -Ay / L3
      rod CoM    r3 = (Ax + W/2, Ay/2),    th3 = -asin(Ay/L3)
      slider     x4 = Ax + W,  y4 = 0
  Every body velocity is linear in pdot: v_k = J_k(p) pdot; every acceleration is
  J_k pddot + b_k(p, pdot), b_k the convective part (pddot = 0), computed from
      Axdd = exdd - L2 s thdd - L2 c thd^2,   Aydd = eydd + L2 c thdd - L2 s thd^2
      Wd   = -Ay Ayd / W
      Wdd  = -(Ayd^2 + Ay Aydd)/W - Ay^2 Ayd^2 / W^3
      th3dd = -Aydd/W - Ay Ayd^2 / W^3
* Virtual power, ideal joints do no work, so with the 3x3 generalised mass
  Mbar = sum_k J_k^T M_k J_k and h = sum_k J_k^T M_k b_k:
      Mbar pddot + h = Qbar + (0, 0, tau)
  where Qbar is the generalised applied force and tau the torque the driver applies
  to the crank (the "crank moment", = -lambda_driver of docs/model.md). With thdd = 0 the
  first two rows give eddot (a 2x2 solve); the third row then gives tau.
* Bearing (docs/model.md section 2): cage angle phi_c = d_i th / (d_i + d_o) (outer race
  on the ground), ball r at phi_r = 2 pi (r-1)/N_b + phi_c, n_r = (cos, sin) phi_r,
  Pi_i = Pi_p sin(N psi_in), psi_in = phi_r - th; Pi_o = Pi_p sin(N psi_out),
  psi_out = phi_r; delta_r = e.n_r - P_d/2 + Pi_i + Pi_o; F_r = K delta^1.5 +
  C max(v.n_r, 0) for delta_r > 0; F = sum F_r n_r. The housing (ground) receives
  +F, the journal (crank, at its pivot P = e) receives -F, so Qbar = (-Fx, -Fy, 0)
  (the pivot does not move with th at fixed e, so -F does no virtual work on th).
  Gravity (off here) would add m_k g to the y rows of bodies 2..4.

Initial conditions: e = 0, edot = 0 (the ideal mechanism: crank CoM velocity
(0, w L2/2)); theta2(0) = 0.

Outputs at t_k = k / 50 kHz from the dense output (state interpolated, outputs
recomputed from the state): slider acceleration x4dd, crank moment tau, |F|.

Checks: ``--energy`` closes docs/model.md section 4.4's balance W_driver = dKE + dV -
int dV/dt|_e dt (+ E_damped) to ~1e-11 of the driver work (C = 300 and C = 0);
at LSODA rtol 1e-11 the outputs agree with studyrun's DOPRI5 at rtol 1e-12 to ~2e-7
of each channel's range over the whole 0.4 s.

Usage:
    python benches/scipy_baseline.py --out baseline.npz
    python benches/scipy_baseline.py --compare /tmp/baseline_case.h5
    python benches/scipy_baseline.py --compare /tmp/baseline_case.h5 --reference TIGHT.h5
        (TIGHT.h5: studyrun on the same case at rtol 1e-12; splits the difference into
        each integrator's own error)
    python benches/scipy_baseline.py --rtol 1e-11 --atol 1e-14 ...   # other tolerances
    python benches/scipy_baseline.py --energy      # energy balance check (docs/model.md §4.4)
"""

import argparse
import math
import sys
import time

import numpy as np
from scipy.integrate import solve_ivp

# ---------------------------------------------------------------- parameters
L2, L3 = 0.05, 0.12
M2, J2 = 0.30, 1.0e-4
M3, J3 = 0.21, 2.5e-4
M4 = 0.14
RPM = 300.0
W = 2.0 * math.pi * RPM / 60.0  # crank speed, rad/s
NB = 9
D_IN, D_OUT = 29.2e-3, 46.6e-3
PD = 40e-6  # diametral clearance
K = 9.57e9
C = 300.0
WAVE_N = 35
WAVE_AMP = 4e-6  # both races, phase 0, offset 0
DURATION = 0.4
RATE = 50_000.0
RTOL, ATOL = 1e-8, 1e-12

A2 = 0.5 * L2
CAGE = D_IN / (D_IN + D_OUT)  # phi_c = CAGE * theta2 (outer race fixed)
BALL0 = 2.0 * np.pi * np.arange(NB) / NB


# ------------------------------------------------------------------ bearing
def bearing_force(t, ex, ey, vx, vy, damping=C):
    """Bearing reaction F = (Fx, Fy) on the housing (the journal gets -F) and the
    number of loaded balls. Vectorised over the balls."""
    th = W * t
    phi = BALL0 + CAGE * th
    cphi = np.cos(phi)
    sphi = np.sin(phi)
    # waviness: inner race turns with the crank (psi_in = phi - th), the outer is fixed
    # (psi_out = phi): Pi_i + Pi_o = A (sin(N (phi - th)) + sin(N phi))
    nphi = WAVE_N * phi
    delta = (ex * cphi + ey * sphi - 0.5 * PD
             + WAVE_AMP * (np.sin(nphi - WAVE_N * th) + np.sin(nphi)))
    if delta.max() <= 0.0:
        return 0.0, 0.0, 0
    loaded = delta > 0.0
    d = np.where(loaded, delta, 0.0)
    vr = vx * cphi + vy * sphi
    f = K * d * np.sqrt(d) + damping * np.where(loaded & (vr > 0.0), vr, 0.0)
    return float(f @ cphi), float(f @ sphi), int(np.count_nonzero(loaded))


def hertz_potential(t, ex, ey):
    """V = sum 0.4 K delta^2.5 and dV/dt|_e (explicit time dependence)."""
    th = W * t
    phi = BALL0 + CAGE * th
    dphi = CAGE * W
    cphi, sphi = np.cos(phi), np.sin(phi)
    delta = (ex * cphi + ey * sphi - 0.5 * PD
             + WAVE_AMP * np.sin(WAVE_N * (phi - th))
             + WAVE_AMP * np.sin(WAVE_N * phi))
    ddelta_dt = ((-ex * sphi + ey * cphi) * dphi
                 + WAVE_AMP * WAVE_N * np.cos(WAVE_N * (phi - th)) * (dphi - W)
                 + WAVE_AMP * WAVE_N * np.cos(WAVE_N * phi) * dphi)
    m = delta > 0
    d = delta[m]
    V = float(np.sum(0.4 * K * d ** 2.5))
    dVdt = float(np.sum(K * d ** 1.5 * ddelta_dt[m]))
    return V, dVdt


# ------------------------------------------------------------------ dynamics
def dynamics(t, ex, ey, vx, vy, damping=C):
    """Minimal-coordinate equations of motion. Returns
    (exdd, eydd, x4dd, tau, Fx, Fy, nloaded)."""
    th = W * t
    thd = W
    c, s = math.cos(th), math.sin(th)
    Ay = ey + L2 * s  # crank pin height (Ax does not enter the dynamics)
    Ayd = vy + L2 * c * thd
    Wr = math.sqrt(L3 * L3 - Ay * Ay)
    q = Ay / Wr
    # Jacobian rows d(velocity)/d(exd, eyd, thd)
    # crank CoM
    j2x = (1.0, 0.0, -A2 * s)
    j2y = (0.0, 1.0, A2 * c)
    # crank pin A
    jAx = (1.0, 0.0, -L2 * s)
    jAy = (0.0, 1.0, L2 * c)
    # Wd = -q Ayd
    jW = (-q * jAy[0], -q * jAy[1], -q * jAy[2])
    j3x = (jAx[0] + 0.5 * jW[0], jAx[1] + 0.5 * jW[1], jAx[2] + 0.5 * jW[2])
    j3y = (0.5 * jAy[0], 0.5 * jAy[1], 0.5 * jAy[2])
    j3t = (-jAy[0] / Wr, -jAy[1] / Wr, -jAy[2] / Wr)
    j4x = (jAx[0] + jW[0], jAx[1] + jW[1], jAx[2] + jW[2])
    # convective accelerations (pddot = 0)
    b2x = -A2 * c * thd * thd
    b2y = -A2 * s * thd * thd
    bAx = -L2 * c * thd * thd
    bAy = -L2 * s * thd * thd
    W3 = Wr * Wr * Wr
    bW = -(Ayd * Ayd + Ay * bAy) / Wr - Ay * Ay * Ayd * Ayd / W3
    b3x = bAx + 0.5 * bW
    b3y = 0.5 * bAy
    b3t = -bAy / Wr - Ay * Ayd * Ayd / W3
    b4x = bAx + bW
    rows = ((M2, j2x, b2x), (M2, j2y, b2y), (J2, (0.0, 0.0, 1.0), 0.0),
            (M3, j3x, b3x), (M3, j3y, b3y), (J3, j3t, b3t), (M4, j4x, b4x))
    Mb = [[0.0] * 3 for _ in range(3)]
    h = [0.0, 0.0, 0.0]
    for m, j, b in rows:
        for i in range(3):
            mji = m * j[i]
            h[i] += mji * b
            for k in range(3):
                Mb[i][k] += mji * j[k]
    Fx, Fy, nl = bearing_force(t, ex, ey, vx, vy, damping)
    # generalised applied force: the journal (crank pivot = e) receives -F
    r0 = -Fx - h[0]
    r1 = -Fy - h[1]
    det = Mb[0][0] * Mb[1][1] - Mb[0][1] * Mb[1][0]
    exdd = (Mb[1][1] * r0 - Mb[0][1] * r1) / det
    eydd = (Mb[0][0] * r1 - Mb[1][0] * r0) / det
    # third row (thdd = 0): tau = Mbar[2,:2] eddot + h[2] - Qbar[2], Qbar[2] = 0
    tau = Mb[2][0] * exdd + Mb[2][1] * eydd + h[2]
    x4dd = j4x[0] * exdd + j4x[1] * eydd + b4x
    return exdd, eydd, x4dd, tau, Fx, Fy, nl


class Rhs:
    """The NumPy right-hand side with an evaluation counter."""

    def __init__(self, damping=C):
        self.n = 0
        self.damping = damping

    def __call__(self, t, y):
        self.n += 1
        ex, ey, vx, vy = y.tolist()  # Python floats: scalar arithmetic on np.float64 is slower
        exdd, eydd = dynamics(t, ex, ey, vx, vy, self.damping)[:2]
        return np.array((vx, vy, exdd, eydd))


def kinetic_energy(t, ex, ey, vx, vy):
    th = W * t
    c, s = math.cos(th), math.sin(th)
    Ay = ey + L2 * s
    Axd, Ayd = vx - L2 * s * W, vy + L2 * c * W
    Wr = math.sqrt(L3 * L3 - Ay * Ay)
    Wd = -Ay * Ayd / Wr
    v2 = (vx - A2 * s * W) ** 2 + (vy + A2 * c * W) ** 2
    v3 = (Axd + 0.5 * Wd) ** 2 + (0.5 * Ayd) ** 2
    th3d = -Ayd / Wr
    v4 = (Axd + Wd) ** 2
    return 0.5 * (M2 * v2 + J2 * W * W + M3 * v3 + J3 * th3d ** 2 + M4 * v4)


def ideal_slider_acceleration(t):
    """Closed-form slider acceleration of the ideal slider-crank (e = 0)."""
    th = W * t
    c, s = np.cos(th), np.sin(th)
    Ay = L2 * s
    Ayd = L2 * c * W
    Aydd = -L2 * s * W * W
    Wr = np.sqrt(L3 * L3 - Ay * Ay)
    return -L2 * c * W * W - (Ayd * Ayd + Ay * Aydd) / Wr - Ay * Ay * Ayd * Ayd / Wr ** 3


# ------------------------------------------------------------------ run
def run(rtol=RTOL, atol=ATOL, duration=DURATION, damping=C, quiet=False):
    n = int(round(duration * RATE)) + 1
    t_s = np.arange(n) / RATE
    rhs = Rhs(damping)
    y0 = np.zeros(4)
    t0 = time.perf_counter()
    c0 = time.process_time()
    sol = solve_ivp(rhs, (0.0, t_s[-1]), y0, method="LSODA", rtol=rtol, atol=atol,
                    dense_output=True)
    wall = time.perf_counter() - t0
    cpu = time.process_time() - c0
    if not sol.success:
        raise RuntimeError(sol.message)
    nrhs = rhs.n
    # outputs at the sample times from the dense output
    t1 = time.perf_counter()
    Y = sol.sol(t_s)
    out = np.empty((n, 6))
    for k in range(n):
        r = dynamics(t_s[k], *Y[:, k].tolist(), damping)
        out[k] = r[2], r[3], math.hypot(r[4], r[5]), r[4], r[5], r[6]
    wall_out = time.perf_counter() - t1
    res = dict(time=t_s, slider_acceleration=out[:, 0], crank_moment=out[:, 1],
               bearing_force=out[:, 2], bearing_force_x=out[:, 3],
               bearing_force_y=out[:, 4], loaded_balls=out[:, 5],
               eccentricity_x=Y[0], eccentricity_y=Y[1],
               ideal_slider_acceleration=ideal_slider_acceleration(t_s))
    # the RHS alone, on the states of the sample times (no solver around it)
    nb = 2000
    ys = [Y[:, k].copy() for k in range(0, n, n // nb)]
    ts = t_s[::n // nb]
    t2 = time.perf_counter()
    for tk, yk in zip(ts, ys):
        rhs(tk, yk)
    rhs_alone = (time.perf_counter() - t2) / len(ts)
    stats = dict(wall=wall, cpu=cpu, wall_out=wall_out, wall_total=wall + wall_out,
                 nfev=sol.nfev, nrhs=nrhs, njev=sol.njev, nlu=sol.nlu,
                 ns_per_rhs=wall / nrhs * 1e9, ns_rhs_alone=rhs_alone * 1e9)
    if not quiet:
        print(f"SciPy LSODA rtol={rtol:g} atol={atol:g}: integration wall time {wall:.3f} s "
              f"(CPU {cpu:.3f} s), nfev {sol.nfev} (RHS calls counted {nrhs}; njev {sol.njev}, "
              f"nlu {sol.nlu}), {stats['ns_per_rhs']:.0f} ns per RHS (integration wall / nfev; "
              f"the RHS alone {stats['ns_rhs_alone']:.0f} ns); output sampling {wall_out:.3f} s; "
              f"total {wall + wall_out:.3f} s")
        print(f"SCIPY_WALL={wall + wall_out:.3f} SCIPY_INTEGRATION_WALL={wall:.3f} "
              f"SCIPY_NFEV={sol.nfev} SCIPY_NS_PER_RHS={stats['ns_per_rhs']:.0f}")
    return res, stats, sol


# ------------------------------------------------------------------ comparison
CHANNELS = ("slider_acceleration", "crank_moment", "bearing_force")


def compare(res, path, case=0):
    import h5py

    with h5py.File(path, "r") as f:
        loc = f["location"][case]
        loc = loc.decode() if isinstance(loc, bytes) else str(loc)
        params = {k: float(f[k][case]) for k in ("rpm", "ball_count", "clearance", "stiffness",
                                                  "damping", "inner_waviness_number",
                                                  "outer_waviness_number",
                                                  "inner_waviness_amplitude",
                                                  "outer_waviness_amplitude")}
        t = f["time"][()]
        ref = {c: f[c][case, :] for c in CHANNELS}
        ref["eccentricity_x"] = f["eccentricity_x"][case, :]
        ref["eccentricity_y"] = f["eccentricity_y"][case, :]
        ref_ideal = f["reference_slider_acceleration"][int(f["reference_index"][case]), :]
        rhs_evals = int(f["rhs_evals"][case])
        wall = float(f["wall_time"][case])
    expect = dict(rpm=RPM, ball_count=NB, clearance=PD, stiffness=K, damping=C,
                  inner_waviness_number=WAVE_N, outer_waviness_number=WAVE_N,
                  inner_waviness_amplitude=WAVE_AMP, outer_waviness_amplitude=WAVE_AMP)
    bad = {k: (params[k], v) for k, v in expect.items() if abs(params[k] - v) > 1e-12 * abs(v)}
    if loc != "crank_ground" or bad or t.shape != res["time"].shape:
        sys.exit(f"{path}: not the baseline case (location {loc}, mismatches {bad})")
    if np.max(np.abs(t - res["time"])) > 1e-12:
        sys.exit("sample times differ")
    print(f"studyrun case: {rhs_evals} RHS evaluations, case wall time {wall:.3f} s")

    def windows():
        yield "first 20 ms", t <= 0.020 + 1e-12
        yield "whole run  ", np.ones_like(t, bool)

    print("\nDifference SciPy - studyrun, relative to each channel's range (studyrun's, whole run):")
    print(f"{'channel':22s} {'window':12s} {'max':>10s} {'rms':>10s}   range")
    summary = {}
    for c in CHANNELS + ("eccentricity_x", "eccentricity_y"):
        rng = np.ptp(ref[c])
        for name, m in windows():
            d = res[c][m] - ref[c][m]
            mx, rms = np.max(np.abs(d)) / rng, np.sqrt(np.mean(d * d)) / rng
            summary[(c, name.strip())] = (mx, rms)
            print(f"{c:22s} {name:12s} {mx:10.2e} {rms:10.2e}   {rng:.4g}")
    # first time the channels separate by more than 1e-3 of their range
    print()
    for c in CHANNELS:
        rng = np.ptp(ref[c])
        over = np.nonzero(np.abs(res[c] - ref[c]) > 1e-3 * rng)[0]
        when = f"{t[over[0]] * 1e3:.2f} ms" if over.size else "never"
        print(f"{c}: |diff| first exceeds 1e-3 of range at {when}")

    # the ideal mechanism, and the RMS deviation from it over t >= 0.2 s
    ideal = res["ideal_slider_acceleration"]
    di = np.max(np.abs(ideal - ref_ideal)) / np.ptp(ref_ideal)
    print(f"\nideal slider acceleration, closed form here vs studyrun's reference: "
          f"max diff {di:.1e} of range")
    m = t >= 0.2 - 1e-12
    rms_py = np.sqrt(np.mean((res["slider_acceleration"][m] - ideal[m]) ** 2))
    rms_sr = np.sqrt(np.mean((ref["slider_acceleration"][m] - ref_ideal[m]) ** 2))
    print(f"RMS deviation of the slider acceleration from ideal, t >= 0.2 s: "
          f"SciPy {rms_py:.4f} m/s^2, studyrun {rms_sr:.4f} m/s^2 "
          f"(ratio {rms_py / rms_sr:.4f})")
    return summary


def reference_check(res, study_path, tight_path, case=0):
    """Both results against a tight-tolerance studyrun run of the same case: splits the
    SciPy - studyrun difference into each integrator's own error."""
    import h5py

    def load(p):
        with h5py.File(p, "r") as f:
            return {c: f[c][case, :] for c in CHANNELS}, f.attrs["solver"]

    tight, tsolver = load(tight_path)
    sr, ssolver = load(study_path)
    t = res["time"]
    tsolver = tsolver.decode() if isinstance(tsolver, bytes) else tsolver
    print(f"\nAgainst the tight reference {tight_path} ({tsolver}), relative to range:")
    print(f"{'result':10s} {'channel':20s} {'20 ms max':>10s} {'whole max':>10s} {'whole rms':>10s}")
    for name, r in (("SciPy", res), ("studyrun", sr)):
        for c in CHANNELS:
            rng = np.ptp(tight[c])
            d = np.abs(r[c] - tight[c]) / rng
            print(f"{name:10s} {c:20s} {d[t <= 0.020 + 1e-12].max():10.2e} {d.max():10.2e} "
                  f"{np.sqrt(np.mean(d * d)):10.2e}")


def energy_check(rtol=1e-11, atol=1e-14, duration=0.1):
    """docs/model.md section 4.4: W_driver = dKE + dV - int dV/dt|_e dt + E_damped, with the
    three integrals carried as extra ODE states (so the residual measures the model
    and the integrator, not a quadrature), for C = 300 and C = 0."""
    for damping in (C, 0.0):
        def rhs(t, y):
            ex, ey, vx, vy = y[:4].tolist()
            r = dynamics(t, ex, ey, vx, vy, damping)
            _, dVdt = hertz_potential(t, ex, ey)
            phi = BALL0 + CAGE * W * t
            cphi, sphi = np.cos(phi), np.sin(phi)
            delta = (ex * cphi + ey * sphi - 0.5 * PD
                     + WAVE_AMP * np.sin(WAVE_N * (phi - W * t)) + WAVE_AMP * np.sin(WAVE_N * phi))
            vr = vx * cphi + vy * sphi
            p_damp = float(np.sum(np.where(delta > 0, damping * np.maximum(vr, 0.0) * vr, 0.0)))
            return np.array((vx, vy, r[0], r[1], r[3] * W, p_damp, dVdt))

        sol = solve_ivp(rhs, (0.0, duration), np.zeros(7), method="LSODA", rtol=rtol,
                        atol=np.r_[np.full(4, atol), 1e-14, 1e-14, 1e-14])
        t = sol.t
        resid = np.empty(t.size)
        ke0 = kinetic_energy(0.0, 0.0, 0.0, 0.0, 0.0)
        for k in range(t.size):
            ex, ey, vx, vy, wd, ed, ip = sol.y[:, k]
            V, _ = hertz_potential(t[k], ex, ey)
            resid[k] = wd - (kinetic_energy(t[k], ex, ey, vx, vy) - ke0 + V - ip + ed)
        scale = np.max(np.abs(sol.y[4]))
        print(f"energy balance, C = {damping:g}, {duration} s, LSODA rtol {rtol:g}: "
              f"max |residual| {np.max(np.abs(resid)):.2e} J = {np.max(np.abs(resid)) / scale:.1e} "
              f"of max |W_driver| ({scale:.4f} J); dissipated {sol.y[5, -1]:.3e} J")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", help="save the sampled outputs (.npz)")
    ap.add_argument("--compare", metavar="STUDY.h5", help="compare with studyrun's result file")
    ap.add_argument("--reference", metavar="TIGHT.h5",
                    help="with --compare: also compare both with a tight-tolerance studyrun file")
    ap.add_argument("--rtol", type=float, default=RTOL)
    ap.add_argument("--atol", type=float, default=ATOL)
    ap.add_argument("--energy", action="store_true", help="energy-balance check (0.1 s, rtol 1e-11, C = 300 and 0)")
    a = ap.parse_args()
    if a.energy:
        energy_check()
        return
    res, stats, _ = run(a.rtol, a.atol)
    if a.out:
        np.savez_compressed(a.out, **res, **{f"stat_{k}": v for k, v in stats.items()})
        print(f"saved {a.out}")
    if a.compare:
        compare(res, a.compare)
        if a.reference:
            reference_check(res, a.compare, a.reference)


if __name__ == "__main__":
    main()
