"""Chunks that studyrun compresses itself and writes with HDF5's direct chunk write,
as h5py and xarray see them: the standard shuffle + gzip filters, and the values bit
for bit.

Environment:
  STUDYRUN_CHUNKS_DIR  the directory `cargo test --release --test hdf5_file` leaves at
                       target/test-files/direct_chunks (NAME.h5 with a [case, time]
                       variable `x`, NAME.f64 its expected values as raw little-endian
                       float64); unset: skip all.
"""

import os

import h5py
import numpy as np
import pytest
import xarray as xr

# name: (stored dtype, deflate level; 0 = no filter)
FILES = {
    "f64_deflate1": (np.float64, 1),
    "f64_deflate9": (np.float64, 9),
    "f64_plain": (np.float64, 0),
    "f32_deflate4": (np.float32, 4),
}


@pytest.fixture(scope="module")
def directory():
    value = os.environ.get("STUDYRUN_CHUNKS_DIR")
    if not value:
        pytest.skip(
            "STUDYRUN_CHUNKS_DIR is not set: run `cargo test --release --test hdf5_file` "
            "and point it at target/test-files/direct_chunks"
        )
    assert os.path.isdir(value), f"STUDYRUN_CHUNKS_DIR={value} does not exist"
    return value


def expected(directory, name, shape):
    return np.fromfile(os.path.join(directory, f"{name}.f64"), dtype="<f8").reshape(shape)


@pytest.mark.parametrize("name", FILES)
def test_filters_are_standard_shuffle_and_gzip(directory, name):
    dtype, level = FILES[name]
    with h5py.File(os.path.join(directory, f"{name}.h5"), "r") as f:
        d = f["x"]
        assert d.dtype == dtype
        assert d.chunks == (1, d.shape[1])
        if level:
            assert d.shuffle, "no shuffle filter"
            assert d.compression == "gzip"
            assert d.compression_opts == level
        else:
            assert not d.shuffle and d.compression is None


@pytest.mark.parametrize("name", FILES)
def test_values_read_back_bit_for_bit(directory, name):
    with h5py.File(os.path.join(directory, f"{name}.h5"), "r") as f:
        got = f["x"][...].astype(np.float64)
        # One row at a time too: each row is one chunk.
        rows = [f["x"][r, :].astype(np.float64) for r in range(f["x"].shape[0])]
    want = expected(directory, name, got.shape)
    np.testing.assert_array_equal(got.view(np.uint64), want.view(np.uint64))
    np.testing.assert_array_equal(np.stack(rows).view(np.uint64), want.view(np.uint64))


def test_xarray_opens_the_file(directory):
    with xr.open_dataset(os.path.join(directory, "f64_deflate1.h5"), engine="h5netcdf") as ds:
        x = ds["x"].load()
    assert x.dims == ("case", "time")
    want = expected(directory, "f64_deflate1", x.shape)
    np.testing.assert_array_equal(x.values.view(np.uint64), want.view(np.uint64))
