"""The work-precision diagram of an accuracy file (STUDYRUN_ACCURACY_FILE, from
`studyrun accuracy studies/accuracy_smoke.yaml`; unset: skip)."""

import os
import sys
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "analysis"))
import work_precision  # noqa: E402


@pytest.fixture(scope="module")
def ds():
    path = os.environ.get("STUDYRUN_ACCURACY_FILE")
    if not path:
        pytest.skip("STUDYRUN_ACCURACY_FILE is not set")
    with xr.open_dataset(path, engine="h5netcdf") as d:
        yield d.load()


def test_errors_fall_as_dopri5_tightens(ds):
    settings, costs, errs = work_precision.points(ds)["dopri5"]
    assert list(settings) == sorted(settings, reverse=True)
    # the tightest setting beats the loosest by orders of magnitude and costs more
    assert errs[-1] < errs[0] / 100
    assert costs[-1] > costs[0]


def test_every_method_is_measured_with_its_cost(ds):
    pts = work_precision.points(ds, cost="rhs_evals")
    assert set(pts) == {"dopri5", "tsit5", "dop853", "sdirk4", "rk4"}
    for _, costs, errs in pts.values():
        assert np.all(costs > 0) and np.all(np.isfinite(errs))


def test_diagram_is_written(ds, tmp_path):
    out = work_precision.plot(ds, str(tmp_path / "wp.png"))
    img = matplotlib.image.imread(out)
    assert img.shape[0] > 300 and img.shape[1] > 400
    assert os.path.getsize(out) > 20_000
