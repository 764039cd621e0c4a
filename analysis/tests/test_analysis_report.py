"""report.py end to end: the command line on the smoke study, and studies that lack
ball counts or bearing cases."""

import re
import subprocess
import sys
from pathlib import Path

import pytest

from analysis import report

SCRIPT = Path(__file__).resolve().parents[1] / "report.py"


def linked_images(index):
    """The PNG file names index.md shows."""
    return re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", index)


def check_index(outdir, assert_png):
    """index.md shows every PNG of `outdir` once, each exists and is a figure, each with
    a caption line; returns the index text and the image names."""
    index = (outdir / "index.md").read_text(encoding="utf-8")
    images = linked_images(index)
    assert len(images) == len(set(images))
    assert sorted(images) == sorted(p.name for p in outdir.glob("*.png"))
    for name in images:
        assert_png(outdir / name, min_kb=10, min_pixels=150)
        caption = index.split(f"({name})", 1)[1].strip().splitlines()[0]
        assert len(caption) > 30, caption
    return index, images


def test_help(capsys):
    with pytest.raises(SystemExit) as done:
        report.main(["--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert "study" in out and "outdir" in out and "--channels" in out and "--select" in out


def test_command_line_on_the_smoke_study(smoke_path, tmp_path, assert_png):
    """From another working directory: metrics views plus panels and spectra for the four
    bearing combinations (2 locations × 2 waviness amplitudes at 600 rpm)."""
    outdir = tmp_path / "report"
    done = subprocess.run(
        [sys.executable, str(SCRIPT), smoke_path, str(outdir), "--channels", "slider_acceleration", "--dpi", "60"],
        cwd=tmp_path, capture_output=True, text=True,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == str(outdir / "index.md")
    index, images = check_index(outdir, assert_png)
    assert "# Study `smoke`" in index and "10 ok" not in index and "12 ok, 0 failed, 4 ideal" in index
    assert sum(name.startswith("metrics_") for name in images) == 6
    panels = sorted(name for name in images if name.startswith("panels_"))
    assert panels == [f"panels_slider_acceleration_{loc}_600rpm_{a}um.png"
                      for loc in ("crank_ground", "crank_rod") for a in (0, 4)]
    assert sum(name.startswith("spectrum_") for name in images) == 4
    assert "not shown" not in index


def test_one_ball_count_and_no_grid_axis_left(smoke_path, tmp_path, assert_png):
    """With ball count, waviness and location fixed nothing varies: no metrics view and a
    one-panel figure, said so in the index."""
    path = report.report(smoke_path, tmp_path, channels=["crank_moment"], dpi=60,
                         selections=["ball_count=8", "waviness_amplitude=4e-6", "location=crank_rod"])
    assert path == tmp_path / "index.md"
    index, images = check_index(tmp_path, assert_png)
    assert "No grid axis varies among the bearing cases" in index
    assert "one ball count per combination" in index
    assert sorted(images) == ["panels_crank_moment_crank_rod_600rpm_4um.png",
                              "spectrum_crank_moment_crank_rod_600rpm_4um.png"]


def test_a_study_of_the_ideal_mechanism_only(smoke, tmp_path):
    """No bearing case: nothing to plot, and the index says why."""
    ideal = tmp_path / "ideal.h5"
    smoke.isel(case=(smoke["location"] == "ideal").values).to_netcdf(ideal, engine="h5netcdf")
    report.report(ideal, tmp_path / "out", dpi=60)
    index = (tmp_path / "out" / "index.md").read_text(encoding="utf-8")
    assert linked_images(index) == []
    assert "No grid axis varies among the bearing cases" in index
    assert "no successful case with a bearing" in index


def test_select_is_checked(smoke_path, tmp_path):
    with pytest.raises(SystemExit, match="NAME=VALUE"):
        report.main([smoke_path, str(tmp_path), "--select", "nonsense"])
