"""analysis/sensitivity.py: Sobol indices of the Ishigami function from a Saltelli design
(closed-form values inside the bootstrap intervals), exact main effects on grids
against closed forms, the assumed Saltelli file layout, and the study file's grid."""

import itertools
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from SALib.sample import sobol as saltelli_sample

from analysis.sensitivity import (
    analyse,
    check_saltelli_rows,
    grid_indices,
    plot_indices,
    saltelli_indices,
    study_saltelli,
    study_grid,
)
from analysis.studyfile import open_study

SCRIPT = Path(__file__).resolve().parents[1] / "sensitivity.py"

A, B = 7.0, 0.1
ISHIGAMI = {"num_vars": 3, "names": ["x1", "x2", "x3"], "bounds": [[-np.pi, np.pi]] * 3}


def ishigami(x, a=A, b=B):
    """Ishigami & Homma (1990): sin x1 + a sin² x2 + b x3⁴ sin x1, x_i uniform on [−π, π]."""
    return np.sin(x[:, 0]) + a * np.sin(x[:, 1]) ** 2 + b * x[:, 2] ** 4 * np.sin(x[:, 0])


def ishigami_closed_form(a=A, b=B):
    """(S1, ST) of the Ishigami function from its variance decomposition:
    V1 = (1 + bπ⁴/5)²/2, V2 = a²/8, V3 = 0, V13 = 8b²π⁸/225, V = a²/8 + bπ⁴/5 + b²π⁸/18 + 1/2."""
    pi4 = np.pi**4
    v = a**2 / 8 + b * pi4 / 5 + b**2 * pi4**2 / 18 + 0.5
    v1, v2, v13 = 0.5 * (1 + b * pi4 / 5) ** 2, a**2 / 8, 8 * b**2 * pi4**2 / 225
    return np.array([v1, v2, 0.0]) / v, np.array([v1 + v13, v2, v13]) / v


def test_ishigami_closed_form_is_the_literature_value():
    s1, st = ishigami_closed_form()
    np.testing.assert_allclose(s1, [0.3139, 0.4424, 0.0], atol=5e-5)
    np.testing.assert_allclose(st, [0.5576, 0.4424, 0.2437], atol=5e-5)


# N = 4096 base rows (32 768 evaluations): over seeds 0..19 every index lay inside its
# 95 % interval and the widest half-width was 0.044.
@pytest.mark.parametrize("second_order", [True, False])
def test_ishigami_indices_within_bootstrap_intervals(second_order):
    x = saltelli_sample.sample(ISHIGAMI, 4096, calc_second_order=second_order, seed=7)
    result = saltelli_indices(ISHIGAMI, x, ishigami(x), second_order=second_order, resamples=1000, seed=7)
    s1, st = ishigami_closed_form()
    assert result.names == ["x1", "x2", "x3"]
    assert result.samples == x.shape[0]
    assert np.all(np.abs(result.first - s1) <= result.first_conf), (result.first, result.first_conf, s1)
    assert np.all(np.abs(result.total - st) <= result.total_conf), (result.total, result.total_conf, st)
    # the intervals are informative: half-widths well below the gaps between the indices
    assert np.all(result.first_conf > 0) and np.all(result.first_conf < 0.06), result.first_conf
    assert np.all(result.total_conf > 0) and np.all(result.total_conf < 0.06), result.total_conf
    # the estimates themselves are close
    np.testing.assert_allclose(result.first, s1, atol=0.03)
    np.testing.assert_allclose(result.total, st, atol=0.03)


def test_bootstrap_is_reproducible_with_a_seed():
    x = saltelli_sample.sample(ISHIGAMI, 256, seed=1)
    y = ishigami(x)
    r0, r1 = saltelli_indices(ISHIGAMI, x, y, seed=0), saltelli_indices(ISHIGAMI, x, y, seed=0)
    r2 = saltelli_indices(ISHIGAMI, x, y, seed=5)
    np.testing.assert_array_equal(r0.first_conf, r1.first_conf)
    np.testing.assert_array_equal(r0.total_conf, r1.total_conf)
    assert not np.array_equal(r0.first_conf, r2.first_conf)
    np.testing.assert_array_equal(r0.first, r2.first)  # the estimates do not depend on the bootstrap


def test_saltelli_rows_out_of_order_are_refused():
    x = saltelli_sample.sample(ISHIGAMI, 64, seed=3)
    assert check_saltelli_rows(x) == 64
    with pytest.raises(ValueError, match="multiple of 8 rows"):
        check_saltelli_rows(x[:-1])
    swapped = x.copy()
    swapped[[1, 2]] = swapped[[2, 1]]  # AB_1 and AB_2 of the first block exchanged
    with pytest.raises(ValueError, match="row 1 should be AB_1"):
        saltelli_indices(ISHIGAMI, swapped, ishigami(swapped))
    with pytest.raises(ValueError, match="multiple of 5 rows"):  # D + 2 without second order
        check_saltelli_rows(x[:8], second_order=False)
    y = ishigami(x)
    y[9] = np.nan
    with pytest.raises(ValueError, match="not finite"):
        saltelli_indices(ISHIGAMI, x, y)
    with pytest.raises(ValueError, match="511 outputs for 512"):
        saltelli_indices(ISHIGAMI, x, y[:-1])


def grid(**axes):
    """Broadcastable 1-D coordinate arrays of a cartesian grid."""
    return {name: xr.DataArray(np.asarray(v), dims=[name], coords={name: v}) for name, v in axes.items()}


def test_additive_grid_main_effects_sum_to_one_and_equal_closed_form():
    g = grid(x=[0.0, 1.0, 3.0], y=[-2.0, 0.5, 1.0, 4.0], location=["crank_ground", "crank_rod"])
    shift = xr.DataArray([0.0, 5.0], dims=["location"], coords={"location": g["location"].values})
    y = 2.0 * g["x"] + g["y"] ** 2 + shift
    result = grid_indices(y)
    parts = np.array([np.var(2.0 * g["x"].values), np.var(g["y"].values ** 2), np.var(shift.values)])
    assert result.names == ["x", "y", "location"]
    np.testing.assert_allclose(result.first, parts / parts.sum(), rtol=1e-12)
    np.testing.assert_allclose(result.first.sum(), 1.0, rtol=1e-12)
    np.testing.assert_allclose(result.total, result.first, rtol=1e-12)  # no interactions
    assert np.all(np.isnan(result.first_conf))


def test_non_additive_grid_main_effects_sum_below_one_as_closed_form():
    xv, yv = np.array([1.0, 2.0, 4.0]), np.array([0.5, 1.0, 3.0, 5.0])
    g = grid(x=xv, y=yv)
    result = grid_indices(g["x"] * g["y"])
    # Y = x y with x, y independent: Var = v_x v_y + v_x m_y² + v_y m_x²,
    # V_x = m_y² v_x, V_y = m_x² v_y, V_xy = v_x v_y.
    mx, my, vx, vy = xv.mean(), yv.mean(), xv.var(), yv.var()
    v = vx * vy + vx * my**2 + vy * mx**2
    np.testing.assert_allclose(result.first, [my**2 * vx / v, mx**2 * vy / v], rtol=1e-12)
    np.testing.assert_allclose(result.total, [(my**2 * vx + vx * vy) / v, (mx**2 * vy + vx * vy) / v], rtol=1e-12)
    np.testing.assert_allclose(1.0 - result.first.sum(), vx * vy / v, rtol=1e-12)
    assert result.first.sum() < 0.99


def test_grid_with_a_hole_or_a_constant_is_refused():
    g = grid(x=[0.0, 1.0], y=[0.0, 1.0, 2.0])
    y = (g["x"] + g["y"]).rename("m")
    with pytest.raises(ValueError, match=r"m is NaN in 1 of 6 grid cells"):
        grid_indices(y.where(~((g["x"] == 1) & (g["y"] == 2))))
    with pytest.raises(ValueError, match="constant"):
        grid_indices(0.0 * y)


def flat_study(path, columns, metrics, axes=(), attrs=None, order=None):
    """Write a minimal study file: `case` with per-case parameters and metrics, in `order`."""
    n = len(next(iter(columns.values())))
    order = np.arange(n) if order is None else np.asarray(order)
    data = {name: ("case", np.asarray(v)[order]) for name, v in {**columns, **metrics}.items()}
    ds = xr.Dataset(data, coords={"case": order.astype("int32")})
    ds.attrs.update({"grid_axes": ",".join(axes), **(attrs or {})})
    ds.to_netcdf(path, engine="h5netcdf")
    return path


def test_grid_study_file_in_shuffled_case_order(tmp_path):
    rows = list(itertools.product([1.0, 2.0, 4.0], [0.5, 1.0, 3.0]))
    x, y = np.array(rows).T
    order = np.random.default_rng(0).permutation(len(rows))
    path = flat_study(tmp_path / "grid.h5", {"rpm": x, "clearance": y}, {"m": x * y}, axes=("rpm", "clearance"),
                      order=order)
    with open_study(path) as ds:
        result = study_grid(ds, "m")
    direct = grid_indices(grid(rpm=[1.0, 2.0, 4.0], clearance=[0.5, 1.0, 3.0])["rpm"]
                          * grid(clearance=[0.5, 1.0, 3.0])["clearance"])
    np.testing.assert_allclose(result.first, direct.first, rtol=1e-12)
    np.testing.assert_allclose(result.total, direct.total, rtol=1e-12)


def test_saltelli_study_file_layout_through_the_cli(tmp_path, assert_png):
    problem = {"num_vars": 3, "names": ["clearance", "rpm", "damping"], "bounds": [[-np.pi, np.pi]] * 3}
    x = saltelli_sample.sample(problem, 1024, seed=2)
    path = flat_study(
        tmp_path / "design.h5",
        {name: x[:, j] for j, name in enumerate(problem["names"])},
        {"ishigami": ishigami(x)},
        attrs={"design_method": "saltelli", "design_parameters": "clearance,rpm,damping"},
    )
    direct = saltelli_indices(problem, x, ishigami(x), resamples=200, seed=4)
    results = analyse(path, ["ishigami"], resamples=200, seed=4, outdir=tmp_path / "fig")
    (indices,) = results["ishigami"]
    assert indices.point == {}
    np.testing.assert_array_equal(indices.first, direct.first)
    np.testing.assert_array_equal(indices.total_conf, direct.total_conf)
    assert_png(tmp_path / "fig" / "sensitivity_ishigami.png", min_kb=10)
    out = subprocess.run(
        [sys.executable, str(SCRIPT), str(path), "--metric", "ishigami",
         "--resamples", "200", "--seed", "4"],
        capture_output=True, text=True, check=True,
    ).stdout
    assert "Saltelli design, 95% intervals (8192 cases)" in out
    assert f"{direct.first[1]:.4f} ± {direct.first_conf[1]:.4f}" in out


def test_a_design_repeated_over_a_grid_axis_is_analysed_per_grid_point(tmp_path):
    """A Saltelli design × rpm: [300, 600] (case id // design_rows the grid point, as
    studyrun writes it) gives one set of indices per rpm, named in the output, equal to
    each half analysed alone; the metric depends on a different parameter at each speed,
    so pooled indices would be wrong for both. study_saltelli refuses to pool them."""
    problem = {"num_vars": 3, "names": ["clearance", "rpm_x", "damping"], "bounds": [[-np.pi, np.pi]] * 3}
    x = saltelli_sample.sample(problem, 64, seed=3)
    rows = x.shape[0]
    design = np.vstack([x, x])
    rpm = np.repeat([300.0, 600.0], rows)
    metric = np.where(rpm == 300.0, ishigami(design), 3.0 * design[:, 2] + 0.1 * design[:, 0])
    names = ["clearance", "rpm_x", "damping"]
    path = flat_study(
        tmp_path / "repeated.h5",
        {**{name: design[:, j] for j, name in enumerate(names)}, "rpm": rpm},
        {"m": metric},
        axes=("rpm",),
        attrs={"design_method": "saltelli", "design_parameters": ",".join(names), "design_rows": np.int64(rows)},
    )
    results = analyse(path, ["m"], resamples=100, seed=1, outdir=tmp_path / "fig")["m"]
    assert [r.point for r in results] == [{"rpm": 300.0}, {"rpm": 600.0}]
    for indices, half in zip(results, (slice(0, rows), slice(rows, 2 * rows))):
        direct = saltelli_indices(problem, design[half], metric[half], resamples=100, seed=1)
        np.testing.assert_array_equal(indices.first, direct.first)
    assert results[1].first[2] > 0.95 and results[0].first[2] < 0.05
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == ["sensitivity_m_0.png", "sensitivity_m_1.png"]
    out = subprocess.run([sys.executable, str(SCRIPT), str(path), "--metric", "m", "--resamples", "100"],
                         capture_output=True, text=True, check=True).stdout
    assert "m at rpm = 300: Saltelli design" in out and "m at rpm = 600: Saltelli design" in out
    with open_study(path) as ds:
        with pytest.raises(ValueError, match="repeated at 2 grid points"):
            study_saltelli(ds, "m")


def test_plot_of_exact_indices(tmp_path, assert_png):
    g = grid(x=[0.0, 1.0, 3.0], y=[-2.0, 0.5, 1.0])
    out = plot_indices(grid_indices(g["x"] * g["y"]), "m", tmp_path / "m.png")
    assert_png(out, min_kb=10)


def test_smoke_study_grid_matches_groupby(smoke_path, tmp_path, assert_png):
    """The exact indices of a real study file equal those computed from its flat cases with
    pandas (each case's axis values, not the unstacked grid)."""
    metric = "slider_acceleration_rms_deviation"
    with open_study(smoke_path) as ds:
        result = study_grid(ds, metric)
        axes = [a for a in str(ds.attrs["grid_axes"]).split(",") if len(np.unique(ds[a].values)) > 1]
        df = ds[axes + [metric]].to_dataframe().reset_index(drop=True)
    assert result.names == axes
    assert len(df) == np.prod([df[a].nunique() for a in axes])  # a full grid
    total_var = df[metric].var(ddof=0)
    first = [df.groupby(a)[metric].mean().var(ddof=0) / total_var for a in axes]
    others = [[b for b in axes if b != a] for a in axes]
    total = [df.groupby(o)[metric].var(ddof=0).mean() / total_var for o in others]
    np.testing.assert_allclose(result.first, first, rtol=1e-9)
    np.testing.assert_allclose(result.total, total, rtol=1e-9)
    assert result.first.sum() <= 1 + 1e-12 and np.all(result.first <= result.total + 1e-12)
    out = subprocess.run(
        [sys.executable, str(SCRIPT), smoke_path, "--metric", metric,
         "--out", str(tmp_path)],
        capture_output=True, text=True, check=True,
    ).stdout
    assert "exact, full grid" in out and f"{result.first[0]:.4f}" in out
    assert_png(tmp_path / f"sensitivity_{metric}.png", min_kb=10)
    refused = subprocess.run(
        [sys.executable, str(SCRIPT), smoke_path, "--metric", "bearing_force_rms_deviation"],
        capture_output=True, text=True,
    )
    assert refused.returncode != 0 and "NaN in" in refused.stderr  # the ideal cases have no bearing force
