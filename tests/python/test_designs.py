"""Sampled designs against SciPy: the unscrambled Sobol points studyrun draws are
the Sobol sequence SciPy's `qmc.Sobol(d, scramble=False)` gives (Joe & Kuo's
direction numbers, Gray-code order from 0), in all 32 dimensions a Saltelli design
over 16 parameters uses, and the Saltelli rows follow SALib's layout.

Environment (unset: skip): STUDYRUN_BIN, the studyrun binary. The design is read
from `--dry-run`, which lists every case's values without running them.
"""

import os
import subprocess

import numpy as np
import pytest
from scipy.stats import qmc

from study_run import studyrun_binary

# Parameter: (min, max) in base units; the ideal mechanism ignores the bearing's,
# so the design is listed without simulating anything of note.
RANGES = {
    "rpm": (300.0, 1324.0),
    "clearance": (0.0, 64e-6),
    "stiffness": (1e9, 2e10),
    "damping": (0.0, 1024.0),
    "inner_waviness_amplitude": (0.0, 4e-6),
    "inner_waviness_phase": (0.0, 3.0),
    "outer_waviness_amplitude": (0.0, 4e-6),
    "outer_waviness_phase": (0.0, 3.0),
    "crank_mass": (0.25, 0.5),
    "crank_inertia": (1e-4, 2e-4),
    "rod_mass": (0.125, 0.25),
    "rod_inertia": (2e-4, 3e-4),
    "slider_mass": (0.125, 0.25),
    "slider_inertia": (1e-4, 2e-4),
    "crank_length": (0.04, 0.05),
    "rod_length": (0.12, 0.13),
}


@pytest.fixture(scope="module")
def studyrun():
    return studyrun_binary()


def unit_design(studyrun, tmp_path, method, samples):
    """The design's points mapped back to the unit cube, one row per case."""
    lines = [
        "name: designs",
        "duration: 0.01",
        "sample_rate: 1000",
        "location: ideal",
        "effects: [clearance, waviness, damping]",
        "design:",
        f"  method: {method}",
        f"  samples: {samples}",
        "  scramble: false",
        "  parameters:",
    ] + [f"    {p}: {{min: {lo!r}, max: {hi!r}}}" for p, (lo, hi) in RANGES.items()]
    grid = tmp_path / f"{method}.yaml"
    grid.write_text("\n".join(lines) + "\n")
    out = subprocess.run(
        [studyrun, str(grid), "--dry-run"], capture_output=True, text=True, check=True
    ).stdout
    table = out.split("\n\n")[0].splitlines()
    header = table[0].split("\t")
    assert header == ["case", *RANGES]
    values = np.array([[float(x) for x in row.split("\t")[1:]] for row in table[1:]])
    lo = np.array([r[0] for r in RANGES.values()])
    hi = np.array([r[1] for r in RANGES.values()])
    return (values - lo) / (hi - lo)


def test_unscrambled_sobol_points_are_scipys(studyrun, tmp_path):
    n, d = 256, len(RANGES)
    ours = unit_design(studyrun, tmp_path, "sobol", n)
    theirs = qmc.Sobol(d, scramble=False).random(n)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


def test_saltelli_rows_are_salibs_layout_over_scipys_sobol_points(studyrun, tmp_path):
    n, d = 64, len(RANGES)
    ours = unit_design(studyrun, tmp_path, "saltelli", n).reshape(n, 2 * d + 2, d)
    base = qmc.Sobol(2 * d, scramble=False).random(n)
    a, b = base[:, :d], base[:, d:]
    np.testing.assert_allclose(ours[:, 0], a, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ours[:, -1], b, rtol=0, atol=1e-12)
    for k in range(d):
        ab, ba = a.copy(), b.copy()
        ab[:, k], ba[:, k] = b[:, k], a[:, k]
        np.testing.assert_allclose(ours[:, 1 + k], ab, rtol=0, atol=1e-12)
        np.testing.assert_allclose(ours[:, 1 + d + k], ba, rtol=0, atol=1e-12)


def test_a_saltelli_study_runs_and_gives_sobol_indices(studyrun, tmp_path):
    """End to end: studyrun runs a small Saltelli design, analysis/sensitivity.py reads
    its file and returns indices for each design parameter with intervals."""
    import sys

    import xarray as xr

    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", ".."))
    from analysis.sensitivity import study_saltelli

    grid = tmp_path / "saltelli.yaml"
    grid.write_text(
        "name: saltelli\nduration: 0.05\nsample_rate: 5000\n"
        "effects: [clearance, waviness, damping]\nrpm: 600\n"
        "design:\n  method: saltelli\n  samples: 16\n  seed: 1\n  parameters:\n"
        "    clearance: {min: \"10 um\", max: \"60 um\"}\n"
        "    damping: {min: 10, max: 1000, scale: log}\n"
    )
    out = tmp_path / "saltelli.h5"
    subprocess.run([studyrun, str(grid), "-o", str(out)], check=True, capture_output=True)
    with xr.open_dataset(out, engine="h5netcdf") as ds:
        assert ds.attrs["design_method"] == "saltelli"
        assert ds.sizes["case"] == 16 * (2 * 2 + 2)
        np.testing.assert_array_equal(ds.design_row.values, np.arange(96))
        indices = study_saltelli(ds.load(), "slider_acceleration_rms_deviation", resamples=200)
    assert list(indices.names) == ["clearance", "damping"]
    assert np.all(np.isfinite(indices.first)) and np.all(np.isfinite(indices.total))
    assert np.all(indices.total_conf > 0) and indices.method == "saltelli"
