"""Order spectra and sensor channels recomputed from the stored series with numpy
(docs/model.md §7.9, §7.4, §7.3): a run-up and a constant-speed case, each resampled in
crank angle with the closed-form θ2(t) of docs/model.md §1.5 inverted in closed form,
Catmull-Rom interpolated and transformed; the envelope spectrum of a noisy sensor
series; the characteristic orders.

Environment: STUDYRUN_BIN (the binary runs a small study written here); else skip.
"""

import math
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
from analysis.diagnosis import analytic_signal  # noqa: E402
from analysis.frequencies import characteristic_frequencies  # noqa: E402
from study_run import opened_run, text, window  # noqa: E402

RTOL = 1e-9

GRID = """name: orders
duration: 0.3
sample_rate: 10000
transient: "0.05 s"
location: crank_ground
sensors:
  - {name: acc, channel: bearing_force_y, natural_frequency: "2 kHz", damping_ratio: 0.05, noise: {snr_db: 10, seed: 5}}
spectra:
  channels: [bearing_force, acc]
  orders: true
envelope:
  channels: [acc, bearing_force]
  band: auto
  orders: true
cases:
  - {speed: {profile: ramp, from: "600 rpm", to: "1200 rpm", over: "0.2 s"}}
  - {rpm: 900}
"""


@pytest.fixture(scope="module")
def f(tmp_path_factory):
    yield from opened_run(tmp_path_factory, "orders", GRID)


def amplitude(x):
    """The file's one-sided amplitude spectrum (periodic Hann, a sinusoid reads A)."""
    n = len(x)
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)
    a = 2 * np.abs(np.fft.rfft(w * x)) / w.sum()
    a[0] /= 2
    if n % 2 == 0:
        a[-1] /= 2
    return a


def close(stored, want, what):
    stored, want = np.asarray(stored, float), np.asarray(want, float)
    np.testing.assert_allclose(
        stored, want, rtol=RTOL, atol=RTOL * np.nanmax(np.abs(want)), err_msg=what
    )


class Drive:
    """θ2(t) of model.md §1.5 and its inverse, both in closed form: constant speed
    θ2 = ω t; a ramp θ2 = ω0 t + α t²/2 up to T, then at ω1 = ω0 + α T."""

    def __init__(self, f, c):
        if text(f["speed_profile"][c]) == "ramp":
            self.w0 = 2 * np.pi * f["speed_from"][c] / 60
            w1 = 2 * np.pi * f["speed_to"][c] / 60
            self.over = f["speed_over"][c]
            self.alpha = (w1 - self.w0) / self.over
        else:
            assert text(f["speed_profile"][c]) == "constant"
            self.w0, self.alpha, self.over = 2 * np.pi * f["rpm"][c] / 60, 0.0, np.inf
        self.w1 = self.w0 + self.alpha * self.over if self.alpha else self.w0

    def angle(self, t):
        t = np.asarray(t, float)
        if self.alpha == 0.0:
            return self.w0 * t
        ramp = t * (self.w0 + 0.5 * self.alpha * t)
        end = self.over * (self.w0 + 0.5 * self.alpha * self.over)
        return np.where(t < self.over, ramp, end + self.w1 * (t - self.over))

    def time(self, phi):
        """The inverse: the root of ω0 t + α t²/2 = φ as 2φ / (ω0 + √(ω0² + 2αφ))."""
        phi = np.asarray(phi, float)
        if self.alpha == 0.0:
            return phi / self.w0
        end = self.over * (self.w0 + 0.5 * self.alpha * self.over)
        ramp = 2 * phi / (self.w0 + np.sqrt(self.w0**2 + 2 * self.alpha * phi))
        return np.where(phi < end, ramp, self.over + (phi - end) / self.w1)


def resample(x, t, drive, revolutions, m):
    """x (the window's samples at times t) at M angles φ_m = θ_a + 2πRm/M, by the
    Catmull-Rom cubic through the four samples around τ_m = θ2⁻¹(φ_m), indices
    clamped to the window (model.md §7.9)."""
    n = len(x)
    phi = drive.angle(t[0]) + 2 * np.pi * revolutions * np.arange(m) / m
    tau = drive.time(phi)
    i = np.clip(np.searchsorted(t, tau, side="right") - 1, 0, n - 2)
    u = (tau - t[i]) / (t[i + 1] - t[i])
    p0, p1 = x[np.maximum(i - 1, 0)], x[i]
    p2, p3 = x[np.minimum(i + 1, n - 1)], x[np.minimum(i + 2, n - 1)]
    return p1 + 0.5 * u * (p2 - p0 + u * (2 * p0 - 5 * p1 + 4 * p2 - p3 + u * (3 * (p1 - p2) + p3 - p0)))


def squared_envelope(x, fs, low, high):
    """|z|² of the analytic signal in [low, high] with its mean removed (model.md §7.4)."""
    s = np.abs(analytic_signal(x, fs, low, high)) ** 2
    return s - s.mean()


def test_order_spectra_recomputed_from_the_series(f):
    win = window(f)
    t = f["time"][win]
    fs = f.attrs["sample_rate"]
    n = len(t)
    revolutions, m = int(f.attrs["order_revolutions"]), int(f.attrs["order_samples"])
    assert m == n
    drives = [Drive(f, c) for c in range(f["case"].shape[0])]
    # R: the fewest whole revolutions any case turns between the window's first and
    # last samples.
    turns = [math.floor((d.angle(t[-1]) - d.angle(t[0])) / (2 * np.pi)) for d in drives]
    assert revolutions == min(turns) >= 1, (revolutions, turns)
    np.testing.assert_allclose(f["order"][:], np.arange(m // 2 + 1) / revolutions, rtol=0, atol=0)
    assert text(f["acc_order_spectrum"].attrs["units"]) == "N"
    assert text(f["acc_envelope_order_spectrum"].attrs["units"]) == "N2"
    assert f["bearing_force_order_spectrum"].dims[1][0].name == "/order"
    for c, drive in enumerate(drives):
        for ch in ["bearing_force", "acc"]:
            x = f[ch][c, win]
            want = amplitude(resample(x, t, drive, revolutions, m))
            close(f[f"{ch}_order_spectrum"][c], want, f"{ch} order spectrum case {c}")
        for ch in ["acc", "bearing_force"]:
            x = f[ch][c, win]
            low, high = f[f"{ch}_envelope_band_low"][c], f[f"{ch}_envelope_band_high"][c]
            s = squared_envelope(x, fs, low, high)
            close(f[f"{ch}_envelope_spectrum"][c], amplitude(s), f"{ch} envelope spectrum case {c}")
            want = amplitude(resample(s, t, drive, revolutions, m))
            close(
                f[f"{ch}_envelope_order_spectrum"][c], want, f"{ch} envelope order spectrum case {c}"
            )


def test_characteristic_orders_for_every_speed(f):
    for c in range(f["case"].shape[0]):
        fr = characteristic_frequencies(
            text(f["location"][c]), 60.0, f["ball_count"][c], f["inner_race_diameter"][c],
            f["outer_race_diameter"][c], 1, 1,
        )
        di, do = f["inner_race_diameter"][c], f["outer_race_diameter"][c]
        ratio = (do - di) / (do + di)
        bsf = (1 - ratio**2) / (2 * ratio)
        want = {"ftf": fr.cage, "bpfo": fr.ball_pass_outer, "bpfi": fr.ball_pass_inner, "bsf": bsf}
        ramp = text(f["speed_profile"][c]) == "ramp"
        for name, order in want.items():
            close(f[f"{name}_order"][c], order, f"{name}_order case {c}")
            # In Hz: NaN for the run-up, the order times the speed otherwise.
            if ramp:
                assert np.isnan(f[name][c])
            else:
                close(f[name][c], order * f["rpm"][c] / 60, f"{name} case {c}")
