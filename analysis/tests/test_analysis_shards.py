"""studyfile.open_shards: the shard files of one study opened as one Dataset.

The synthetic tests write small shard-like files themselves; the others need the smoke
study's shards (STUDYRUN_SHARD_FILES, colon-separated) and compare them with the merged
file (STUDYRUN_MERGED_FILE) and with the single run (STUDYRUN_SMOKE_FILE).
"""

import numpy as np
import pytest
import xarray as xr

from analysis.studyfile import STRINGS_CHECKSUM, _has_dask, open_shards, open_study

LAZY = [
    pytest.param(False, id="eager"),
    pytest.param(True, id="dask", marks=pytest.mark.skipif(not _has_dask(), reason="dask is not installed")),
]

# Metrics that measure the run, not the case: they differ between two runs of a case.
RUN_DEPENDENT = {"wall_time"}


def same_attr(a, b):
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return np.array_equal(np.asarray(a), np.asarray(b))
    return a == b


def assert_same_values(got, want, skip=()):
    """`got` has the variables of `want` in the same order, with the same dimensions,
    dtypes, attributes and values (NaN equal to NaN), except the variables in `skip`,
    whose values may differ, and the checksum of one file's strings (STRINGS_CHECKSUM),
    which shards opened together do not have."""
    assert list(got.variables) == list(want.variables)
    assert dict(got.sizes) == dict(want.sizes)
    for name, w in want.variables.items():
        g = got[name].variable
        assert g.dims == w.dims, name
        assert g.dtype == w.dtype, (name, g.dtype, w.dtype)
        keys = set(w.attrs) - {STRINGS_CHECKSUM}
        assert set(g.attrs) - {STRINGS_CHECKSUM} == keys, name
        for key in keys:
            assert same_attr(g.attrs[key], w.attrs[key]), (name, key)
        if name in skip:
            continue
        if w.dtype.kind in "fc":
            np.testing.assert_array_equal(g.values, w.values, err_msg=name)  # NaN == NaN here
        else:
            assert np.array_equal(g.values, w.values), name


# ---------------------------------------------------------------- synthetic shards


def shard(case_ids, **attrs):
    """A small study-like dataset holding `case_ids` (a shard of ids 0..5)."""
    case_ids = np.asarray(case_ids, dtype=np.int32)
    n_time = 5
    time = np.arange(n_time) / 100.0
    series = case_ids[:, None] * 10.0 + np.arange(n_time)
    series[case_ids == 3, 2] = np.nan  # a NaN sample travels as NaN
    ds = xr.Dataset(
        {
            "location": ("case", np.array(["crank_ground", "crank_rod"] * 3)[case_ids].astype(object)),
            "ball_count": ("case", 8.0 + case_ids % 2, {"units": "1"}),
            "reference_index": ("case", np.zeros(len(case_ids), dtype=np.int32)),
            "peak": ("case", series.max(axis=1), {"units": "N"}),
            "force": (("case", "time"), series, {"units": "N"}),
            "reference_force": (("reference", "time"), np.arange(n_time)[None, :] * 1.0, {"units": "N"}),
        },
        coords={
            "case": ("case", case_ids, {"units": "1"}),
            "time": ("time", time, {"units": "s"}),
            "reference": ("reference", np.array([0], dtype=np.int32), {"units": "1"}),
        },
        attrs={
            "Conventions": "CF-1.8",
            "study_name": "synthetic",
            "study_fingerprint": "0123456789abcdef",
            "study_cases": np.int64(6),
            "file_cases": np.int64(len(case_ids)),
            "duration": 0.04,
            "created": f"2026-01-01T00:00:0{int(case_ids[0])}Z",
            "history": f"2026-01-01T00:00:0{int(case_ids[0])}Z: studyrun s.yaml --shard {int(case_ids[0]) + 1}/2",
        },
    )
    ds.attrs.update(attrs)
    return ds


def write(ds, path):
    ds.to_netcdf(path, engine="h5netcdf")
    return str(path)


@pytest.fixture
def two_shards(tmp_path):
    """Shards 1/2 (ids 0, 2, 4) and 2/2 (ids 1, 3, 5), and the whole study as read back
    from a file of its own."""
    paths = [write(shard([0, 2, 4]), tmp_path / "part1.h5"), write(shard([1, 3, 5]), tmp_path / "part2.h5")]
    return paths, xr.load_dataset(write(shard(np.arange(6)), tmp_path / "whole.h5"), engine="h5netcdf")


@pytest.mark.parametrize("lazy", LAZY)
def test_open_shards_gives_the_cases_in_id_order_and_the_references_once(two_shards, lazy):
    paths, whole = two_shards
    # any order of the files
    with open_shards(paths[::-1], lazy=lazy) as ds:
        assert ds.sizes["reference"] == 1
        assert ds["reference_force"].dims == ("reference", "time")
        assert_same_values(ds.load(), whole)


def test_the_default_open_mfdataset_cannot_order_interleaved_shards(two_shards):
    """Why open_shards exists: `combine="by_coords"` refuses ids 0, 2, 4 + 1, 3, 5."""
    if not _has_dask():
        pytest.skip("xr.open_mfdataset needs dask")
    paths, _ = two_shards
    with pytest.raises(ValueError, match="monotonic"):
        xr.open_mfdataset(paths, engine="h5netcdf", data_vars="all", coords="different", compat="equals", join="outer")


def test_open_shards_takes_a_glob_pattern(two_shards, tmp_path):
    paths, whole = two_shards
    with open_shards(str(tmp_path / "part*.h5")) as ds:
        np.testing.assert_array_equal(ds["case"].values, np.arange(6))
        np.testing.assert_array_equal(ds["force"].values, whole["force"].values)


def test_open_shards_keeps_the_common_attributes_and_joins_the_histories(two_shards):
    paths, _ = two_shards
    with open_shards(paths) as ds:
        assert ds.attrs["study_name"] == "synthetic"
        assert ds.attrs["study_cases"] == 6
        assert ds.attrs["file_cases"] == 6
        assert ds.attrs["duration"] == 0.04
        assert "created" not in ds.attrs  # differs between the shards
        assert ds.attrs["history"].splitlines() == [
            "2026-01-01T00:00:00Z: studyrun s.yaml --shard 1/2",
            "2026-01-01T00:00:01Z: studyrun s.yaml --shard 2/2",
        ]
        assert ds["force"].attrs["units"] == "N"


@pytest.mark.parametrize("lazy", LAZY)
def test_open_shards_refuses_shards_of_other_studies(tmp_path, lazy):
    paths = [
        write(shard([0, 2, 4]), tmp_path / "a.h5"),
        write(shard([1, 3, 5], study_fingerprint="fedcba9876543210"), tmp_path / "b.h5"),
    ]
    with pytest.raises(ValueError, match="different studies"):
        open_shards(paths, lazy=lazy)


@pytest.mark.parametrize("lazy", LAZY)
def test_open_shards_refuses_a_case_in_two_files(tmp_path, lazy):
    paths = [write(shard([0, 2, 4]), tmp_path / "a.h5"), write(shard([1, 2, 5]), tmp_path / "b.h5")]
    with pytest.raises(ValueError, match=r"more than one file: \[2\]"):
        open_shards(paths, lazy=lazy)


@pytest.mark.parametrize("lazy", LAZY)
def test_open_shards_refuses_different_reference_runs_or_times(tmp_path, lazy):
    other_reference = shard([1, 3, 5])
    other_reference["reference_force"] = other_reference["reference_force"] + 1.0
    paths = [write(shard([0, 2, 4]), tmp_path / "a.h5"), write(other_reference, tmp_path / "b.h5")]
    with pytest.raises(ValueError, match="not shards of one study"):
        open_shards(paths, lazy=lazy)
    other_times = shard([1, 3, 5]).assign_coords(time=np.arange(5) / 50.0)
    paths[1] = write(other_times, tmp_path / "c.h5")
    with pytest.raises(ValueError, match="not shards of one study"):
        open_shards(paths, lazy=lazy)


def test_open_shards_refuses_no_files(tmp_path):
    with pytest.raises(ValueError, match="no shard files"):
        open_shards([])
    with pytest.raises(ValueError, match="no shard file matches"):
        open_shards(str(tmp_path / "none*.h5"))


# ---------------------------------------------------------------- the smoke study's shards


@pytest.mark.parametrize("lazy", LAZY)
def test_shards_open_as_the_merged_file(shard_paths, merged_path, lazy):
    """open_shards gives what `studyrun merge` writes, value for value."""
    with open_shards(shard_paths, lazy=lazy) as got, open_study(merged_path) as want:
        assert_same_values(got.load(), want.load())
        for key, value in want.attrs.items():
            if key in ("created", "history"):
                continue
            assert key in got.attrs, key
            assert same_attr(got.attrs[key], value), key


def test_shards_open_as_the_single_run(shard_paths, smoke):
    """The shards of a study together equal one run of it (the run's timing aside)."""
    with open_shards(shard_paths) as got:
        assert len(shard_paths) > 1
        assert_same_values(got.load(), smoke, skip=RUN_DEPENDENT)
        assert got.attrs["file_cases"] == smoke.sizes["case"] == smoke.attrs["study_cases"]


@pytest.mark.parametrize("lazy", LAZY)
def test_open_shards_gathers_each_shards_own_references(tmp_path, lazy):
    """A shard holds the references its cases use: shard 1/2 (ids 0, 2, 4) those of
    speeds 0 and 2, shard 2/2 (ids 1, 3, 5) that of speed 1. Opened together, every
    reference is there once, in id order, and each case's `reference_index` points at
    its own, as in the single run's file."""
    speed = np.array([0, 1, 2, 1, 0, 1])  # each case's reference id
    curves = np.arange(3)[:, None] * 100.0 + np.arange(5)

    def with_refs(ds, ids):
        ids = np.asarray(ids, dtype=np.int32)
        rows = np.searchsorted(ids, speed[ds["case"].values])
        ds = ds.drop_vars(["reference_force", "reference"])
        ds["reference_index"] = ("case", rows.astype(np.int32))
        ds["reference_force"] = (("reference", "time"), curves[ids], {"units": "N"})
        return ds.assign_coords(reference=("reference", ids, {"units": "1"}))

    paths = [
        write(with_refs(shard([0, 2, 4]), [0, 2]), tmp_path / "part1.h5"),
        write(with_refs(shard([1, 3, 5]), [1]), tmp_path / "part2.h5"),
    ]
    whole = xr.load_dataset(write(with_refs(shard(np.arange(6)), [0, 1, 2]), tmp_path / "whole.h5"),
                            engine="h5netcdf")
    with open_shards(paths, lazy=lazy) as ds:
        assert ds["reference"].values.tolist() == [0, 1, 2]
        assert_same_values(ds.load(), whole)
