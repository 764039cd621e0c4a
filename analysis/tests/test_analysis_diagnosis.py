"""analysis/diagnosis.py: crank motion, fault orders, envelope, kurtogram, STFT and order
spectrum, against closed forms and against what studyrun stores (studies/diagnosis.yaml)."""

import math

import numpy as np
import pytest
import xarray as xr

from analysis import diagnosis as dg

RTOL = 1e-9


def constant_cases(ds):
    """Positions of the cases with a constant speed."""
    return [k for k in range(ds.sizes["case"]) if math.isfinite(dg.constant_rpm(ds, k))]


def test_the_fault_lines_are_the_stored_frequencies(diagnosis):
    """Orders from geometry × rpm/60 equal the file's ftf, bpfo, bpfi, bsf; the run-ups
    store NaN (their lines move) and are recognised as varying."""
    cases = constant_cases(diagnosis)
    assert len(cases) == 8
    for k in cases:
        f_shaft = dg.constant_rpm(diagnosis, k) / 60
        orders = dg.fault_orders(diagnosis, k)
        for name in ("ftf", "bpfo", "bpfi", "bsf"):
            stored = float(diagnosis[name].values[k])
            assert getattr(orders, name) * f_shaft == pytest.approx(stored, rel=RTOL), name
    for k in set(range(diagnosis.sizes["case"])) - set(cases):
        assert np.isnan(diagnosis["bpfo"].values[k])


@pytest.mark.parametrize("channel", ["bearing_force", "accelerometer"])
def test_envelope_and_kurtogram_recomputed_from_the_series(diagnosis, channel):
    """docs/model.md §7.4 and §7.6 from the stored series (the simulated bearing force and the
    housing accelerometer's noisy series): the kurtogram's band exactly, its kurtosis to
    1e-9, the envelope spectrum to 1e-9 of its largest value (the healthy bearing force's
    chosen band holds only rounding, 1e-13 N² against a variance of 100s of N²: there both
    stay below 1e-12 of the variance)."""
    fs = float(diagnosis.attrs["sample_rate"])
    for k in range(diagnosis.sizes["case"]):
        _, x = dg.window_series(diagnosis, channel, k)
        result = dg.kurtogram(x, fs)
        low = float(diagnosis[f"{channel}_envelope_band_low"].values[k])
        high = float(diagnosis[f"{channel}_envelope_band_high"].values[k])
        assert result.band == (low, high)
        stored_kurtosis = float(diagnosis[f"{channel}_envelope_band_kurtosis"].values[k])
        assert result.kurtosis == pytest.approx(stored_kurtosis, rel=RTOL)
        _, spectrum = dg.envelope_spectrum(x, fs, low, high)
        stored = diagnosis[f"{channel}_envelope_spectrum"].values[k]
        roundoff = 1e-12 * np.var(x)  # a band holding only the FFTs' rounding of the series
        if stored.max() < roundoff:
            assert spectrum.max() < roundoff
        else:
            np.testing.assert_allclose(spectrum, stored, rtol=0, atol=RTOL * stored.max())


def test_kurtogram_finds_the_resonance_of_an_impulse_train():
    """Impulses every 1/97 s ring a 6 kHz resonance (ζ = 0.02) in white noise of twice their
    power, 25.6 kHz (the engine's unit test): the chosen band holds 6 kHz, is at most 1.6 kHz
    wide, its kurtosis is over 0.5 and five times the whole band's, and its envelope
    spectrum's largest line below 200 bins is at 97 Hz."""
    fs, n = 25_600.0, 1 << 15
    t = np.arange(n) / fs
    since = t % (1 / 97)
    ring = np.exp(-0.02 * 2 * math.pi * 6000 * since) * np.sin(2 * math.pi * 6000 * since)
    x = 3.0 * ring + 1.5 * np.random.default_rng(11).standard_normal(n)
    result = dg.kurtogram(x, fs)
    low, high = result.band
    assert low <= 6000 <= high and high - low <= fs / 16, result.band
    whole = result.levels[0][1][0]
    assert result.kurtosis > 0.5 and result.kurtosis > 5 * whole, (result.kurtosis, whole)
    widths = [len(row) for _, row in result.levels]
    assert widths[:5] == [1, 2, 3, 4, 6] and widths[-1] == 2 ** dg.kurtogram_depth(n) == 64
    f, a = dg.envelope_spectrum(x, fs, low, high)
    assert abs(f[1 + np.argmax(a[1:200])] - 97) <= f[1]


def test_envelope_of_an_am_tone():
    """(1 + m cos 2π f_m t) cos 2π f_c t on bins: the envelope spectrum reads 2m at f_m and
    m²/2 at 2 f_m (docs/model.md §7.4)."""
    fs, n, fc, fm, m = 8000.0, 8000, 1000.0, 25.0, 0.4
    t = np.arange(n) / fs
    x = (1 + m * np.cos(2 * math.pi * fm * t)) * np.cos(2 * math.pi * fc * t)
    f, a = dg.envelope_spectrum(x, fs, 800.0, 1200.0)
    assert a[np.argmin(abs(f - fm))] == pytest.approx(2 * m, rel=1e-12)
    assert a[np.argmin(abs(f - 2 * fm))] == pytest.approx(m**2 / 2, rel=1e-12)


def test_stft_reads_a_sinusoid_on_a_bin():
    fs, segment = 1000.0, 200
    t = np.arange(1000) / fs
    times, freqs, amp = dg.stft(3.0 * np.sin(2 * math.pi * 50 * t), fs, segment, 50)
    assert len(times) == (1000 - segment) // 50 + 1 and times[0] == pytest.approx(0.1)
    np.testing.assert_allclose(amp[:, np.argmin(abs(freqs - 50))], 3.0, rtol=1e-12)
    with pytest.raises(ValueError, match="longer than the series"):
        dg.stft(t, fs, 2000, 10)


def ramp_case(from_rpm, to_rpm, over):
    """A one-case Dataset with a ramp speed profile, as a study file stores it."""
    values = dict(rpm=np.nan, speed_from=from_rpm, speed_to=to_rpm, speed_over=over)
    data = {k: ("case", [v]) for k, v in values.items()}
    data["speed_profile"] = ("case", ["ramp"])
    return xr.Dataset(data, coords={"case": [0]})


def test_crank_motion_of_a_ramp_integrates_its_speed():
    """θ2 of a ramp (docs/model.md §1.5) against the trapezoidal integral of its speed."""
    ds = ramp_case(300.0, 900.0, 0.6)
    t = np.linspace(0, 1.0, 100_001)
    theta, rpm = dg.crank_motion(ds, 0, t)
    assert rpm[0] == 300 and rpm[-1] == 900 and rpm[30_000] == pytest.approx(600)
    integral = np.concatenate([[0], np.cumsum(0.5 * (rpm[1:] + rpm[:-1]) * np.diff(t))]) * 2 * math.pi / 60
    np.testing.assert_allclose(theta, integral, rtol=0, atol=1e-9)
    assert math.isnan(dg.constant_rpm(ds, 0))
    assert dg.constant_rpm(ramp_case(600.0, 600.0, 1.0), 0) == 600


def test_order_spectrum_of_a_run_up():
    """cos(7 θ2) over a 300→900 rpm run-up reads 1 at order 7 (a whole number of cycles in the
    whole revolutions kept); the spectrum over time smears it over 35–105 Hz."""
    ds = ramp_case(300.0, 900.0, 1.0)
    fs = 20_000.0
    t = np.arange(int(fs)) / fs
    theta, _ = dg.crank_motion(ds, 0, t)
    x = np.cos(7 * theta)
    orders, amplitude = dg.order_spectrum(x, theta, 256)
    k = np.argmin(abs(orders - 7))
    assert orders[k] == pytest.approx(7) and amplitude[k] == pytest.approx(1.0, abs=2e-3)
    assert np.sort(amplitude)[-4] < 0.01  # the line and its two Hann neighbours only
    with pytest.raises(ValueError, match="no whole crank revolution"):
        dg.order_spectrum(x[:100], theta[:100], 256)
