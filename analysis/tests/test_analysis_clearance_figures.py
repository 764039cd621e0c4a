"""analysis/clearance_figures.py on a small clearance study (studies/clearance.yaml at
5000 rpm, two clearances, 0.024 s at 20 kHz) run with STUDYRUN_BIN: the script writes
its three figures, and refuses a selection with no case and a file without the series;
and on a small bifurcation sweep (studies/clearance_bifurcation.yaml, two clearances ×
two speeds): one Poincaré point per whole revolution of the last half, and the figure."""

import os
import subprocess
from pathlib import Path

import pytest

from analysis import clearance_figures
from analysis.studyfile import open_study

REPO = Path(__file__).resolve().parents[2]


def shortened(text, lines, drop=None):
    """`text` with each line whose stripped start is a key of `lines` replaced by its
    value, and the lines containing `drop` left out."""
    out = []
    for line in text.splitlines():
        if drop is not None and drop in line:
            continue
        out.append(next((new for start, new in lines.items() if line.strip().startswith(start)), line))
    return "\n".join(out) + "\n"


def small_study(text):
    """studies/clearance.yaml shortened: 0.024 s at 20 kHz, 5000 rpm, 0.5 and 0.1 mm."""
    lines = {
        "duration:": "duration: 0.024",
        "sample_rate:": "sample_rate: 20000",
        "rpm: [2000, 5000]": "  rpm: [5000]",
        "journal_clearance:": '  journal_clearance: ["0.5 mm", "0.1 mm"]',
    }
    return shortened(text, lines, drop="rpm: 2000}")


def run_shortened(tmp_path_factory, name, shorten):
    """studies/<name>.yaml shortened by `shorten`, run with STUDYRUN_BIN (skipped
    without it): the loaded Dataset and the file's path."""
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("STUDYRUN_BIN is not set")
    work = tmp_path_factory.mktemp(name)
    grid = work / f"{name}.yaml"
    grid.write_text(shorten((REPO / f"studies/{name}.yaml").read_text()))
    out = work / f"{name}.h5"
    subprocess.run([binary, str(grid), "-o", str(out), "-j", "2", "--force", "-q"], check=True)
    with open_study(out) as ds:
        return ds.load(), out


@pytest.fixture(scope="module")
def clearance(tmp_path_factory):
    return run_shortened(tmp_path_factory, "clearance", small_study)


def test_draws_the_three_figures(clearance, tmp_path, assert_png):
    ds, _ = clearance
    assert list(clearance_figures.dry_cases(ds, 5000.0, 0.01)) == [0.5e-3, 0.1e-3]
    paths = clearance_figures.draw(ds, tmp_path, 5000.0, 0.01)
    assert [p.name for p in paths] == [
        f"clearance_{name}_5000rpm_mu0.01.png" for name in ("slider_acceleration", "orbit", "contact_force")
    ]
    for path in paths:
        assert_png(path)


def test_command_line(clearance, tmp_path):
    _, path = clearance
    assert clearance_figures.main([str(path), str(tmp_path), "--friction", "0"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        f"clearance_{name}_5000rpm_mu0.png" for name in ("contact_force", "orbit", "slider_acceleration")
    ]


def test_refuses_what_is_not_there(clearance, tmp_path):
    ds, _ = clearance
    with pytest.raises(ValueError, match="no successful dry_clearance case at 2000"):
        clearance_figures.orbit(ds, tmp_path / "x.png", 2000.0, 0.01)
    with pytest.raises(ValueError, match="stores no eccentricity_x"):
        clearance_figures.orbit(ds.drop_vars("eccentricity_x"), tmp_path / "x.png", 5000.0, 0.01)


def small_sweep(text):
    """studies/clearance_bifurcation.yaml shortened: 0.06 s at 20 kHz, 2 replicates,
    0.5 and 0.02 mm at 2000 and 5000 rpm."""
    lines = {
        "duration:": "duration: 0.06",
        "sample_rate:": "sample_rate: 20000",
        "count:": "  count: 2",
        "journal_clearance:": '  journal_clearance: ["0.5 mm", "0.02 mm"]',
        "rpm:": "  rpm: [2000, 5000]",
    }
    return shortened(text, lines)


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    return run_shortened(tmp_path_factory, "clearance_bifurcation", small_sweep)


def test_poincare_sections_and_the_bifurcation_figure(sweep, tmp_path, assert_png):
    ds, path = sweep
    assert ds.sizes["case"] == 4
    for case in range(4):
        rpm = float(ds["rpm"].values[case])
        section = clearance_figures.poincare(ds, case, ds["slider_acceleration"].values[case])
        # The whole revolutions k·60/rpm in the last half of 0.06 s: 0.03 s ≤ t ≤ 0.06 s.
        period = 60.0 / rpm
        expected = int(0.06 / period + 1e-9) - int(-(-0.03 // period)) + 1
        assert len(section) == expected, (rpm, len(section), expected)
    assert_png(clearance_figures.bifurcation(ds, tmp_path / "b.png"))
    assert clearance_figures.main([str(path), str(tmp_path), "--bifurcation"]) == 0
    assert_png(tmp_path / "clearance_bifurcation.png")
    with pytest.raises(ValueError, match="stores no chaotic"):
        clearance_figures.bifurcation(ds.drop_vars("chaotic"), tmp_path / "x.png")
