"""The study file passes IOOS compliance-checker's CF-1.8 suite (`compliance-checker
--test cf:1.8`) with no failure of high or medium priority (the command line's "Errors"
and "Warnings"), through the API and through the command line users run.

The file is checked through a link named `*.nc` (the checker wants that suffix, §2.1).

Environment: STUDYRUN_SMOKE_FILE (the result of `studyrun studies/smoke.yaml`) and,
optional, STUDYRUN_MERGED_FILE (`studyrun merge` of its shards) and
STUDYRUN_ACCURACY_FILE (`studyrun accuracy studies/accuracy_smoke.yaml`); unset: skip.
"""

import os
import shutil
import subprocess
import sys

import h5py
import numpy as np
import pytest

from cf_quantities import units_attribute

FILES = ("STUDYRUN_SMOKE_FILE", "STUDYRUN_MERGED_FILE", "STUDYRUN_ACCURACY_FILE")

# CF-1.8 §2.2 numeric types (compliance-checker's cf:1.8 list): no 64-bit or unsigned integers.
CF18_INTEGERS = (np.int8, np.int16, np.int32)
IDS = ("case", "reference", "reference_index")


@pytest.fixture(scope="module", params=FILES)
def path(request):
    value = os.environ.get(request.param)
    if not value:
        pytest.skip(f"{request.param} is not set")
    assert os.path.isfile(value), f"{request.param}={value} does not exist"
    return os.path.abspath(value)


def failed(result):
    value = result.value
    if isinstance(value, tuple):
        return value[0] < value[1]
    return not value


@pytest.mark.filterwarnings("ignore::DeprecationWarning")  # the checker's own ioos_sos plugin
def test_cf18_compliance(path, tmp_path):
    runner = pytest.importorskip("compliance_checker.runner")
    from compliance_checker.base import BaseCheck

    link = tmp_path / "study.nc"
    link.symlink_to(path)
    suite = runner.CheckSuite()
    suite.load_all_available_checkers()
    dataset = suite.load_dataset(str(link))
    results, exceptions = suite.run_all(dataset, ["cf:1.8"], skip_checks=[])["cf:1.8"]
    assert not exceptions, f"checks that crashed: {exceptions}"
    problems = []
    for r in results:
        if r.weight < BaseCheck.MEDIUM or not failed(r):
            continue
        level = "error" if r.weight >= BaseCheck.HIGH else "warning"
        problems.append(f"{level} {r.name}: {r.msgs}")
    assert not problems, "\n".join(problems)


def test_the_command_line_checker_passes(path, tmp_path):
    """`compliance-checker --test cf:1.8 FILE` as a user runs it: exit 0, nothing to fix."""
    checker = shutil.which("compliance-checker", path=os.path.dirname(sys.executable))
    checker = checker or shutil.which("compliance-checker")
    if checker is None:
        pytest.skip("compliance-checker is not installed")
    link = tmp_path / "study.nc"
    link.symlink_to(path)
    result = subprocess.run(
        [checker, "--test", "cf:1.8", "--criteria", "strict", str(link)],
        capture_output=True, text=True, timeout=600,
    )
    assert result.returncode == 0 and "All tests passed!" in result.stdout, (
        result.stdout + result.stderr
    )


def test_ids_are_cf18_signed_integers(path):
    with h5py.File(path, "r") as f:
        for name in IDS:
            assert f[name].dtype.type in CF18_INTEGERS, (name, f[name].dtype)
        case = f["case"][:]
        assert len(np.unique(case)) == len(case) and (case >= 0).all()
        assert (f["reference_index"][:] < f["reference"].shape[0]).all()


def test_history_records_the_run(path):
    """CF §2.6.2 `history`: one line per program that made or changed the file."""
    with h5py.File(path, "r") as f:
        assert "history" in f.attrs, "no history attribute"
        history = units_attribute(f.attrs["history"])
    lines = [line for line in history.splitlines() if line.strip()]
    assert lines, "history is empty"
    assert any("studyrun" in line for line in lines), history
    merged = os.environ.get("STUDYRUN_MERGED_FILE")
    if merged and os.path.abspath(merged) == path:
        assert any("studyrun merge" in line for line in lines), history
