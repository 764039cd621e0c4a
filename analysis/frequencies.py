"""Characteristic frequencies of the ball bearing (docs/model.md section 7.3).

Rolling without slip, the cage turns at ω_m = (ω_i d_i + ω_o d_o)/(d_i + d_o)
(rad/s) with ω_i, ω_o the mean speeds of the inner and outer race. Balls pass a
point of the inner race at f_in = (ω_i − ω_m)/2π and of the outer race at
f_out = (ω_m − ω_o)/2π (Hz). Marked in spectra: the cage f_c = ω_m/2π, the ball
pass frequencies N_b f_out and N_b f_in, and per wavy race the journal's whirl
|(N ± 1) ω_m − N ω_race|/2π when N_b divides N ± 1 (docs/model.md §7.3: other orders
cancel among equally loaded balls), else the rate N f_out or N f_in at which the
waviness passes one ball. All frequencies are returned as absolute values in Hz.

Mean race speeds per bearing location (ω_crank = 2π rpm/60 rad/s):
- crank_ground: inner race on the crank, ω_i = ω_crank; outer race on the ground, ω_o = 0.
- crank_rod: outer race on the crank pin, ω_o = ω_crank; inner race on the
  connecting rod. The rod only oscillates, so its angular velocity averaged over a
  crank revolution is 0 and ω_i = 0 is used. This is an approximation: the rod's
  oscillation modulates the ball angles, which spreads each line into sidebands at
  multiples of the crank frequency.
"""

import math
from dataclasses import dataclass

CRANK_ROD_NOTE = (
    "crank_rod: inner race on the rod, taken at its mean speed over a revolution (0); "
    "the rod's swing adds sidebands at multiples of the crank frequency"
)


@dataclass(frozen=True)
class BearingFrequencies:
    """Characteristic frequencies of one bearing case; `cage_speed` in rad/s, the rest in Hz."""

    cage_speed: float
    cage: float
    inner_pass: float
    outer_pass: float
    ball_pass_outer: float
    ball_pass_inner: float
    waviness_outer: float
    """N_o f_out: the outer waviness passing one ball."""
    waviness_inner: float
    """N_i f_in: the inner waviness passing one ball."""
    whirl_outer: float
    """The journal's whirl from the outer waviness, NaN when N_b divides neither N_o ± 1."""
    whirl_inner: float
    """The journal's whirl from the inner waviness, NaN when N_b divides neither N_i ± 1."""


def race_speeds(location, rpm):
    """Mean angular speeds (ω_i, ω_o) of the inner and outer race in rad/s for a crank
    turning at `rpm` (rev/min), with the bearing at `location` (see the module docstring)."""
    omega_crank = 2 * math.pi * rpm / 60
    if location == "crank_ground":
        return omega_crank, 0.0
    if location == "crank_rod":
        return 0.0, omega_crank
    raise ValueError(f"no bearing at location {location!r}: use crank_ground or crank_rod")


def waviness_whirl(order, ball_count, cage_speed, race_speed):
    """|(N ± 1) ω_m − N ω_race| / 2π (Hz) for the N ± 1 that `ball_count` divides (the
    first-order resultant of a waviness of order N over equally spaced balls,
    docs/model.md §7.3), or NaN when it divides neither."""
    n, balls = round(order), round(ball_count)
    for m in (n + 1, n - 1):
        if balls > 0 and m != 0 and m % balls == 0:
            return abs(m * cage_speed - n * race_speed) / (2 * math.pi)
    return math.nan


def characteristic_frequencies(
    location, rpm, ball_count, inner_diameter, outer_diameter, inner_waviness_number, outer_waviness_number
):
    """Bearing frequencies (Hz; cage speed rad/s) from the raceway diameters d_i, d_o (m),
    the ball count N_b and the waviness numbers N_i, N_o, at `rpm` and `location`."""
    omega_i, omega_o = race_speeds(location, rpm)
    omega_m = (omega_i * inner_diameter + omega_o * outer_diameter) / (inner_diameter + outer_diameter)
    f_in = abs(omega_i - omega_m) / (2 * math.pi)
    f_out = abs(omega_m - omega_o) / (2 * math.pi)
    return BearingFrequencies(
        cage_speed=omega_m,
        cage=abs(omega_m) / (2 * math.pi),
        inner_pass=f_in,
        outer_pass=f_out,
        ball_pass_outer=ball_count * f_out,
        ball_pass_inner=ball_count * f_in,
        waviness_outer=outer_waviness_number * f_out,
        waviness_inner=inner_waviness_number * f_in,
        whirl_outer=waviness_whirl(outer_waviness_number, ball_count, omega_m, omega_o),
        whirl_inner=waviness_whirl(inner_waviness_number, ball_count, omega_m, omega_i),
    )


def case_frequencies(ds, case):
    """`characteristic_frequencies` of the case at position `case` of a flat study
    Dataset, from its stored parameters (the first waviness harmonic's numbers)."""
    p = ds.isel(case=case)
    return characteristic_frequencies(
        location=str(p["location"].values),
        rpm=float(p["rpm"]),
        ball_count=float(p["ball_count"]),
        inner_diameter=float(p["inner_race_diameter"]),
        outer_diameter=float(p["outer_race_diameter"]),
        inner_waviness_number=float(p["inner_waviness_number"]),
        outer_waviness_number=float(p["outer_waviness_number"]),
    )
