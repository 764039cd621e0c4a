"""docs/faults.md agrees with a run of studies/faults.yaml: its table is what
`python -m analysis.faults` prints, row for row, and the numbers its text quotes from
the table and the file are there.

The study runs as written but with `output: {series: none}`: the spectra, metrics and
counts are computed from the full-rate series whatever `output:` stores
(docs/result-file.md), and the file stays small.

Environment: STUDYRUN_BIN (the binary runs the study); else skip.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis import faults  # noqa: E402
from analysis.studyfile import open_study  # noqa: E402
from study_run import run_grid  # noqa: E402

DOC = REPO / "docs" / "faults.md"


@pytest.fixture(scope="module")
def path(tmp_path_factory):
    grid = (REPO / "studies" / "faults.yaml").read_text() + "output: {series: none}\n"
    return run_grid(tmp_path_factory.mktemp("faults"), "faults", grid)


def doc_table():
    lines = DOC.read_text(encoding="utf-8").splitlines()
    start = lines.index(next(line for line in lines if line.startswith("| location | fault | width (mm)")))
    table = []
    for line in lines[start:]:
        if not line.startswith("|"):
            break
        table.append(line)
    return table


def test_the_table_is_what_analysis_faults_prints(path):
    freq, cases = faults.read(path)
    assert len(cases) == 14  # the constant-speed cases: 12 defects and 2 healthy bearings
    printed = faults.table(freq, cases).splitlines()
    assert len(printed) == 14
    assert doc_table() == printed


def test_the_text_quotes_the_table_and_the_file(path):
    text = " ".join(DOC.read_text(encoding="utf-8").split())  # one space for every line break
    freq, cases = faults.read(path)
    rows = {(r.split("|")[1].strip(), r.split("|")[2].strip(), r.split("|")[3].strip()): r.split("|")
            for r in doc_table()[2:]}
    inner = rows[("crank_ground", "inner", "2.0")][5].split(",")[0].strip()
    assert f"{inner} N at 1× for the 2 mm defect" in text
    with open_study(path) as ds:
        one_speed = ds["speed_from"].values == ds["speed_to"].values
        defect = one_speed & (ds["fault"].values != "none")
        healthy = one_speed & (ds["fault"].values == "none")
        peak = ds["max_bearing_force"].values
        rms = ds["bearing_force_rms_deviation"].values
        assert f"to {round(peak[defect].min(), -1):.0f}–{round(peak[defect].max(), -1):.0f} N" in text
        assert (f"from {rms[healthy].min():.1f}–{rms[healthy].max():.1f} N to "
                f"{rms[defect].min():.0f}–{rms[defect].max():.0f} N") in text
        for loc, value in zip(ds["location"].values[healthy], peak[healthy]):
            assert f"{value:.0f} N ({loc})" in text
    ftf = faults.pass_frequency("outer", "crank_ground", 600, 9, cases[0]["d_i"], cases[0]["d_o"]) / 9
    assert f"FTF = {ftf:.2f} Hz at crank_ground" in text
    assert "BPFO = 34.67 Hz, inner race BPFI = 55.33 Hz, ball 2 BSF = 41.27 Hz" in text
    assert np.isclose(freq[1] - freq[0], 1.0)  # "the bins are 1 Hz apart"
