"""The sensors' series recomputed from the stored channels with scipy (docs/model.md §7.8):
`<name>_clean` is the response of `y'' + 2 zeta w_n y' + w_n^2 y = w_n^2 u(t)` to the
stored channel taken linear between samples (scipy.signal.lsim, which holds the input
linear between samples, and an independent matrix-exponential stepping), from rest at
the first sample; `<name>` minus `<name>_clean` has the requested SNR over the analysed
window.

Environment: STUDYRUN_BIN (the binary runs a small study written here); else skip.
"""

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.signal import lsim

from study_run import opened_run, window

RTOL = 1e-9

GRID = """name: sensors
duration: 0.1
sample_rate: 20000
transient: "0.02 s"
grid:
  location: [crank_ground, crank_rod]
  rpm: [600, 900]
sensors:
  - {name: acc, channel: bearing_force_y, natural_frequency: "3 kHz", damping_ratio: 0.05, noise: {snr_db: 10, seed: 3}}
  - {name: torque, channel: crank_moment, natural_frequency: 800, damping_ratio: 0.3}
"""

SENSORS = [
    ("acc", "bearing_force_y", 3000.0, 0.05, 10.0),
    ("torque", "crank_moment", 800.0, 0.3, None),
]


@pytest.fixture(scope="module")
def f(tmp_path_factory):
    yield from opened_run(tmp_path_factory, "sensors", GRID)


def by_lsim(u, t, fn, zeta):
    wn = 2 * math.pi * fn
    a = [[0.0, 1.0], [-wn * wn, -2 * zeta * wn]]
    b = [[0.0], [wn * wn]]
    _, y, _ = lsim((a, b, [[1.0, 0.0]], [[0.0]]), u, t, X0=[u[0], 0.0], interp=True)
    return y


def by_expm(u, dt, fn, zeta):
    """Exact stepping of the state (y, y', u, u') over each sample interval."""
    wn = 2 * math.pi * fn
    m = np.zeros((4, 4))
    m[0, 1] = 1.0
    m[1, 0], m[1, 1], m[1, 2] = -wn * wn, -2 * zeta * wn, wn * wn
    m[2, 3] = 1.0
    e = expm(m * dt)
    y = np.empty_like(u)
    state = np.array([u[0], 0.0])
    y[0] = u[0]
    for k in range(len(u) - 1):
        full = e @ np.array([state[0], state[1], u[k], (u[k + 1] - u[k]) / dt])
        state = full[:2]
        y[k + 1] = state[0]
    return y


def test_the_clean_series_is_the_transducer_response(f):
    t = f["time"][:]
    dt = 1.0 / f.attrs["sample_rate"]
    assert np.allclose(np.diff(t), dt, rtol=1e-12, atol=0)
    for name, channel, fn, zeta, _ in SENSORS:
        assert f[name].attrs["units"] == f[channel].attrs["units"]
        for row in range(f["case"].shape[0]):
            u = f[channel][row, :]
            clean = f[f"{name}_clean"][row, :]
            scale = np.max(np.abs(clean))
            for ref in (by_lsim(u, t, fn, zeta), by_expm(u, dt, fn, zeta)):
                err = np.max(np.abs(ref - clean)) / scale
                assert err < RTOL, f"{name} row {row}: {err:.2e}"


def test_the_noise_has_the_requested_snr_over_the_analysed_window(f):
    w = window(f)
    for name, _, _, _, snr in SENSORS:
        for row in range(f["case"].shape[0]):
            clean = f[f"{name}_clean"][row, :]
            noisy = f[name][row, :]
            if snr is None:
                assert np.array_equal(noisy, clean)
                continue
            c = clean[w]
            signal = np.mean((c - c.mean()) ** 2)
            noise = np.mean((noisy[w] - c) ** 2)
            measured = 10 * math.log10(signal / noise)
            assert abs(measured - snr) < 1e-6, f"{name} row {row}: {measured} dB"
            # White: the lag-1 autocorrelation of the noise is small (N ~ 1600).
            z = noisy[w] - c
            r1 = np.sum(z[1:] * z[:-1]) / np.sum(z * z)
            assert abs(r1) < 5 / math.sqrt(len(z)), r1
