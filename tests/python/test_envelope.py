"""Every number of the envelope analysis recomputed from the stored series with numpy
(docs/model.md §7.3–§7.7): envelope spectra, the kurtogram's band, spectral kurtosis,
condition indicators, band energies and characteristic frequencies.

Environment: STUDYRUN_ENVELOPE_FILE, the result of `studyrun studies/envelope_smoke.yaml`
(.ci/run produces it); else, with STUDYRUN_BIN set, the test runs that study itself;
neither: skip.
"""

import os
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))
from analysis.frequencies import characteristic_frequencies  # noqa: E402
from study_run import text, window  # noqa: E402

RTOL = 1e-9
INDICATORS = [
    "rms", "peak", "crest_factor", "kurtosis", "skewness",
    "impulse_factor", "shape_factor", "clearance_factor",
]


@pytest.fixture(scope="module")
def path(tmp_path_factory):
    value = os.environ.get("STUDYRUN_ENVELOPE_FILE")
    if value:
        return value
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("neither STUDYRUN_ENVELOPE_FILE nor STUDYRUN_BIN is set")
    out = tmp_path_factory.mktemp("envelope") / "envelope_smoke.h5"
    subprocess.run(
        [binary, str(REPO / "studies/envelope_smoke.yaml"), "-o", str(out), "--force", "-q"],
        check=True,
    )
    return str(out)


@pytest.fixture(scope="module")
def f(path):
    with h5py.File(path, "r") as h:
        yield h


def hann(n):
    return 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)


def amplitude(x):
    """The file's one-sided amplitude spectrum (periodic Hann, a sinusoid reads A)."""
    n = len(x)
    w = hann(n)
    a = 2 * np.abs(np.fft.rfft(w * x)) / w.sum()
    a[0] /= 2
    if n % 2 == 0:
        a[-1] /= 2
    return a


def analytic(y_fft, freqs, low, high, n):
    z = np.zeros(n, dtype=complex)
    sel = (freqs >= low) & (freqs <= high)
    weight = np.full(len(freqs), 2.0)
    weight[0] = 1.0  # DC and (even n) Nyquist have no negative-frequency twin
    if n % 2 == 0:
        weight[-1] = 1.0
    z[: len(freqs)][sel] = weight[sel] * y_fft[sel]
    return np.fft.ifft(z), sel.sum()


def band_kurtosis(z):
    p = np.abs(z) ** 2
    return np.mean(p * p) / np.mean(p) ** 2 - 2


def kurtogram_bands(fs, n):
    depth = next((k for k in range(6, -1, -1) if n >> (k + 1) >= 16), 0)
    nyq = 0.5 * fs
    levels = [1]
    for k in range(1, depth + 1):
        if k >= 2:
            levels.append(3 << (k - 2))
        levels.append(1 << k)
    return [(i * nyq / m, (i + 1) * nyq / m) for m in levels for i in range(m)]


def stft_segment(n):
    target = min(max(n // 8, 2), 256)
    return 1 << (target.bit_length() - 1)


def spectral_kurtosis(y, n):
    """SK over segments of stft_segment(n) samples, each transformed at its own length."""
    seg = stft_segment(n)
    hop = seg // 2
    count = (n - seg) // hop + 1
    w = hann(seg)
    s2 = np.zeros(seg // 2 + 1)
    s4 = np.zeros(seg // 2 + 1)
    for m in range(count):
        p = np.abs(np.fft.rfft(w * y[m * hop : m * hop + seg])) ** 2
        s2 += p
        s4 += p * p
    return count * s4 / s2**2 - 2


def band_energy(a, freqs, f):
    h = max(0.02 * f, 1.5 * freqs[1])
    return np.sum(a[np.abs(freqs - f) <= h] ** 2) / 3


def close(stored, want, what, scale=None):
    """Equal to RTOL relative, relative to `scale` (an array's largest value) for arrays."""
    stored, want = np.asarray(stored, float), np.asarray(want, float)
    atol = RTOL * (np.nanmax(np.abs(want)) if scale is None else scale)
    np.testing.assert_allclose(stored, want, rtol=RTOL, atol=atol, err_msg=what)


def envelope_channels(f):
    return [k[: -len("_envelope_spectrum")] for k in f.keys() if k.endswith("_envelope_spectrum")]


def test_the_study_has_every_envelope_variable(f):
    assert sorted(envelope_channels(f)) == ["bearing_force", "slider_acceleration"]
    assert text(f.attrs["envelope_band"]) == "kurtogram"
    n = window(f).stop - window(f).start
    assert f.attrs["stft_segment"] == stft_segment(n)
    spectrum = f["bearing_force_envelope_spectrum"]
    assert spectrum.dims[1][0].name == "/frequency"
    sk = f["bearing_force_spectral_kurtosis"]
    assert sk.dims[1][0].name == "/sk_frequency"
    seg = stft_segment(n)
    np.testing.assert_array_equal(f["sk_frequency"][:], np.arange(seg // 2 + 1) * f.attrs["sample_rate"] / seg)
    assert text(f["sk_frequency"].attrs["units"]) == "Hz"
    assert text(spectrum.attrs["units"]) == "N2"
    assert text(f["bearing_force_envelope_energy_bpfo"].attrs["units"]) == "N4"
    assert text(f["slider_acceleration_envelope_spectrum"].attrs["units"]) == "m2 s-4"
    assert all(f["status"][:] == 1)


def test_envelope_spectra_kurtogram_and_spectral_kurtosis(f):
    win = window(f)
    freqs = f["frequency"][:]
    fs = f.attrs["sample_rate"]
    for ch in envelope_channels(f):
        for c in range(f["case"].shape[0]):
            x = f[ch][c, win]
            n = len(x)
            y = x - x.mean()
            y_fft = np.fft.rfft(y)
            # The kurtogram: the stored band is a band of the 1/3-binary grid of
            # largest kurtosis (to 1e-9: a tie within roundoff may pick either).
            low = f[f"{ch}_envelope_band_low"][c]
            high = f[f"{ch}_envelope_band_high"][c]
            kurt = {}
            for b in kurtogram_bands(fs, n):
                z, bins = analytic(y_fft, freqs, *b, n)
                if bins and np.mean(np.abs(z) ** 2) > 0:
                    kurt[b] = band_kurtosis(z)
            assert (low, high) in kurt, f"{ch} case {c}: band {low}..{high} not in the grid"
            best = max(kurt.values())
            assert kurt[(low, high)] >= best - RTOL * abs(best), (ch, c, kurt[(low, high)], best)
            close(f[f"{ch}_envelope_band_kurtosis"][c], kurt[(low, high)], f"{ch} band kurtosis")
            # The squared envelope's spectrum.
            z, _ = analytic(y_fft, freqs, low, high, n)
            s = np.abs(z) ** 2
            env = amplitude(s - s.mean())
            close(f[f"{ch}_envelope_spectrum"][c], env, f"{ch} envelope spectrum case {c}")
            # Spectral kurtosis: values of order 1, compared to 1e-9 absolute.
            close(f[f"{ch}_spectral_kurtosis"][c], spectral_kurtosis(y, n), f"{ch} SK", scale=1.0)


def test_indicators_band_energies_and_fault_frequencies(f):
    win = window(f)
    freqs = f["frequency"][:]
    for c in range(f["case"].shape[0]):
        loc = text(f["location"][c])
        fr = characteristic_frequencies(
            loc, f["rpm"][c], f["ball_count"][c], f["inner_race_diameter"][c],
            f["outer_race_diameter"][c], 1, 1,
        )
        di, do = f["inner_race_diameter"][c], f["outer_race_diameter"][c]
        ratio = (do - di) / (do + di)
        bsf = (1 - ratio**2) / (2 * ratio) * f["rpm"][c] / 60
        want = {"ftf": fr.cage, "bpfo": fr.ball_pass_outer, "bpfi": fr.ball_pass_inner, "bsf": bsf}
        for name, value in want.items():
            close(f[name][c], value, name)
        for ch in envelope_channels(f):
            x = f[ch][c, win]
            y = x - x.mean()
            rms = np.sqrt(np.mean(y**2))
            peak = np.max(np.abs(y))
            m1 = np.mean(np.abs(y))
            got = {
                "rms": rms,
                "peak": peak,
                "crest_factor": peak / rms,
                "kurtosis": np.mean(y**4) / np.mean(y**2) ** 2,
                "skewness": np.mean(y**3) / np.mean(y**2) ** 1.5,
                "impulse_factor": peak / m1,
                "shape_factor": rms / m1,
                "clearance_factor": peak / np.mean(np.sqrt(np.abs(y))) ** 2,
            }
            for name in INDICATORS:
                scale = 1.0 if name == "skewness" else None
                close(f[f"{ch}_{name}"][c], got[name], f"{ch}_{name} case {c}", scale=scale)
            env = f[f"{ch}_envelope_spectrum"][c]
            lines = {"ftf": want["ftf"], "bpfo": want["bpfo"], "bpfi": want["bpfi"], "2bsf": 2 * bsf}
            total = np.sum(env**2) / 3
            for name, line in lines.items():
                close(
                    f[f"{ch}_envelope_energy_{name}"][c],
                    band_energy(env, freqs, line),
                    f"{ch}_envelope_energy_{name} case {c}",
                    scale=total,
                )
