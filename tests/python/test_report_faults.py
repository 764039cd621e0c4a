"""report.py on a small fault study shaped like studies/faults.yaml: defects on two races
and two widths, each speed a ramp profile (600 → 600 rpm, which runs as a constant
600 rpm, and a 300 → 900 rpm run-up, zipped), and the healthy bearing as explicit
`cases:` with `defect_depth: 0` at both speeds.

- The healthy cases are stored and shown as healthy: `defect_race` none, no defect width
  of their own (NaN), beside the defects of every width in the metrics views and in
  every diagnosis condition they share.
- The 600 → 600 rpm cases are constant-speed cases: the report draws their panels and
  spectra, at 600 rpm; `analysis.faults` reads them at 600 rpm too, through the one
  helper `studyfile.constant_rpm`.

Environment: STUDYRUN_BIN (the binary runs the study written here); else skip.
"""

import re
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis import diagnosis, faults, report  # noqa: E402
from analysis import studyfile  # noqa: E402
from analysis.studyfile import open_study, unstack  # noqa: E402
from study_run import run_grid  # noqa: E402

GRID = """name: minifaults
description: two races x two widths x a constant 600 rpm and a run-up, and the healthy bearing
duration: 0.3
sample_rate: 10000
transient: "0.1 s"
effects: [clearance, damping, defects]
speed: {profile: ramp, from: "600 rpm", to: "600 rpm", over: "0.3 s"}
bearing:
  clearance: "40 um"
  damping: 300
  defects: [{race: outer, angle: "0 deg", width: "1 mm", depth: "20 um", profile: flat}]
grid:
  location: [crank_ground]
  defect_race: [outer, inner]
  defect_width: ["0.5 mm", "2 mm"]
zip:
  - speed_from: ["600 rpm", "300 rpm"]
    speed_to: ["600 rpm", "900 rpm"]
cases:
  - {defect_depth: 0}
  - {defect_depth: 0, speed_from: "300 rpm", speed_to: "900 rpm"}
"""


DEPTHS = """name: depths
duration: 0.15
sample_rate: 5000
transient: "0.05 s"
rpm: 600
effects: [clearance, damping, defects]
bearing:
  clearance: "10 um"
  damping: 300
  defects: [{race: outer, angle: "0 deg", width: "1 mm", depth: "20 um", profile: flat}]
grid:
  defect_depth: ["0 um", "20 um"]
  defect_race: [outer, inner]
  defect_width: ["0.5 mm", "2 mm"]
"""


@pytest.fixture(scope="module")
def path(tmp_path_factory):
    return run_grid(tmp_path_factory.mktemp("faults"), "minifaults", GRID)


@pytest.fixture(scope="module")
def ds(path):
    with open_study(path) as d:
        yield d.load()


@pytest.fixture(scope="module")
def rendered(path, tmp_path_factory):
    outdir = tmp_path_factory.mktemp("report")
    report.report(path, outdir, channels=["bearing_force"], dpi=40)
    return outdir, (outdir / "index.md").read_text(encoding="utf-8")


def healthy_positions(ds):
    return [k for k in range(ds.sizes["case"]) if str(ds["fault"].values[k]) == "none"]


def test_the_file_stores_its_healthy_cases_without_defect_parameters(ds):
    """The healthy cases (`defect_depth: 0` over an outer defect 1 mm wide) are stored with
    race none and NaN angle, width and depth, as their fault label says; the 600 → 600 rpm
    ramps, which run as a constant speed, store their rpm, the run-ups NaN."""
    healthy = healthy_positions(ds)
    assert len(healthy) == 2 and ds.sizes["case"] == 10
    assert {str(ds["defect_race"].values[k]) for k in healthy} == {"none"}
    for name in ("defect_angle", "defect_width", "defect_depth"):
        assert np.all(np.isnan(ds[name].values[healthy])), name
    sick = [k for k in range(ds.sizes["case"]) if k not in healthy]
    assert np.all(np.isfinite(ds["defect_width"].values[sick]))
    constant = ds["speed_to"].values == ds["speed_from"].values
    np.testing.assert_array_equal(ds["rpm"].values[constant], ds["speed_from"].values[constant])
    assert np.all(np.isnan(ds["rpm"].values[~constant])) and set(ds["speed_profile"].values) == {"ramp"}


def test_the_metrics_grid_shows_the_healthy_bearing_in_the_none_row_of_every_width(ds):
    marked = report.mark_healthy(ds)
    view, repeated = report.healthy_beside_defects(marked)
    grid = unstack(view)
    assert repeated == 0
    assert sorted(grid["defect_width"].values.tolist()) == [0.0005, 0.002]  # no 1 mm facet
    assert sorted(grid["defect_race"].values.tolist()) == ["inner", "none", "outer"]
    metric = grid["bearing_force_rms_deviation"]
    for k in healthy_positions(ds):
        speed = {"speed_from": float(ds["speed_from"].values[k]), "speed_to": float(ds["speed_to"].values[k])}
        for width in (0.0005, 0.002):
            cell = metric.sel(location="crank_ground", defect_race="none", defect_width=width, **speed)
            assert float(cell) == float(ds["bearing_force_rms_deviation"].values[k])
    # The defects' cells are their own cases' values.
    k = next(k for k in range(ds.sizes["case"]) if str(ds["fault"].values[k]) == "inner"
             and ds["defect_width"].values[k] == 0.002 and ds["speed_to"].values[k] == 600)
    cell = metric.sel(location="crank_ground", defect_race="inner", defect_width=0.002,
                      speed_from=600.0, speed_to=600.0)
    assert float(cell) == float(ds["bearing_force_rms_deviation"].values[k])


def test_healthy_cases_are_marked_not_applicable(ds):
    marked = report.mark_healthy(ds)
    for k in range(ds.sizes["case"]):
        if k in healthy_positions(ds):
            assert str(marked["defect_race"].values[k]) == "none"
            assert np.isnan(marked["defect_width"].values[k]) and np.isnan(marked["defect_angle"].values[k])
        else:
            assert str(marked["defect_race"].values[k]) == str(ds["defect_race"].values[k]) != "none"
            assert marked["defect_width"].values[k] == ds["defect_width"].values[k]


def test_every_diagnosis_condition_has_the_healthy_bearing(ds):
    prepared = report.with_constant_rpm(report.mark_healthy(ds))
    groups, dropped = report.conditions(prepared, report.bearing_cases(prepared))
    assert dropped == 0
    assert len(groups) == 4, list(groups)  # 2 widths x (600 rpm, run-up)
    healthy = {float(ds["speed_to"].values[k]): k for k in healthy_positions(ds)}
    for name, group in groups.items():
        assert "1 mm" not in name and "n/a" not in name, name
        assert sorted(group) == ["inner", "none", "outer"], name
        speed_to = float(ds["speed_to"].values[group["outer"]])
        assert group["none"] == healthy[speed_to], name


def test_one_speed_ramps_are_constant_speed_cases_everywhere(ds):
    assert report.constant_rpm is studyfile.constant_rpm is diagnosis.constant_rpm is faults.constant_rpm
    prepared = report.with_constant_rpm(ds)
    one_speed = ds["speed_from"].values == ds["speed_to"].values
    assert one_speed.sum() == 5
    np.testing.assert_array_equal(prepared["rpm"].values[one_speed], 600.0)
    assert np.all(np.isnan(prepared["rpm"].values[~one_speed]))
    assert prepared["rpm"].attrs["units"] == ds["rpm"].attrs["units"]


def test_faults_reads_the_one_speed_ramps_at_their_speed(path):
    _, cases = faults.read(path)
    assert len(cases) == 5 and {c["rpm"] for c in cases} == {600.0}
    assert sorted(c["fault"] for c in cases) == ["inner", "inner", "none", "outer", "outer"]


def test_the_report_draws_panels_and_spectra_of_the_constant_speed_cases(rendered):
    outdir, index = rendered
    series = index.split("## Time series")[1].split("## Diagnosis")[0]
    panels = re.findall(r"\((panels_[^)]+\.png)\)", series)
    spectra = re.findall(r"\((spectrum_[^)]+\.png)\)", series)
    assert len(panels) == 5 and len(spectra) == 5, series
    assert all("600rpm" in name for name in panels + spectra)
    assert sum("_none_" in name for name in panels) == 1  # the healthy bearing's
    assert "5 combinations run a `speed:` profile whose speed varies" in series
    for name in panels + spectra:
        assert (outdir / name).stat().st_size > 5000


def test_the_report_never_shows_the_healthy_cases_as_a_1_mm_defect(rendered):
    outdir, index = rendered
    metrics = index.split("## Vibration metrics")[1].split("## Time series")[0]
    assert len(re.findall(r"\((metrics_[^)]+\.png)\)", metrics)) == 6
    assert "defect_race none: the bearing without a defect, shown at every defect_width." in metrics
    assert "1 mm" not in index and "defect_width1mm" not in index
    assert "defect_race none, defect_width n/a" in index  # the healthy bearing's panels


def test_a_depth_axis_with_zero_shows_its_healthy_cases_once(tmp_path):
    """`defect_depth: [0, 20 um]` as an axis: the four zero-depth cases are one healthy
    bearing, shown once in the `none` row (not four times as outer/inner defects)."""
    path = run_grid(tmp_path, "depths", DEPTHS)
    with open_study(path) as ds:
        view, repeated = report.healthy_beside_defects(report.mark_healthy(ds.load()))
        assert repeated == 3
        grid = unstack(view)
        assert sorted(grid["defect_race"].values.tolist()) == ["inner", "none", "outer"]
        assert grid["defect_depth"].values.tolist() == [2e-5]
        first_healthy = int(np.flatnonzero(ds["fault"].values == "none")[0])
        cells = grid["crank_moment_rms_deviation"].sel(defect_race="none").values
        np.testing.assert_array_equal(cells.ravel(), ds["crank_moment_rms_deviation"].values[first_healthy])
    outdir = tmp_path / "report"
    index = report.report(path, outdir, channels=["crank_moment"], dpi=40).read_text(encoding="utf-8")
    assert "not shown" not in index
    assert index.count("3 cases without a defect repeat another's") == 2  # the metrics and the panels
    series = index.split("## Time series")[1].split("## Diagnosis")[0]
    panels = re.findall(r"\((panels_[^)]+\.png)\)", series)
    assert len(panels) == 5 and sum("_none_" in name for name in panels) == 1, panels
