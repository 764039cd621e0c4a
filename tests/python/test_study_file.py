"""A study file as Python analysis sees it (h5py and xarray only).

Environment:
  STUDYRUN_TEST_FILE  path of the study file (e.g. target/test-files/synthetic_study.h5,
                      left by `cargo test --release --test hdf5_file`); unset: skip all.
  STUDYRUN_TEST_AXES  comma-separated names of f64 case parameters that form a full
                      grid (e.g. ball_count,rpm); unset: skip the unstack check.
"""

import os

import h5py
import numpy as np
import pytest
import xarray as xr

DIMS = {"case", "time", "frequency", "reference"}
ARRAY_ROLES = {"series", "spectrum", "reference_series"}


@pytest.fixture(scope="module")
def path():
    value = os.environ.get("STUDYRUN_TEST_FILE")
    if not value:
        pytest.skip(
            "STUDYRUN_TEST_FILE is not set: run `cargo test --release --test hdf5_file` "
            "and point it at target/test-files/synthetic_study.h5"
        )
    assert os.path.isfile(value), f"STUDYRUN_TEST_FILE={value} does not exist"
    return value


@pytest.fixture(scope="module")
def ds(path):
    """The file as analysis/ opens it: `time` in seconds, not decoded to dates."""
    with xr.open_dataset(path, engine="h5netcdf", decode_times=False) as dataset:
        yield dataset.load()


def roles(path):
    """{dataset name: studyrun_role} for the caller variables."""
    with h5py.File(path, "r") as f:
        return {
            name: obj.attrs["studyrun_role"]
            for name, obj in f.items()
            if isinstance(obj, h5py.Dataset) and "studyrun_role" in obj.attrs
        }


def test_dimensions_are_named_without_phony_dims(ds):
    assert set(ds.sizes) == DIMS
    for name, var in ds.variables.items():
        assert not any(d.startswith("phony_dim") for d in var.dims), (name, var.dims)
        assert set(var.dims) <= DIMS, (name, var.dims)
    assert set(ds.coords) >= DIMS


def test_every_variable_has_units_and_long_name(ds):
    for name, var in ds.variables.items():
        assert isinstance(var.attrs.get("units"), str), f"{name}: no units"
        long_name = var.attrs.get("long_name")
        assert isinstance(long_name, str) and long_name, f"{name}: no long_name"


def test_coordinates_match_the_file(ds, path):
    with h5py.File(path, "r") as f:
        case = f["case"][:]
        time = f["time"][:]
        reference = f["reference"][:]
        ids = {name: f[name].dtype for name in ("case", "reference", "reference_index")}
    # CF-1.8 §2.2 has no unsigned or 64-bit integers: the ids are int32 (NC_INT)
    assert ids == {name: np.dtype(np.int32) for name in ids}, ids
    np.testing.assert_array_equal(ds["case"].values, case)
    assert len(np.unique(case)) == len(case)
    # time stays float seconds (not decoded to timedelta or datetime)
    assert ds["time"].dtype == np.float64
    np.testing.assert_array_equal(ds["time"].values, time)
    np.testing.assert_array_equal(ds["reference"].values, reference)
    assert ds["reference_index"].max() < ds.sizes["reference"]


def test_status_is_a_cf_flag_variable_and_pending_rows_are_nan(ds, path):
    status = ds["status"]
    assert status.dtype == np.int8
    np.testing.assert_array_equal(status.attrs["flag_values"], [0, 1, 2])
    assert status.attrs["flag_meanings"] == "pending ok failed"
    assert set(np.unique(status.values)) <= {0, 1, 2}
    series = [n for n, r in roles(path).items() if r == "series"]
    assert series, "no series variables"
    pending = status.values == 0
    for name in series:
        values = ds[name].values
        assert np.isnan(values[pending]).all(), name
        assert np.isfinite(values[status.values == 1]).all(), name


def test_root_attributes(ds):
    assert ds.attrs["studyrun_file_format"] == 2
    for key in ("Conventions", "studyrun_version", "git_commit", "created"):
        assert isinstance(ds.attrs.get(key), str), key


def test_parameter_grid_unstacks(ds):
    axes = os.environ.get("STUDYRUN_TEST_AXES")
    if not axes:
        pytest.skip("STUDYRUN_TEST_AXES is not set (e.g. ball_count,rpm)")
    axes = [a.strip() for a in axes.split(",")]
    for a in axes:
        assert ds[a].dims == ("case",) and ds[a].dtype == np.float64, a
    grid = ds.set_index(case=axes).unstack("case")
    shape = [len(np.unique(ds[a].values)) for a in axes]
    assert [grid.sizes[a] for a in axes] == shape
    assert int(np.prod(shape)) == ds.sizes["case"], "parameters do not form a full grid"
    # each case lands where its parameter values say
    for i in range(ds.sizes["case"]):
        where = {a: ds[a].values[i] for a in axes}
        assert grid["status"].sel(where).item() == ds["status"].values[i]
        for name in ("reference_index", next(iter(grid.data_vars))):
            np.testing.assert_array_equal(
                grid[name].sel(where).values, ds[name].isel(case=i).values
            )


def test_arrays_are_chunked_per_case_with_shuffle_and_gzip(path):
    arrays = [n for n, r in roles(path).items() if r in ARRAY_ROLES]
    assert arrays, "no series or spectra"
    with h5py.File(path, "r") as f:
        for name in arrays:
            d = f[name]
            assert d.ndim == 2, name
            assert d.chunks == (1, d.shape[1]), (name, d.chunks)
            assert d.shuffle, f"{name}: no shuffle filter"
            assert d.compression == "gzip", f"{name}: compression {d.compression}"
