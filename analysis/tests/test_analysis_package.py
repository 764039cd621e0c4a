"""`analysis` as a package: pyproject.toml installs it with its console scripts
(studyrun-report, -sensitivity, -significance, -features) that run outside the
repository, and every script also runs as `python analysis/<name>.py`; the feature table
(analysis/features.py) has one row per case with every per-case value, to CSV and
Parquet alike."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from analysis import features
from analysis.studyfile import text

REPO = Path(__file__).resolve().parents[2]
SCRIPTS = ["report", "sensitivity", "significance", "features", "faults", "work_precision"]
CONSOLE = {"studyrun-report": "report", "studyrun-sensitivity": "sensitivity",
           "studyrun-significance": "significance", "studyrun-features": "features"}


@pytest.mark.parametrize("name", SCRIPTS)
def test_each_script_runs_by_its_path_from_anywhere(name, tmp_path):
    done = subprocess.run([sys.executable, str(REPO / "analysis" / f"{name}.py"), "--help"],
                          cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage:")


@pytest.mark.parametrize("script", sorted(CONSOLE))
def test_console_scripts_run_outside_the_repository(installed, script, tmp_path):
    site, bin_dir = installed
    assert (bin_dir / script).is_file()
    entry = (bin_dir / script).read_text()
    assert f"from analysis.{CONSOLE[script]} import main" in entry
    env = {"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"}
    done = subprocess.run([sys.executable, str(bin_dir / script), "--help"], cwd=tmp_path, env=env,
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("usage:")
    where = subprocess.run([sys.executable, "-c", "import analysis.studyfile as s; print(s.__file__)"],
                           cwd=tmp_path, env=env, capture_output=True, text=True, check=True).stdout
    assert where.startswith(str(site))


def test_feature_table_has_a_row_per_case_and_every_per_case_value(diagnosis_path, tmp_path):
    """The diagnosis study: 12 rows in case-id order, every [case] variable (fault labels,
    parameters, indicators of both envelope channels, metrics) equal to the file's; the
    CSV and the Parquet read back to the same table, the Parquet with the units."""
    csv, parquet = tmp_path / "f.csv", tmp_path / "t" / "f.parquet"
    done = subprocess.run([sys.executable, str(REPO / "analysis" / "features.py"), diagnosis_path, str(csv),
                           str(parquet)], cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    from analysis.studyfile import open_study

    with open_study(diagnosis_path) as ds:
        ds = ds.load()
        frame = features.table(ds)
        names = [str(n) for n in ds.data_vars if ds[n].dims == ("case",)]
    assert list(frame.columns) == ["case"] + names
    assert frame["case"].tolist() == sorted(ds["case"].values.tolist()) == list(range(12))
    for name in ("fault", "location", "defect_race", "speed_profile"):
        assert frame[name].tolist() == [text(v) for v in ds[name].values]
    for name in ("accelerometer_kurtosis", "bearing_force_envelope_energy_bpfo", "bearing_force_rms_deviation",
                 "rpm", "defect_width"):
        np.testing.assert_array_equal(frame[name].to_numpy(), ds[name].values)
    from_parquet = pd.read_parquet(parquet)
    pd.testing.assert_frame_equal(from_parquet, frame)
    assert from_parquet.attrs["units"]["accelerometer_rms"] == "m s-2"
    from_csv = pd.read_csv(csv, keep_default_na=False, na_values=["NaN"])
    pd.testing.assert_frame_equal(from_csv, frame, check_dtype=False, rtol=1e-15)
    assert done.stdout.strip().endswith(f"12 cases, {len(names) + 1} columns")


def test_feature_table_refuses_another_format(tmp_path, diagnosis_path):
    done = subprocess.run([sys.executable, str(REPO / "analysis" / "features.py"), diagnosis_path,
                           str(tmp_path / "f.xlsx")], capture_output=True, text=True)
    assert done.returncode == 1 and "f.xlsx: not a .csv or .parquet file name" in done.stderr
    with pytest.raises(ValueError, match=r"suffix .txt is not a table format; use one of .csv, .parquet"):
        features.write(pd.DataFrame({"a": [1]}), tmp_path / "x.txt")
