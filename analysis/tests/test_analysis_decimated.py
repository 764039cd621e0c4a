"""The diagnosis figures of a decimated study file (`output: {decimate: 2}`: series stored at
sample_rate / 2) work at the series' stored rate: the kurtogram's frequencies agree with the
band the file records (computed from the full-rate series) and the time–frequency figures
span the whole analysed window."""

import numpy as np
import pytest

from analysis import diagnosis as dg
from analysis import diagnosis_figures as dfig
from analysis.studyfile import series_rate


def by_fault(ds, keep):
    """{fault label: case position} of the cases whose constant speed passes `keep`
    (NaN for a run-up)."""
    return {str(ds["fault"].values[k]): k for k in range(ds.sizes["case"]) if keep(dg.constant_rpm(ds, k))}


def test_the_series_rate_is_the_stored_one(decimated_diagnosis):
    ds = decimated_diagnosis
    assert series_rate(ds) == 10_000.0 == float(ds.attrs["series_sample_rate"])
    assert float(ds.attrs["sample_rate"]) == 20_000.0 and int(ds.attrs["decimate"]) == 2
    bare = ds.copy()
    del bare.attrs["series_sample_rate"]
    assert series_rate(bare) == 10_000.0  # sample_rate / decimate


def test_kurtogram_of_a_decimated_series_meets_the_stored_band(decimated_diagnosis, drawn, tmp_path):
    """For each defect at 600 rpm, the accelerometer's recomputed kurtogram (outlined white)
    lies below the stored series' Nyquist frequency, 5 kHz, and overlaps the band the file
    records (cyan); at the study's 20 kHz it would lie at 5 kHz and above, outside it."""
    ds = decimated_diagnosis
    for fault, case in by_fault(ds, lambda rpm: rpm == 600.0).items():
        if fault == "none":
            continue
        dfig.kurtogram(ds, "accelerometer", case, tmp_path / f"k_{fault}.png", dpi=40)
        ax = drawn[-1].axes[0]
        assert ax.get_xlim() == (0.0, 5000.0)
        best, stored = ax.patches
        low, high = best.get_x(), best.get_x() + best.get_width()
        s_low, s_high = stored.get_x(), stored.get_x() + stored.get_width()
        assert s_low == float(ds["accelerometer_envelope_band_low"].values[case])
        assert high <= 5000.0 and min(high, s_high) - max(low, s_low) > 0, (fault, (low, high), (s_low, s_high))


def test_time_frequency_figures_span_the_decimated_run(decimated_diagnosis, drawn, tmp_path):
    """The run-up's spectrogram reaches the end of the 1.2 s run (its last segment centre
    within one segment of it) and its waterfall segments reach the run-up's end speed,
    900 rpm (within the speed change over a 0.2 s segment)."""
    ds = decimated_diagnosis
    runups = by_fault(ds, np.isnan)
    dfig.spectrogram(ds, "bearing_force", runups, tmp_path / "s.png", dpi=40)
    duration = float(ds.attrs["duration"])
    for ax in drawn[-1].axes[: len(runups)]:
        centres = ax.collections[0].get_coordinates()[0, :, 0]
        segment = float(ax.get_title().split(", ")[-1].split(" s segments")[0])
        assert duration - segment <= centres.max() < duration, (centres.max(), segment)
        assert ax.get_xlim()[1] == ds["time"].values[dg.analysis_window(ds)][-1] == pytest.approx(duration - 1e-4)
    rows = dfig._envelope_rows(ds, "bearing_force", runups["outer"], 0.2)
    speeds = [rpm for rpm, _, _ in rows]
    assert max(speeds) > 900 - 0.2 * 600 / 1.2 and min(speeds) < 400, speeds
