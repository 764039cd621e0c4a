"""The study file `studyrun` writes, read the way users read it (xarray, h5py).

Environment: STUDYRUN_SMOKE_FILE, the result of `studyrun studies/smoke.yaml`
(.ci/run produces it); unset: skip.
"""

import os

import h5py
import numpy as np
import pytest
import xarray as xr


def half_open_window(ds):
    """The samples the metrics and spectra analyse: transient <= t < duration."""
    assert ds.attrs["analysis_window"].startswith("transient <= time < duration")
    t = ds.time.values
    return (t >= ds.attrs["transient"] - 1e-12) & (t < ds.attrs["duration"] - 1e-12)


@pytest.fixture(scope="module")
def path():
    value = os.environ.get("STUDYRUN_SMOKE_FILE")
    if not value:
        pytest.skip("STUDYRUN_SMOKE_FILE is not set: run `studyrun studies/smoke.yaml` first")
    return value


@pytest.fixture(scope="module")
def ds(path):
    """The file as the analysis scripts open it: `time` in seconds."""
    with xr.open_dataset(path, engine="h5netcdf", decode_times=False) as d:
        yield d.load()


def test_time_is_a_cf_time_coordinate_of_seconds(path, ds):
    """`time` is seconds from the start (the file's numbers, decode_times=False); with
    xarray's default decoding it is the nominal date 1970-01-01 plus those seconds,
    truncated to the nanosecond."""
    with h5py.File(path, "r") as f:
        seconds = f["time"][:]
    np.testing.assert_array_equal(ds.time.values, seconds)
    assert np.array_equal(seconds, np.arange(seconds.size) / ds.attrs["sample_rate"])
    assert ds.time.attrs["units"] == "seconds since 1970-01-01 00:00:00"
    assert ds.time.attrs["standard_name"] == "time" and ds.time.attrs["axis"] == "T"
    with xr.open_dataset(path, engine="h5netcdf") as decoded:
        t = decoded.time
        assert np.issubdtype(t.dtype, np.datetime64)
        offset_ns = (t.values - np.datetime64("1970-01-01T00:00:00", "ns")).astype(np.int64)
        exact_ns = seconds * 1e9
        assert ((offset_ns - exact_ns) <= 1e-6).all() and ((exact_ns - offset_ns) < 1.0 + 1e-6).all()


def test_named_dimensions_units_and_long_names(ds):
    assert set(ds.sizes) == {"case", "time", "frequency", "reference"}
    assert ds.sizes["time"] == 1001 and ds.sizes["case"] == 12
    for name, var in ds.variables.items():
        assert not any(d.startswith("phony_dim") for d in var.dims), name
        assert isinstance(var.attrs.get("units"), str), f"{name}: no units"
        assert var.attrs.get("long_name"), f"{name}: no long_name"
    assert ds["slider_acceleration"].attrs["units"] == "m s-2"
    assert ds["clearance"].attrs["units"] == "m"


def test_case_dimension_unstacks_into_the_grid_axes(ds):
    axes = ds.attrs["grid_axes"].split(",")
    assert axes == ["location", "waviness_amplitude", "ball_count", "rpm"]
    grid = ds.set_index(case=axes).unstack("case")
    assert dict((a, grid.sizes[a]) for a in axes) == {"location": 3, "waviness_amplitude": 2, "ball_count": 2, "rpm": 1}
    one = grid.sel(location="crank_rod", ball_count=9, waviness_amplitude=4e-6, rpm=600)
    case = ds.where(
        (ds.location == "crank_rod") & (ds.ball_count == 9) & (ds.waviness_amplitude == 4e-6), drop=True
    )
    np.testing.assert_array_equal(one.slider_acceleration.values, case.slider_acceleration.values[0])


def test_compressed_one_case_per_chunk(path):
    with h5py.File(path, "r") as f:
        for name in ("slider_acceleration", "bearing_force", "slider_acceleration_spectrum"):
            d = f[name]
            assert d.chunks == (1, d.shape[1]), name
            assert d.shuffle and d.compression == "gzip", name


def test_status_and_which_channels_exist_where(ds):
    assert (ds.status == 1).all()
    ideal = (ds.location == "ideal").values
    bearing = ds.bearing_force.values
    assert np.isnan(bearing[ideal]).all()
    assert np.isfinite(bearing[~ideal]).all()
    assert np.isfinite(ds.slider_acceleration.values).all()
    # each case is compared with the ideal mechanism at its own speed
    assert (ds.reference_rpm.values[ds.reference_index.values] == ds.rpm.values).all()


def test_metric_recomputed_from_the_series_matches(ds):
    """RMS deviation of the slider acceleration from the ideal mechanism after the transient."""
    window = half_open_window(ds)
    ref = ds.reference_slider_acceleration.values[ds.reference_index.values]
    dev = ds.slider_acceleration.values - ref
    rms = np.sqrt(np.mean(dev[:, window] ** 2, axis=1))
    np.testing.assert_allclose(ds.slider_acceleration_rms_deviation.values, rms, rtol=1e-12, atol=1e-12)
    peak = np.max(np.abs(dev[:, window]), axis=1)
    np.testing.assert_allclose(ds.slider_acceleration_peak_deviation.values, peak, rtol=1e-12, atol=1e-12)


def test_spectrum_recomputed_with_numpy_matches(ds):
    """One-sided amplitude spectrum, Hann window, a sinusoid of amplitude A on a bin reads A."""
    window = half_open_window(ds)
    x = ds.slider_acceleration.values[5, window]
    n = len(x)
    w = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)  # periodic Hann
    spec = np.abs(np.fft.rfft(x * w)) / w.sum()
    spec[1 : (n + 1) // 2] *= 2
    np.testing.assert_allclose(ds.frequency.values, np.fft.rfftfreq(n, 1 / ds.attrs["sample_rate"]))
    stored = ds.slider_acceleration_spectrum.values[5]
    np.testing.assert_allclose(stored, spec, rtol=1e-9, atol=1e-9 * spec.max())
