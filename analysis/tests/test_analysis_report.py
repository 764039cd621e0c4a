"""report.py end to end: the command line on the smoke study, studies that lack ball
counts or bearing cases, and the diagnosis figures on studies/diagnosis.yaml's file and on
files changed to lack (or to add) what they draw."""

import itertools
import re
import subprocess
import sys
from pathlib import Path

import pytest

import numpy as np
import xarray as xr

from analysis import diagnosis as dg
from analysis import diagnosis_figures as dfig
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
    index, _ = check_index(outdir, assert_png)
    images = linked_images(index.split("## Diagnosis")[0])
    assert "# Study `smoke`" in index and "10 ok" not in index and "12 ok, 0 failed, 4 ideal" in index
    assert sum(name.startswith("metrics_") for name in images) == 6
    panels = sorted(name for name in images if name.startswith("panels_"))
    assert panels == [f"panels_slider_acceleration_{loc}_600rpm_{a}um.png"
                      for loc in ("crank_ground", "crank_rod") for a in (0, 4)]
    assert sum(name.startswith("spectrum_") for name in images) == 4
    assert "not shown" not in index
    section = diagnosis_section(index)  # the orbits of 8 conditions, the first one's spectrogram
    assert linked_images(section) == ["orbit_0.png", "orbit_1.png",
                                      "spectrogram_bearing_force_crank_ground_waviness0um_N_b8_600rpm.png"]
    assert "no `envelope:`" in section and "no order spectra" in section


def test_one_ball_count_and_no_grid_axis_left(smoke_path, tmp_path, assert_png):
    """With ball count, waviness and location fixed nothing varies: no metrics view and a
    one-panel figure, said so in the index."""
    path = report.report(smoke_path, tmp_path, channels=["crank_moment"], dpi=60,
                         selections=["ball_count=8", "waviness_amplitude=4e-6", "location=crank_rod"])
    assert path == tmp_path / "index.md"
    index, images = check_index(tmp_path, assert_png)
    assert "No grid axis varies among the bearing cases" in index
    assert "one ball count per combination" in index
    assert sorted(images) == ["orbit_0.png",
                              "panels_crank_moment_crank_rod_600rpm_4um.png",
                              "spectrogram_bearing_force_600rpm.png",
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



DIAGNOSIS_FIGURES = [
    "orbit_0.png",
    "envelope_bearing_force_600rpm.png",
    "envelope_bearing_force_900rpm.png",
    "envelope_accelerometer_600rpm.png",
    "envelope_accelerometer_900rpm.png",
    "spectrogram_bearing_force_run-up300-900rpm.png",
    "waterfall_bearing_force.png",
    "waterfall_accelerometer.png",
    "orders_bearing_force_run-up300-900rpm.png",
    "rpm_orders_bearing_force_run-up300-900rpm.png",
    "spectral_kurtosis_bearing_force_600rpm.png",
    "spectral_kurtosis_accelerometer_600rpm.png",
] + [f"kurtogram_bearing_force_600rpm_{fault}.png" for fault in ("outer", "inner", "ball", "none")] + [
    "indicators_bearing_force.png",
    "indicators_accelerometer.png",
]


def diagnosis_section(index):
    """The text of index.md's diagnosis section."""
    return index.split("## Diagnosis", 1)[1]


@pytest.fixture(scope="module")
def diagnosis_report(diagnosis_path, tmp_path_factory):
    """report.py run on studies/diagnosis.yaml's file: (output directory, index text)."""
    outdir = tmp_path_factory.mktemp("diagnosis_report")
    report.report(diagnosis_path, outdir, channels=["bearing_force"], dpi=60)
    return outdir, (outdir / "index.md").read_text(encoding="utf-8")


def test_the_diagnosis_study_shows_every_figure(diagnosis_report, assert_png):
    """Orbit, envelope spectra of the bearing force and of the housing accelerometer per
    constant speed, spectrogram, order spectra and rpm–order map of the run-up, a waterfall,
    the spectral kurtosis and indicator heatmaps of each envelope channel, a kurtogram per
    fault label; nothing skipped."""
    outdir, index = diagnosis_report
    check_index(outdir, assert_png)
    section = diagnosis_section(index)
    assert linked_images(section) == DIAGNOSIS_FIGURES
    assert "not shown" not in section and "*" not in section
    # The healthy cases (defect_race none) complete the grid: defect_race × speed (speed_from,
    # each case's speed shown by its profile) tells every case apart.
    assert "indicators of bearing_force (docs/model.md §7.7) over defect_race × speed" in section
    assert "indicators of accelerometer (docs/model.md §7.7) over defect_race × speed" in section


def fault_cases(ds, rpm):
    """{fault label: case position} of the cases at the constant speed `rpm`."""
    return {str(ds["fault"].values[k]): k for k in range(ds.sizes["case"]) if dg.constant_rpm(ds, k) == rpm}


@pytest.mark.parametrize("rpm", [600.0, 900.0])
def test_each_fault_line_stands_in_its_envelope_spectrum(diagnosis, rpm):
    """In the stored envelope spectrum of the bearing force (the kurtogram's band), each
    defect's line (outer BPFO, inner BPFI, ball 2·BSF; largest within ±1 bin) is the largest
    of the three lines, at least 5 times the spectrum's median below 3× the line (measured
    12–116), and a million times the healthy bearing's there; its band energy is the largest
    of the three."""
    freq = diagnosis["frequency"].values
    spectra = diagnosis["bearing_force_envelope_spectrum"].values
    cases = fault_cases(diagnosis, rpm)
    assert sorted(cases) == ["ball", "inner", "none", "outer"]

    def at(case, f):
        k = int(np.argmin(np.abs(freq - f)))
        return spectra[case, k - 1 : k + 2].max()

    energy = {"BPFO": "bpfo", "BPFI": "bpfi", "2·BSF": "2bsf"}
    for fault, own in dg.FAULT_LINE.items():
        case = cases[fault]
        lines = {name: order * rpm / 60 for name, order in dg.fault_orders(diagnosis, case).lines().items()}
        heights = {name: at(case, lines[name]) for name in energy}
        assert max(heights, key=heights.get) == own, (fault, heights)
        median = np.median(spectra[case, (freq > 1) & (freq < 3 * lines[own])])
        assert heights[own] > 5 * median, (fault, heights[own], median)
        assert heights[own] > 1e6 * at(cases["none"], lines[own]), fault
        energies = {name: float(diagnosis[f"bearing_force_envelope_energy_{e}"].values[case])
                    for name, e in energy.items()}
        assert max(energies, key=energies.get) == own, (fault, energies)


@pytest.mark.parametrize("rpm", [600.0, 900.0])
def test_each_fault_line_stands_in_the_noisy_sensor_s_envelope(diagnosis, rpm):
    """The accelerometer (3 kHz, ζ = 0.05, 10 dB SNR on housing_acceleration_y): in its stored
    envelope spectrum, in the band the file records for the case (the sensor's resonance,
    below 5 kHz), each defect's line is the largest of BPFO, BPFI and 2·BSF and at least 4
    times the spectrum's median below 3× the line (measured 41, 40, 17 at 600 rpm and 66,
    58, 13 at 900 rpm: outer, inner, ball)."""
    cases = fault_cases(diagnosis, rpm)
    for fault, own in dg.FAULT_LINE.items():
        case = cases[fault]
        freq, spectrum, (low, high), stored = dfig.case_envelope(diagnosis, "accelerometer", case)
        assert stored
        np.testing.assert_array_equal(spectrum, diagnosis["accelerometer_envelope_spectrum"].values[case])
        assert (low, high) == tuple(float(diagnosis[f"accelerometer_envelope_band_{e}"].values[case])
                                    for e in ("low", "high"))
        assert high <= 5000, (low, high)  # the sensor's resonance, not the 5–10 kHz of the force
        lines = {name: order * rpm / 60 for name, order in dg.fault_orders(diagnosis, case).lines().items()}

        def at(f):
            k = int(np.argmin(np.abs(freq - f)))
            return spectrum[k - 1 : k + 2].max()

        heights = {name: at(lines[name]) for name in ("BPFO", "BPFI", "2·BSF")}
        assert max(heights, key=heights.get) == own, (fault, heights)
        assert heights[own] > 4 * np.median(spectrum[(freq > 1) & (freq < 3 * lines[own])]), fault


def test_envelope_figure_marks_the_lines_and_sidebands(diagnosis, drawn, tmp_path):
    """Each panel marks FTF, BPFO, BPFI, BSF, 2·BSF at order × rpm/60 and, around its own
    fault line, the shaft sidebands ±1 and ±2 × rpm/60; the accelerometer's panels show the
    band the file records in the squared unit of an acceleration."""
    cases = fault_cases(diagnosis, 600.0)
    dfig.envelope_spectra(diagnosis, "bearing_force", cases, tmp_path / "e.png", dpi=50)
    axes = drawn[0].axes
    assert [ax.get_title().split(":")[0] for ax in axes] == list(cases)
    for ax, (fault, case) in zip(axes, cases.items()):
        marks = sorted(round(line.get_xdata()[0], 6) for line in ax.lines if line.get_linestyle() in ("--", ":"))
        lines = {k: v * 10 for k, v in dg.fault_orders(diagnosis, case).lines().items()}
        want = list(lines.values())
        if fault in dg.FAULT_LINE:
            want += [lines[dg.FAULT_LINE[fault]] + k * 10 for k in (-2, -1, 1, 2)]
        assert marks == sorted(round(f, 6) for f in want), fault
        assert ax.get_xlabel() == "frequency (Hz)" and ax.get_ylabel() == "envelope amplitude (N²)"
    dfig.envelope_spectra(diagnosis, "accelerometer", cases, tmp_path / "a.png", dpi=50)
    for ax, case in zip(drawn[-1].axes, cases.values()):
        low = float(diagnosis["accelerometer_envelope_band_low"].values[case])
        assert ax.get_title().split(": ")[1].startswith(f"band {low:g}–"), ax.get_title()
        assert ax.get_ylabel() == "envelope amplitude ((m/s²)²)"


def test_orbit_draws_the_clearance_circle(diagnosis, drawn, tmp_path):
    """The preloaded study has no circle (the legend says so); with a 40 µm diametral
    clearance the dashed circle has radius 20 µm."""
    groups = {"600 rpm": fault_cases(diagnosis, 600.0)}
    dfig.orbit(diagnosis, groups, tmp_path / "o.png", dpi=50)
    ax = drawn[-1].axes[0]
    assert any("preload 10 µm" in t.get_text() for t in ax.get_legend().get_texts())
    assert not any(line.get_linestyle() == "--" for line in ax.lines)
    loose = diagnosis.assign(clearance=diagnosis["clearance"] * 0 + 40e-6)
    dfig.orbit(loose, groups, tmp_path / "o2.png", dpi=50)
    ax = drawn[-1].axes[0]
    circle = [line for line in ax.lines if line.get_linestyle() == "--"]
    assert len(circle) == 1
    np.testing.assert_allclose(np.hypot(circle[0].get_xdata(), circle[0].get_ydata()), 20.0, rtol=1e-12)
    assert ax.get_xlabel() == "eccentricity x (µm)"


def test_order_spectra_draw_a_stored_order_spectrum(diagnosis, drawn, tmp_path):
    """A file with `<channel>_order_spectrum[case, order]` (here synthetic: a line of 5 N at
    order 7 in the run-ups, NaN at constant speeds) is drawn as stored; without it the panels
    are resampled in crank angle."""
    orders = np.arange(0, 20.01, 0.25)
    runups = [k for k in range(diagnosis.sizes["case"]) if np.isnan(dg.constant_rpm(diagnosis, k))]
    values = np.full((diagnosis.sizes["case"], orders.size), np.nan)
    values[runups] = 1e-3
    values[runups, 28] = 5.0
    stored = diagnosis.assign_coords(order=orders).assign(
        bearing_force_order_spectrum=(("case", "order"), values, {"units": "N"}))
    path = tmp_path / "orders.h5"
    stored.to_netcdf(path, engine="h5netcdf")
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        cases = {str(ds["fault"].values[k]): k for k in runups}
        dfig.order_spectra(ds, "bearing_force", cases, tmp_path / "s.png", dpi=50)
    for ax in drawn[-1].axes:
        assert ax.get_title().endswith("stored")
        x, y = ax.lines[0].get_data()
        assert x[np.argmax(y)] == 7.0 and y.max() == 5.0
    dfig.order_spectra(diagnosis, "bearing_force", cases, tmp_path / "r.png", dpi=50)
    assert all(ax.get_title().endswith("resampled in crank angle") for ax in drawn[-1].axes)


def test_kurtogram_figure_marks_the_band_of_the_file(diagnosis, drawn, tmp_path):
    """The recomputed largest band (white) is the one the file records (cyan, dashed), on
    the same level row; one image row per level."""
    case = fault_cases(diagnosis, 600.0)["outer"]
    dfig.kurtogram(diagnosis, "bearing_force", case, tmp_path / "k.png", dpi=50)
    ax = drawn[-1].axes[0]
    best, stored = ax.patches
    assert best.get_xy() == stored.get_xy() and best.get_width() == stored.get_width()
    low = float(diagnosis["bearing_force_envelope_band_low"].values[case])
    assert best.get_x() == low
    n = int(dg.analysis_window(diagnosis).sum())
    assert len(ax.get_yticks()) == 2 * dg.kurtogram_depth(n)
    assert ax.get_xlabel() == "frequency (Hz), series stored at 20000 Hz"


@pytest.mark.parametrize("order", ["file", "reversed"])
def test_indicators_over_two_grid_axes(diagnosis, drawn, tmp_path, order):
    """Without the healthy cases (added outside the grid) the grid axes defect_race and
    speed_from tell the cases apart: the heatmaps go over them, one cell per case, the
    speeds in numeric order (constant speeds, then the run-up by its profile) however the
    cases come, the races in the order they first come."""
    defects = diagnosis.isel(case=np.flatnonzero((diagnosis["fault"] != "none").values))
    if order == "reversed":
        defects = defects.isel(case=np.arange(defects.sizes["case"])[::-1])
    path = tmp_path / "defects.h5"
    defects.to_netcdf(path, engine="h5netcdf")
    with report.open_study(path) as ds:
        index = report.Index("defects")
        report.render_indicators(ds, report.bearing_cases(ds), ["bearing_force"], tmp_path, index, 50)
        cell = {(str(ds["defect_race"].values[k]), report.speed_text(ds, k)): float(ds["bearing_force_rms"].values[k])
                for k in range(ds.sizes["case"])}
    assert "indicators of bearing_force (docs/model.md §7.7) over defect_race × speed" in index.text()
    ax = drawn[-1].axes[0]
    assert ax.get_title() == "bearing_force_rms (N)"
    races = [t.get_text() for t in ax.get_xticklabels()]
    assert races == (["outer", "inner", "ball"] if order == "file" else ["ball", "inner", "outer"])
    speeds = [t.get_text() for t in ax.get_yticklabels()]
    assert speeds == ["600 rpm", "900 rpm", "run-up 300→900 rpm"]
    grid = ax.collections[0].get_array()
    for (j, speed), (i, race) in itertools.product(enumerate(speeds), enumerate(races)):
        assert grid[j, i] == cell[(race, speed)]


def test_diagnosis_figures_are_skipped_without_their_data(diagnosis, tmp_path):
    """A study without `envelope:`, sensors and eccentricities: the index says what is not
    shown and why; the spectrogram then shows the raw series of the run-up."""
    names = [n for n in diagnosis.data_vars
             if "envelope" in n or n.startswith(("eccentricity", "ftf", "bpf", "bsf", "accelerometer"))
             or "spectral_kurtosis" in n
             or n.startswith("bearing_force_") and n.split("bearing_force_")[1] in report.INDICATORS]
    bare = diagnosis.drop_vars(names)
    path = tmp_path / "bare.h5"
    bare.to_netcdf(path, engine="h5netcdf")
    report.report(path, tmp_path / "out", channels=["crank_moment"], dpi=50)
    section = diagnosis_section((tmp_path / "out" / "index.md").read_text(encoding="utf-8"))
    assert "orbit: not shown (the study has no eccentricity_x)" in section
    assert "no `envelope:`" in section
    images = linked_images(section)
    assert images == ["spectrogram_bearing_force_run-up300-900rpm.png", "orders_bearing_force_run-up300-900rpm.png",
                      "rpm_orders_bearing_force_run-up300-900rpm.png"]
    assert "spectrogram of bearing_force at run-up 300→900 rpm, from 0 to where 99.5 % of its power lies" in section
