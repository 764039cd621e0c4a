"""`analysis.studyfile.amplitude_spectrum` with the file's window: the stored
`<channel>_spectrum` recomputed from the stored series for a study with the default
Hann window and one with `spectra: {window: rectangular}` (docs/result-file.md#spectra),
and the ideal mechanism's spectrum that `figures.spectra` draws beside it.

Environment: STUDYRUN_BIN (the binary runs the studies written here); else skip.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis.figures import ideal_spectra  # noqa: E402
from analysis.studyfile import amplitude_spectrum, analysis_window, open_study, spectrum_window  # noqa: E402
from study_run import run_grid  # noqa: E402

GRID = """name: window_{window}
duration: 0.08
sample_rate: 10000
transient: "0.013 s"
{spectra}grid:
  location: [ideal, crank_ground, crank_rod]
"""
SPECTRA = {
    "hann": "",  # the default window and channels
    "rectangular": "spectra: {window: rectangular, channels: [slider_acceleration, crank_moment, bearing_force_x]}\n",
}


@pytest.fixture(scope="module", params=sorted(SPECTRA))
def study(request, tmp_path_factory):
    window = request.param
    path = run_grid(tmp_path_factory.mktemp(window), f"window_{window}",
                    GRID.format(window=window, spectra=SPECTRA[window]))
    with open_study(path) as ds:
        yield window, ds.load()


def stored_spectra(ds):
    return [name[: -len("_spectrum")] for name in ds.data_vars
            if name.endswith("_spectrum") and ds[name].dims == ("case", "frequency")]


def test_the_file_records_its_window(study):
    window, ds = study
    assert spectrum_window(ds) == window == ds.attrs["spectrum_window"]


def test_amplitude_spectrum_with_the_files_window_gives_the_stored_spectra(study):
    window, ds = study
    other = "hann" if window == "rectangular" else "rectangular"
    rate = float(ds.attrs["sample_rate"])
    keep = analysis_window(ds)
    channels = stored_spectra(ds)
    assert "slider_acceleration" in channels and "crank_moment" in channels
    for channel in channels:
        for case in range(ds.sizes["case"]):
            stored = ds[f"{channel}_spectrum"].values[case]
            if np.isnan(stored).all():  # the `ideal` case's bearing force: no bearing
                assert str(ds["location"].values[case]) == "ideal" and channel.startswith("bearing_force")
                assert np.isnan(ds[channel].values[case]).all()
                continue
            freq, got = amplitude_spectrum(ds[channel].values[case, keep], rate, spectrum_window(ds))
            np.testing.assert_allclose(freq, ds["frequency"].values, rtol=1e-12, atol=0)
            scale = np.max(np.abs(stored))
            assert np.max(np.abs(got - stored)) <= 1e-9 * scale, (window, channel, case)
            # The other window gives another spectrum: the comparison can tell them apart.
            _, wrong = amplitude_spectrum(ds[channel].values[case, keep], rate, other)
            assert np.max(np.abs(wrong - stored)) > 1e-3 * scale, (window, channel, case)


def test_the_ideal_spectrum_of_the_figures_is_the_ideal_cases_stored_one(study):
    """The grey curve of figures.spectra uses the file's window: for the `ideal` case (whose
    series is the ideal mechanism's) it is the stored spectrum."""
    window, ds = study
    ideal = int(np.flatnonzero(ds["location"].values == "ideal")[0])
    for channel in ("slider_acceleration", "crank_moment"):
        freq, amplitudes = ideal_spectra(ds, [ideal, 1, 2], channel)
        stored = ds[f"{channel}_spectrum"].values[ideal]
        np.testing.assert_allclose(freq, ds["frequency"].values, rtol=1e-12, atol=0)
        assert amplitudes.shape == (3, stored.size)
        for row in amplitudes:  # every case here runs the same ideal mechanism
            assert np.max(np.abs(row - stored)) <= 1e-9 * np.max(np.abs(stored)), (window, channel)


def test_an_unknown_window_is_refused():
    with pytest.raises(ValueError, match="window 'hamming': expected one of hann, rectangular"):
        amplitude_spectrum(np.ones(8), 100.0, "hamming")
    import xarray as xr

    with pytest.raises(ValueError, match="spectrum_window 'flattop'"):
        spectrum_window(xr.Dataset(attrs={"spectrum_window": "flattop"}))
    assert spectrum_window(xr.Dataset()) == "hann"


def test_a_rectangular_window_reads_an_on_bin_sinusoid_exactly():
    rate, n = 1000.0, 1000
    t = np.arange(n) / rate
    freq, amp = amplitude_spectrum(0.5 + 2.0 * np.cos(2 * np.pi * 40 * t), rate, "rectangular")
    assert amp[0] == pytest.approx(0.5, abs=1e-12)
    assert amp[40] == pytest.approx(2.0, abs=1e-12) and freq[40] == 40.0
    assert np.max(np.delete(amp, [0, 40])) < 1e-12
