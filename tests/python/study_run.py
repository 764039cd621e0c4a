"""What the Python tests share: running a grid written here with the studyrun binary
named by STUDYRUN_BIN (the test is skipped without it), and reading a study file with
h5py."""

import math
import os
import subprocess

import pytest


def studyrun_binary():
    """The absolute path in STUDYRUN_BIN; skips the calling test when it is unset."""
    value = os.environ.get("STUDYRUN_BIN")
    if not value:
        pytest.skip("STUDYRUN_BIN is not set")
    return os.path.abspath(value)


def run_grid(directory, name, grid):
    """Writes `grid` as `directory/<name>.yaml`, runs it quietly into
    `directory/<name>.h5` (failing on a non-zero exit) and returns that path."""
    path = directory / f"{name}.yaml"
    path.write_text(grid)
    out = directory / f"{name}.h5"
    subprocess.run([studyrun_binary(), str(path), "-o", str(out), "-q"], check=True)
    return out


def opened_run(tmp_path_factory, name, grid):
    """Runs `grid` in a fresh temporary directory (`run_grid`) and yields its file open
    in h5py: the body of a module-scoped fixture (`yield from opened_run(...)`)."""
    import h5py

    path = run_grid(tmp_path_factory.mktemp(name), name, grid)
    with h5py.File(path, "r") as f:
        yield f


def text(value):
    """A text value or attribute as str (h5py gives variable-length strings as bytes)."""
    return value.decode() if isinstance(value, bytes) else str(value)


def window(f):
    """The analysed samples' indices in h5py file `f`:
    ceil(transient fs - 1e-9) <= k < N - 1 (docs/model.md §5.3)."""
    fs, n_all = f.attrs["sample_rate"], f["time"].shape[0]
    k0 = max(0, math.ceil(f.attrs["transient"] * fs - 1e-9))
    return slice(min(k0, n_all - 1), n_all - 1)
