"""A recordings study (docs/grid-file.md, Recordings) read by the loader, its shards
combined, and windowed together with a simulated study, labels aligned. Needs
STUDYRUN_BIN (the studyrun binary); skipped without it."""

import os
import subprocess

import numpy as np
import pytest

from analysis.dataset import make_joint_splits
from analysis.studyfile import open_shards, open_study
from analysis.tests.conftest import REPO

SIMULATED = """name: sim
duration: 0.25
sample_rate: 12000
transient: 0.05
effects: [clearance, damping, defects]
rpm: 1800
envelope: {channels: [bearing_force_y], band: auto}
bearing: {defects: [{race: outer, angle: "0 deg", width: "1 mm", depth: "20 um", profile: flat}]}
grid: {defect_race: [outer, inner]}
cases: [{defect_depth: 0}]
"""


@pytest.fixture(scope="module")
def studies(tmp_path_factory):
    """The example recordings study, two shards of it, and a small simulated study at
    the same 12 kHz, run with STUDYRUN_BIN: their paths."""
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("STUDYRUN_BIN is not set")
    binary = os.path.abspath(binary)  # the studies run in their own folder
    folder = tmp_path_factory.mktemp("recordings")
    grid = str(REPO / "studies/recordings.yaml")
    run = lambda *args: subprocess.run([binary, *args, "-q"], check=True, cwd=folder)  # noqa: E731
    run(grid, "-o", "rec.h5")
    for k in (1, 2):
        run("run", grid, "--shard", f"{k}/2", "-o", f"rec{k}.h5")
    (folder / "sim.yaml").write_text(SIMULATED)
    run("sim.yaml", "-o", "sim.h5", "-j", "2")
    return folder


def test_loader_and_shards_read_a_recordings_file(studies):
    with open_study(studies / "rec.h5") as ds:
        whole = ds.load()
    assert list(whole["fault"].values) == ["outer", "inner", "none"]
    assert whole.sizes["reference"] == 0 and "reference_index" not in whole
    assert whole.sizes["time"] == 6000
    assert list(whole["recording_samples"].values) == [6000, 7200, 6600]
    energy = np.stack([whole[f"vibration_envelope_energy_{k}"].values for k in ("bpfo", "bpfi", "2bsf")])
    assert list(energy[:, :2].argmax(axis=0)) == [0, 1]
    combined = open_shards([studies / "rec2.h5", studies / "rec1.h5"]).load()
    np.testing.assert_array_equal(combined["vibration"].values, whole["vibration"].values)
    np.testing.assert_array_equal(combined["vibration_envelope_spectrum"].values,
                                  whole["vibration_envelope_spectrum"].values)


def test_a_simulated_and_a_measured_study_window_together(studies):
    with open_study(studies / "sim.h5") as sim, open_study(studies / "rec.h5") as rec:
        sim, rec = sim.load(), rec.load()
    splits = make_joint_splits([("simulated", sim, "bearing_force_y"), ("measured", rec, "vibration")],
                               length=512, hop=256, labels=("fault",), fractions=(0.34, 0.33, 0.33))
    every = {n: np.concatenate([splits[s].labels[n] for s in splits]) for n in ("fault", "study")}
    assert set(every["study"]) == {"simulated", "measured"}
    assert set(every["fault"][every["study"] == "measured"]) == {"outer", "inner", "none"}
    assert set(every["fault"][every["study"] == "simulated"]) == {"outer", "inner", "none"}
    for w in splits.values():
        assert w.x.shape[1:] == (1, 512) and w.channels == ["bearing_force_y|vibration"]
        # One class list for both studies: a code names the same fault in each.
        assert list(w.classes["fault"]) == ["inner", "none", "outer"]
        np.testing.assert_array_equal(w.classes["fault"][w.codes["fault"]], w.labels["fault"])
    # A measured window is the recording's samples, unchanged but for float32.
    measured = [(w, k) for w in splits.values() for k in np.flatnonzero(w.labels["study"] == "measured")][0]
    w, k = measured
    row = int(np.flatnonzero(rec["case"].values == w.case[k])[0])
    np.testing.assert_array_equal(w.x[k, 0], rec["vibration"].values[row, w.start[k]:w.start[k] + 512]
                                  .astype(np.float32))
    with pytest.raises(ValueError, match="different rates"):
        make_joint_splits([("a", sim, "bearing_force_y"), ("b", rec.assign_attrs(series_sample_rate=6000.0),
                                                           "vibration")], length=512, hop=256)


def test_report_draws_a_recordings_study_beside_a_simulated_one(studies, tmp_path, assert_png):
    """report.py draws the recordings' envelope spectra with the fault lines and their
    kurtograms with the chosen band, and, given the simulated study, one figure per
    shared fault with a measured and a simulated case side by side."""
    from analysis import report

    out = tmp_path / "report"
    index = report.report(studies / "rec.h5", out, simulated=studies / "sim.h5").read_text(encoding="utf-8")
    names = sorted(p.name for p in out.glob("*.png"))
    assert "envelope_vibration_1800rpm.png" in names, names
    assert [n for n in names if n.startswith("kurtogram_vibration")] == [
        f"kurtogram_vibration_1800rpm_{label}.png" for label in ("inner", "none", "outer")]
    assert [n for n in names if n.startswith("measured_simulated")] == [
        f"measured_simulated_{label}.png" for label in ("inner", "none", "outer")]
    for name in names:
        assert f"({name})" in index
        assert_png(out / name, min_kb=10, min_pixels=150)
