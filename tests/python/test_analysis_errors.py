"""Wrong inputs to the analysis scripts end in one clear line, never a traceback: a
missing or non-HDF5 file, a file of the wrong kind (no bearing cases with a defect, not
an accuracy file, replicates off the paper's grid), a `--select` that matches nothing or
gives a unit, and the ideal-mechanism series a file does not store.

Environment: STUDYRUN_BIN runs the small studies written here; the tests that need
one skip without it.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis import report  # noqa: E402
from analysis.studyfile import (  # noqa: E402
    StudyFileError,
    check_study_file,
    open_study,
    reference_for,
    select_cases,
    study_file_or_exit,
)
from study_run import run_grid  # noqa: E402

SCRIPTS = {
    "report": ["analysis/report.py", "{file}", "{out}"],
    "sensitivity": ["analysis/sensitivity.py", "{file}", "--metric", "slider_acceleration_rms_deviation"],
    "faults": ["-m", "analysis.faults", "{file}"],
    "work_precision": ["analysis/work_precision.py", "{file}", "{out}/wp.png"],
    "significance": ["analysis/significance.py", "{file}"],
}

SMALL = """name: small
duration: 0.05
sample_rate: 10000
transient: "0.01 s"
{extra}grid:
  location: [ideal, crank_ground, crank_rod]
  waviness_amplitude: ["0 um", "4 um"]
"""

REPLICATES = """name: rep
duration: 0.05
sample_rate: 10000
transient: "0.01 s"
replicates: {count: 3, perturbation: "1 nm", seed: 3}
grid:
  location: [crank_ground, crank_rod]
  ball_count: [8, 9]
"""


def run(script, file, out):
    """Runs `script` of SCRIPTS from the repository root; returns the finished process."""
    args = [a.format(file=file, out=out) for a in SCRIPTS[script]]
    return subprocess.run([sys.executable, *args], cwd=REPO, capture_output=True, text=True, timeout=300)


def assert_one_line_error(done, *fragments):
    """A non-zero exit whose stderr is one line holding every fragment, and no traceback."""
    assert done.returncode != 0, done.stdout
    lines = done.stderr.strip().splitlines()
    assert "Traceback" not in done.stderr and len(lines) == 1, done.stderr
    for fragment in fragments:
        assert fragment in lines[0], (fragment, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    return run_grid(tmp_path_factory.mktemp("small"), "small", SMALL.format(extra=""))


@pytest.fixture(scope="module")
def some_series(tmp_path_factory):
    """The same study storing the bearing force and slider acceleration series only."""
    extra = "output: {series: [slider_acceleration, bearing_force]}\n"
    return run_grid(tmp_path_factory.mktemp("some"), "some", SMALL.format(extra=extra))


@pytest.fixture(scope="module")
def replicates(tmp_path_factory):
    return run_grid(tmp_path_factory.mktemp("rep"), "rep", REPLICATES)


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_a_missing_file(script, tmp_path):
    missing = tmp_path / "missing.h5"
    assert_one_line_error(run(script, missing, tmp_path), f"{script}: ", str(missing), "no such file")


@pytest.mark.parametrize("script", sorted(SCRIPTS))
def test_a_file_that_is_not_hdf5(script, tmp_path):
    text = tmp_path / "notes.h5"
    text.write_text("not a study\n")
    assert_one_line_error(run(script, text, tmp_path), f"{script}: ", str(text), "not an HDF5 file")


def test_the_shared_check(tmp_path, small):
    with pytest.raises(StudyFileError, match="no such file"):
        open_study(tmp_path / "none.h5")
    with pytest.raises(StudyFileError, match=r"is a directory|not a file"):
        check_study_file(tmp_path)
    with pytest.raises(StudyFileError, match=r"no method, horizon: not an accuracy file"):
        check_study_file(small, needs=("method", "case", "horizon"), kind="an accuracy file")
    assert study_file_or_exit("x", small) == small
    with pytest.raises(SystemExit, match=r"^x: .*none\.h5: no such file"):
        study_file_or_exit("x", tmp_path / "none.h5")


def test_faults_on_a_study_without_defects_says_so(small, tmp_path):
    """The study has `ideal` cases (no bearing, no pass frequency) and no defect."""
    line = assert_one_line_error(run("faults", small, tmp_path), "faults: ", str(small))
    assert "no successful constant-speed bearing case with a defect" in line


def test_work_precision_on_a_study_file_says_it_is_not_an_accuracy_file(small, tmp_path):
    assert_one_line_error(run("work_precision", small, tmp_path), "work_precision: ", "not an accuracy file",
                          "horizon")


def test_significance_needs_replicates_on_the_papers_grid(small, replicates, tmp_path):
    assert_one_line_error(run("significance", small, tmp_path), "significance: ", "no replicate")
    line = assert_one_line_error(run("significance", replicates, tmp_path), "significance: ",
                                 "not on the paper's grid")
    assert "10 balls" in line  # the grid has 8 and 9 balls only


def test_select_that_matches_nothing_lists_the_values(small, tmp_path):
    done = subprocess.run([sys.executable, "analysis/report.py", str(small), str(tmp_path), "--select", "rpm=301"],
                          cwd=REPO, capture_output=True, text=True)
    assert_one_line_error(done, "report: ", "--select rpm=301", "no case has rpm 301", "the file has 300")
    with open_study(small) as ds:
        with pytest.raises(ValueError,
                           match="no case has location nowhere; the file has crank_ground, crank_rod, ideal"):
            report.restrict(ds, ["location=nowhere"])
        # Each alone matches cases (a NaN metric: the ideal cases'), together none.
        with pytest.raises(ValueError, match="no case matches them all"):
            report.restrict(ds, ["location=crank_rod", "bearing_force_rms_deviation=nan"])


def test_select_with_a_unit_is_refused_clearly(small, tmp_path):
    done = subprocess.run([sys.executable, "analysis/report.py", str(small), str(tmp_path),
                           "--select", "waviness_amplitude=4 um"], cwd=REPO, capture_output=True, text=True)
    assert_one_line_error(done, "report: ", "waviness_amplitude takes a plain number in the file's unit m",
                          "0, 4e-06")
    with open_study(small) as ds:
        with pytest.raises(ValueError, match=r"waviness_amplitude is a number in the file's unit \(m\)"):
            select_cases(ds, waviness_amplitude="4 um")
        assert select_cases(ds, waviness_amplitude=4e-6).size == 3
        restricted = report.restrict(ds, ["waviness_amplitude=4e-6", "location=crank_rod"])
        assert restricted.sizes["case"] == 1


def test_reference_for_names_the_series_a_file_does_not_store(some_series):
    with open_study(some_series) as ds:
        with pytest.raises(ValueError) as refused:
            reference_for(ds)
        message = str(refused.value)
        assert "reference_crank_ground_force_x" in message and "`output.series`" in message
        assert "\n" not in message
        # What it stores is there.
        ideal = reference_for(ds, ["slider_acceleration"])["slider_acceleration"].values
        assert ideal.shape == (ds.sizes["case"], ds.sizes["time"]) and np.isfinite(ideal).all()


def test_report_on_a_file_with_some_series_notes_what_it_cannot_draw(some_series, tmp_path):
    """The bearing force's ideal counterpart needs the joint forces: noted, not a crash."""
    path = report.report(some_series, tmp_path, channels=["bearing_force"], dpi=40)
    index = path.read_text(encoding="utf-8")
    assert "not shown (the file does not store the ideal mechanism's reference_crank_ground_force_x" in index
