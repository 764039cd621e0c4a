"""`studyrun inspect` and `studyrun merge` read study files that standard netCDF tools
have rewritten: NCO (ncatted, ncks), netCDF-C (nccopy) and xarray (to_netcdf with
h5netcdf or netCDF4). What they change in the file (seen with h5py):

* ncatted writes text attributes as NC_CHAR: fixed-length ASCII strings, scalar (an
  empty one with a null dataspace; UTF-8 text as bytes in an ASCII-typed string), and
  the global `history` (fixed-length, newest line first) and `NCO`;
  `-a name,global,c,sng,...` writes an NC_STRING as a one-element array;
* nccopy -k nc4, ncks, xarray: every attribute becomes a one-element array (strings stay
  variable-length UTF-8), `_NCProperties` (fixed-length) is added to the root and
  `_Netcdf4Coordinates` (int32 array) to every variable; ncks and xarray also add
  `_Netcdf4Dimid` to non-coordinate variables; nccopy stores the series in one chunk
  per variable; ncks sorts the variables by name and compresses the 1-D ones;
* xarray adds `_FillValue = NaN` to float variables that had none (`time`, parameters),
  and the netCDF4 engine writes every text attribute as NC_CHAR.

Environment (unset: skip): STUDYRUN_BIN (the studyrun binary, e.g.
target/release/studyrun), STUDYRUN_SMOKE_FILE, and for the merge tests
STUDYRUN_SHARD_FILES (colon-separated shards of the smoke study) and
STUDYRUN_MERGED_FILE (`studyrun merge` of them). Each tool missing from PATH
(Debian: apt-get install nco netcdf-bin) skips its cases.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from analysis.studyfile import _has_dask, open_shards  # noqa: E402

INSPECT_LINES = ("study:", "grid:", "sampling:", "effects:", "cases:")


def ncatted(*args):
    def apply(src, dst):
        shutil.copyfile(src, dst)
        run(["ncatted", *args, str(dst)])

    return apply, "ncatted"


def ncks(*args):
    return (lambda src, dst: run(["ncks", "-O", *args, str(src), str(dst)])), "ncks"


def nccopy(*args):
    return (lambda src, dst: run(["nccopy", *args, str(src), str(dst)])), "nccopy"


def to_netcdf(engine):
    def apply(src, dst):
        with xr.open_dataset(src, engine="h5netcdf") as ds:
            ds.load().to_netcdf(dst, engine=engine)

    return apply, ("netCDF4" if engine == "netcdf4" else None)


TOOLS = {
    # the command: a new global NC_CHAR attribute (and NCO's history)
    "ncatted_global_char": ncatted("-a", "comment,global,c,c,x"),
    "ncatted_global_char_empty": ncatted("-h", "-a", "comment,global,c,c,"),
    "ncatted_global_char_utf8": ncatted("-h", "-a", "comment,global,c,c,\u00e9t\u00e9"),
    "ncatted_global_string": ncatted("-h", "-a", "comment,global,c,sng,x"),
    # an attribute studyrun reads, rewritten with the same text as NC_CHAR
    "ncatted_variable_char": ncatted("-h", "-a", "units,slider_acceleration,o,c,m s-2"),
    "ncatted_root_char": ncatted("-h", "-a", "study_name,global,o,c,smoke"),
    "nccopy_nc4": nccopy("-k", "nc4"),
    "ncks": ncks(),
    "ncks_nc4": ncks("-4"),
    "xarray_h5netcdf": to_netcdf("h5netcdf"),
    "xarray_netcdf4": to_netcdf("netcdf4"),
}


def run(cmd, **kwargs):
    result = subprocess.run(cmd, capture_output=True, text=True, timeout=300, **kwargs)
    assert result.returncode == 0, f"{' '.join(map(str, cmd))} failed:\n{result.stdout}{result.stderr}"
    return result


def env_file(variable):
    value = os.environ.get(variable)
    if not value:
        pytest.skip(f"{variable} is not set")
    assert os.path.exists(value), f"{variable}={value} does not exist"
    return os.path.abspath(value)


@pytest.fixture(scope="module")
def studyrun():
    return env_file("STUDYRUN_BIN")


@pytest.fixture(scope="module")
def smoke_path():
    return env_file("STUDYRUN_SMOKE_FILE")


def rewrite(tool, src, dst):
    """`src` rewritten by `tool` into `dst`, or skip if the tool is missing."""
    apply, needs = TOOLS[tool]
    if needs == "netCDF4":
        pytest.importorskip("netCDF4")
    elif needs and shutil.which(needs) is None:
        pytest.skip(f"{needs} is not installed (apt-get install nco netcdf-bin)")
    apply(src, dst)
    return dst


def inspect_lines(studyrun, path):
    out = run([studyrun, "inspect", str(path)]).stdout
    return [line for line in out.splitlines() if line.startswith(INSPECT_LINES)]


@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_inspect_reads_a_file_a_tool_rewrote(studyrun, smoke_path, tool, tmp_path):
    copy = rewrite(tool, smoke_path, tmp_path / "smoke.h5")
    assert inspect_lines(studyrun, copy) == inspect_lines(studyrun, smoke_path)


def test_inspect_reads_a_numeric_array_attribute(studyrun, smoke_path, tmp_path):
    """A global attribute of two numbers (`ncatted -a pair,global,c,d,"1,2"`)."""
    if shutil.which("ncatted") is None:
        pytest.skip("ncatted is not installed")
    copy = tmp_path / "smoke.h5"
    shutil.copyfile(smoke_path, copy)
    run(["ncatted", "-h", "-a", "pair,global,c,d,1,2", str(copy)])
    assert inspect_lines(studyrun, copy) == inspect_lines(studyrun, smoke_path)


@pytest.fixture(scope="module")
def shards():
    value = os.environ.get("STUDYRUN_SHARD_FILES")
    if not value:
        pytest.skip("STUDYRUN_SHARD_FILES is not set")
    return [os.path.abspath(p) for p in value.split(os.pathsep) if p]


@pytest.mark.parametrize("which", ["all", "last"])
@pytest.mark.parametrize("tool", sorted(TOOLS))
def test_merge_reads_shards_a_tool_rewrote(studyrun, shards, tool, which, tmp_path):
    """Every shard (`all`) or only the last one (`last`: the others as studyrun wrote
    them) rewritten by the tool; the merge holds what merging the originals does."""
    merged = env_file("STUDYRUN_MERGED_FILE")
    rewritten = [
        rewrite(tool, s, tmp_path / f"part{k}.h5") if which == "all" or k == len(shards) - 1 else s
        for k, s in enumerate(shards)
    ]
    out = tmp_path / "merged.h5"
    run([studyrun, "merge", str(out), *map(str, rewritten)])
    raw = dict(engine="h5netcdf", decode_times=False)  # `time` as stored: seconds and its units
    with xr.open_dataset(out, **raw) as got, xr.open_dataset(merged, **raw) as want:
        assert set(got.variables) == set(want.variables)
        assert dict(got.sizes) == dict(want.sizes)
        for name, w in want.variables.items():
            g = got[name]
            assert g.dims == w.dims, name
            assert g.dtype == w.dtype, (name, g.dtype, w.dtype)
            assert g.attrs.get("units") == w.attrs.get("units"), name
            if w.dtype.kind in "fc":
                np.testing.assert_array_equal(g.values, w.values, err_msg=name)
            else:
                assert np.array_equal(g.values, w.values), name
        for key in ("study_name", "study_fingerprint", "grid_axes", "study_cases", "file_cases"):
            assert str(got.attrs[key]) == str(want.attrs[key]), key


def test_time_in_other_units_is_refused_not_taken_for_seconds(studyrun, smoke_path, tmp_path):
    """A tool that writes `time` in milliseconds (xarray with another encoding): the
    numbers are not seconds, so studyrun refuses the file, naming the units."""
    out = tmp_path / "ms.h5"
    with xr.open_dataset(smoke_path, engine="h5netcdf") as ds:
        ds = ds.load()
        ds.time.encoding.update(units="milliseconds since 1970-01-01", dtype="float64")
        ds.to_netcdf(out, engine="h5netcdf")
    result = subprocess.run([studyrun, "inspect", str(out)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "milliseconds since 1970-01-01" in result.stderr and "`time`" in result.stderr, result.stderr


@pytest.mark.parametrize("lazy", [False, True])
def test_open_shards_reads_a_shard_xarray_rewrote(shards, tmp_path, lazy):
    """A shard written back from xarray's default (datetime) decoding has times a
    nanosecond early; open_shards puts them back and opens the set like the originals."""
    if lazy and not _has_dask():
        pytest.skip("lazy opening needs dask")
    rewritten = rewrite("xarray_h5netcdf", shards[-1], tmp_path / "last.h5")
    with h5py.File(shards[-1], "r") as a, h5py.File(rewritten, "r") as b:
        assert (a["time"][:] != b["time"][:]).any(), "the round trip moves some time"
    with open_shards(shards, lazy=lazy) as want, open_shards([*shards[:-1], rewritten], lazy=lazy) as got:
        np.testing.assert_array_equal(got.time.values, want.time.values)
        for name in ("slider_acceleration", "stiffness", "case"):
            np.testing.assert_array_equal(got[name].values, want[name].values, err_msg=name)
