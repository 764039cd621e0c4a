"""studyfile: the loader, unstacking, the ideal-mechanism series and the metrics they give."""

import numpy as np
import pytest

from analysis.studyfile import (
    amplitude_spectrum,
    analysis_window,
    reference_for,
    select_cases,
    unstack,
)

AXES = ["location", "waviness_amplitude", "ball_count", "rpm"]


def bearing(ds):
    return ds["location"].values != "ideal"


def test_unstack_gives_the_grid_dimensions_and_coordinates(smoke):
    grid = unstack(smoke)
    assert {a: grid.sizes[a] for a in AXES} == {"location": 3, "waviness_amplitude": 2, "ball_count": 2, "rpm": 1}
    assert grid["slider_acceleration"].dims == (*AXES, "time")
    assert grid["slider_acceleration_spectrum"].dims == (*AXES, "frequency")
    assert grid["reference_slider_acceleration"].dims == ("reference", "time")
    assert grid["location"].dtype.kind == "U"
    assert sorted(grid["location"].values) == ["crank_ground", "crank_rod", "ideal"]
    np.testing.assert_array_equal(grid["waviness_amplitude"].values, [0.0, 4e-6])
    np.testing.assert_array_equal(grid["ball_count"].values, [8, 9])
    np.testing.assert_array_equal(grid["rpm"].values, [600])


def test_unstacked_cells_are_the_flat_cases(smoke):
    grid = unstack(smoke)
    for case in range(smoke.sizes["case"]):
        p = {a: smoke[a].values[case] for a in AXES}
        cell = grid.sel(p)
        assert int(cell["case_id"]) == int(smoke["case"].values[case])
        np.testing.assert_array_equal(cell["slider_acceleration"].values, smoke["slider_acceleration"].values[case])
    one = grid.sel(ball_count=9, rpm=600, location="crank_rod", waviness_amplitude=4e-6)
    assert one["slider_acceleration_rms_deviation"].ndim == 0


def test_unstack_refuses_axes_that_do_not_identify_the_cases(smoke):
    with pytest.raises(ValueError, match="uniquely"):
        unstack(smoke.assign_attrs(grid_axes="ball_count,rpm"))
    with pytest.raises(ValueError, match="no grid axes"):
        unstack(smoke.assign_attrs(grid_axes=""))


def test_select_cases(smoke):
    cases = select_cases(smoke, location="crank_rod", waviness_amplitude=4e-6)
    assert sorted(smoke["ball_count"].values[cases]) == [8, 9]
    assert (smoke["location"].values[cases] == "crank_rod").all()
    assert select_cases(smoke, rpm=300).size == 0


def test_ideal_cases_equal_their_reference(smoke):
    """The `ideal` cases are the ideal mechanism at the reference's speed: identical series."""
    ideal = ~bearing(smoke)
    refs = reference_for(smoke)
    for name in ("slider_acceleration", "crank_moment", "crank_ground_force_x", "crank_rod_force_y"):
        assert refs[name].dims == ("case", "time")
        np.testing.assert_array_equal(refs[name].values[ideal], smoke[name].values[ideal])
    assert np.isnan(refs["bearing_force"].values[ideal]).all()
    assert np.isfinite(refs["bearing_force"].values[~ideal]).all()


def rms(x):
    return np.sqrt(np.mean(x**2, axis=-1))


def test_slider_acceleration_metric_recomputed_from_the_series(smoke):
    """RMS of slider_acceleration minus its reference over transient <= t < duration equals the stored metric."""
    window = analysis_window(smoke)
    # transient 0.01 s at 20 kHz: samples 200 .. 999 of 0 .. 1000 (t = 0.05 s left out)
    assert window.sum() == smoke.sizes["time"] - 201
    assert np.flatnonzero(window)[[0, -1]].tolist() == [200, smoke.sizes["time"] - 2]
    assert smoke.sizes["frequency"] == window.sum() // 2 + 1
    ref = reference_for(smoke, ["slider_acceleration"])["slider_acceleration"].values
    dev = smoke["slider_acceleration"].values - ref
    stored = smoke["slider_acceleration_rms_deviation"].values
    b = bearing(smoke)
    np.testing.assert_allclose(rms(dev[:, window])[b], stored[b], rtol=1e-12, atol=0)
    assert (stored[~b] == 0).all() and (stored[b] > 1).all()
    np.testing.assert_allclose(rms(ref[:, window]), smoke["slider_acceleration_reference_rms"].values, rtol=1e-12)


def test_crank_moment_metric_recomputed_from_the_series(smoke):
    window = analysis_window(smoke)
    ref = reference_for(smoke, ["crank_moment"])["crank_moment"].values
    dev = smoke["crank_moment"].values - ref
    b = bearing(smoke)
    np.testing.assert_allclose(rms(dev[:, window])[b], smoke["crank_moment_rms_deviation"].values[b], rtol=1e-12)


def test_bearing_force_reference_is_the_joint_at_the_bearing_location(smoke):
    """|F| of crank_ground_force for crank_ground cases, crank_rod_force for crank_rod cases:
    its RMS and the deviation's equal the stored bearing_force metrics."""
    window = analysis_window(smoke)
    b = bearing(smoke)
    ref = reference_for(smoke, ["bearing_force"])["bearing_force"].values[b][:, window]
    stored_ref = smoke["bearing_force_reference_rms"].values[b]
    np.testing.assert_allclose(rms(ref), stored_ref, rtol=1e-12)
    dev = smoke["bearing_force"].values[b][:, window] - ref
    np.testing.assert_allclose(rms(dev), smoke["bearing_force_rms_deviation"].values[b], rtol=1e-12)
    locations = smoke["location"].values[b]
    # the two joints carry different forces, so the choice above is tested
    assert abs(stored_ref[locations == "crank_ground"][0] / stored_ref[locations == "crank_rod"][0] - 1) > 0.2


def test_reference_for_refuses_unknown_channels(smoke):
    with pytest.raises(ValueError, match="loaded_balls"):
        reference_for(smoke, ["loaded_balls"])


def test_amplitude_spectrum_reproduces_the_stored_spectra(smoke):
    window = analysis_window(smoke)
    case = int(select_cases(smoke, location="crank_ground", waviness_amplitude=4e-6, ball_count=8)[0])
    for channel in ("slider_acceleration", "crank_moment", "bearing_force"):
        freq, amp = amplitude_spectrum(smoke[channel].values[case, window], smoke.attrs["sample_rate"])
        np.testing.assert_allclose(freq, smoke["frequency"].values, rtol=1e-12)
        stored = smoke[f"{channel}_spectrum"].values[case]
        np.testing.assert_allclose(amp, stored, rtol=1e-9, atol=1e-9 * stored.max())


def test_amplitude_spectrum_reads_a_sinusoid_amplitude():
    rate, n = 1000.0, 1000
    t = np.arange(n) / rate
    freq, amp = amplitude_spectrum(1.5 + 3.0 * np.sin(2 * np.pi * 50 * t), rate)
    assert amp[np.argmin(abs(freq - 50))] == pytest.approx(3.0, rel=1e-12)
    assert amp[0] == pytest.approx(1.5, rel=1e-12)


def test_select_cases_matches_nan(smoke):
    """A both-races parameter is NaN where the races differ; selecting NaN finds those cases."""
    values = smoke["waviness_amplitude"].values.copy()
    values[3] = np.nan
    mixed = smoke.assign(waviness_amplitude=("case", values))
    np.testing.assert_array_equal(select_cases(mixed, waviness_amplitude=np.nan), [3])
