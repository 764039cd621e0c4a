"""figures: every plotting function writes a readable PNG, on the smoke and (optionally) the paper study."""

import pytest

from analysis import figures
from analysis.studyfile import select_cases


@pytest.mark.parametrize("channel", figures.PANEL_CHANNELS)
def test_paper_panels(smoke, tmp_path, channel, assert_png):
    out = figures.paper_panels(smoke, "crank_ground", 600, 4e-6, channel, tmp_path / "panels.png", window=(0.02, 0.05))
    assert out == tmp_path / "panels.png"
    assert_png(out)


def test_paper_panels_default_window_and_one_ball_count(smoke, tmp_path, assert_png):
    assert figures.default_window(smoke, 600) == (0.01, pytest.approx(0.05))
    assert_png(figures.paper_panels(smoke, "crank_rod", 600, 0.0, "bearing_force", tmp_path / "p.png", ball_counts=[9]))


def test_paper_panels_refuse_what_does_not_exist(smoke, tmp_path):
    with pytest.raises(ValueError, match="channel 'housing' is not a series of the file; it has slider_acceleration"):
        figures.paper_panels(smoke, "crank_ground", 600, 4e-6, "housing", tmp_path / "x.png")
    with pytest.raises(ValueError, match="no successful case"):
        figures.paper_panels(smoke, "crank_ground", 300, 4e-6, "crank_moment", tmp_path / "x.png")
    with pytest.raises(ValueError, match="window"):
        figures.paper_panels(smoke, "crank_ground", 600, 4e-6, "crank_moment", tmp_path / "x.png", window=(1, 2))
    assert not (tmp_path / "x.png").exists()


@pytest.mark.parametrize("location", ["crank_ground", "crank_rod"])
def test_spectra(smoke, tmp_path, location, assert_png):
    out = figures.spectra(smoke, location, 600, 4e-6, "slider_acceleration", tmp_path / "s.png", fmax=2000)
    assert_png(out)
    assert_png(figures.spectra(smoke, location, 600, 0.0, "bearing_force", tmp_path / "s0.png"))


def test_spectra_need_a_bearing(smoke, tmp_path):
    with pytest.raises(ValueError, match="ideal"):
        figures.spectra(smoke, "ideal", 600, 4e-6, "slider_acceleration", tmp_path / "s.png")


def test_characteristic_marks_follow_the_waviness(smoke):
    smooth, wavy = (int(select_cases(smoke, location="crank_ground", ball_count=8, waviness_amplitude=a)[0])
                    for a in (0.0, 4e-6))
    assert [label for label, _, _ in figures._marks(smoke, smooth)] == [
        "cage f_c", "ball pass outer N_b f_out", "ball pass inner N_b f_in"]
    marks = figures._marks(smoke, wavy)  # 4 µm on both races at 600 rpm
    assert [round(f, 1) for _, f, _ in marks[3:]] == [134.8, 215.2]


def test_metrics_heatmap(smoke, tmp_path, assert_png):
    out = figures.metrics_view(smoke, "slider_acceleration_rms_deviation", "ball_count", "waviness_amplitude",
                               out=tmp_path / "m.png")
    assert_png(out)


def test_metrics_lines_and_selection(smoke, tmp_path, assert_png):
    assert_png(figures.metrics_view(smoke, "bearing_force_peak_deviation", "ball_count", None, out=tmp_path / "l.png"))
    out = figures.metrics_view(smoke, "crank_moment_rms_deviation", "location", None, out=tmp_path / "s.png",
                               select={"waviness_amplitude": 4e-6})
    assert_png(out)


def test_metrics_refuse_an_axis_that_is_not_in_the_grid(smoke, tmp_path):
    with pytest.raises(ValueError, match="clearance"):
        figures.metrics_view(smoke, "slider_acceleration_rms_deviation", "clearance", None, out=tmp_path / "m.png")


def test_value_text(smoke):
    assert figures.value_text(smoke, "waviness_amplitude", 4e-6) == "4 µm"
    assert figures.value_text(smoke, "waviness_amplitude", 0.0) == "0 µm"
    assert figures.value_text(smoke, "rpm", 600.0) == "600 rpm"
    assert figures.value_text(smoke, "ball_count", 9.0) == "9"
    assert figures.value_text(smoke, "crank_length", 0.05) == "50 mm"
    # the file's N (the force at 1 m of deflection) is shown as the stiffness it states
    assert smoke["stiffness"].attrs["units"] == "N"
    assert figures.value_text(smoke, "stiffness", 9.57e9) == "9.57e+09 N/m^1.5"
    with pytest.raises(ValueError, match=r"file's unit \(N/m\^1\.5\)"):
        select_cases(smoke, stiffness="9.57e9 N/m^1.5")


def test_paper_study_figures(paper, tmp_path, assert_png):
    """The paper's layout: 2×2 panels (8-11 balls), spectra, ball count × rpm per location and waviness."""
    panels = assert_png(figures.paper_panels(paper, "crank_ground", 300, 4e-6, "slider_acceleration",
                                             tmp_path / "p.png"), min_kb=50)
    assert panels.shape[0] > 450  # two rows of panels
    assert_png(figures.spectra(paper, "crank_rod", 600, 4e-6, "bearing_force", tmp_path / "s.png"), min_kb=50)
    assert_png(figures.metrics_view(paper, "slider_acceleration_rms_deviation", "ball_count", "rpm",
                                    out=tmp_path / "m.png"), min_kb=30)
    assert_png(figures.metrics_view(paper, "crank_moment_rms_deviation", "rpm", None, out=tmp_path / "l.png",
                                    select={"location": "crank_rod"}))
