"""A study whose `cases:` vary a parameter outside the grid, e.g.

    grid: {location: [crank_ground, crank_rod], ball_count: [8, 9]}
    cases:
      - {location: crank_rod, ball_count: 9, stiffness: "5e9 N/m^1.5"}
      - {location: crank_rod, ball_count: 10, clearance: "20 um"}

studyrun writes the grid's cases (ids 0-3) then the explicit ones (4, 5), with
`grid_axes = "location,ball_count"`: case 4 has the grid axes of case 3. open_study
opens it, select_cases finds every case, and unstack refuses it (it would have to put
cases 3 and 4 in one cell). The file here is written like studyrun's (the layout
`studyrun` gave for the study above).
"""

import numpy as np
import pytest
import xarray as xr

from analysis.studyfile import open_study, select_cases, unstack


@pytest.fixture
def explicit(tmp_path):
    n_time = 4
    location = np.array(["crank_ground", "crank_ground", "crank_rod", "crank_rod", "crank_rod", "crank_rod"], dtype=object)
    ds = xr.Dataset(
        {
            "ball_count": ("case", [8.0, 9.0, 8.0, 9.0, 9.0, 10.0], {"units": "1"}),
            "clearance": ("case", [4e-5, 4e-5, 4e-5, 4e-5, 4e-5, 2e-5], {"units": "m"}),
            "stiffness": ("case", [9.57e9, 9.57e9, 9.57e9, 9.57e9, 5e9, 9.57e9]),
            "location": ("case", location, {"units": "1"}),
            "slider_acceleration": (("case", "time"), np.arange(6)[:, None] + np.zeros(n_time), {"units": "m s-2"}),
        },
        coords={"case": ("case", np.arange(6, dtype=np.int32)), "time": ("time", np.arange(n_time) * 1e-4)},
        attrs={"grid_axes": "location,ball_count", "study_cases": np.int64(6)},
    )
    path = tmp_path / "cases.h5"
    ds.to_netcdf(path, engine="h5netcdf")
    with open_study(path) as opened:
        yield opened.load()


def test_open_study_opens_a_study_with_cases_outside_the_grid(explicit):
    assert explicit.sizes["case"] == 6
    np.testing.assert_array_equal(explicit["case"].values, np.arange(6))
    assert explicit.attrs["grid_axes"] == "location,ball_count"


def test_select_cases_finds_the_extra_cases(explicit):
    np.testing.assert_array_equal(select_cases(explicit, location="crank_rod", ball_count=9), [3, 4])
    np.testing.assert_array_equal(select_cases(explicit, location="crank_rod", ball_count=9, stiffness=5e9), [4])
    np.testing.assert_array_equal(select_cases(explicit, clearance=2e-5), [5])
    one = explicit.isel(case=select_cases(explicit, stiffness=5e9))
    np.testing.assert_array_equal(one["slider_acceleration"].values, [[4.0] * 4])


def test_unstack_refuses_cases_the_grid_axes_do_not_tell_apart(explicit):
    with pytest.raises(ValueError, match="do not identify the cases uniquely"):
        unstack(explicit)
    # without the extra case that repeats a grid cell, the rest unstack (10 balls: a new cell)
    rest = explicit.isel(case=[0, 1, 2, 3, 5])
    grid = unstack(rest)
    assert dict(grid.sizes)["ball_count"] == 3
    assert np.isnan(grid["stiffness"].sel(location="crank_ground", ball_count=10.0))
