"""What the figures show and leave out: no facet for a combination a `zip:` skips, one
index line per reason a figure is not shown, `--channels` taking a sensor's series, the
stored spectral kurtosis, the rpm–order map of a run-up, a raw spectrogram's frequency
axis up to its content, and no `none` labels in a study without defects."""

import itertools

import numpy as np
import pytest
import xarray as xr

from analysis import diagnosis as dg
from analysis import diagnosis_figures as dfig
from analysis import figures, report
from analysis.studyfile import open_study, text


def zipped_study():
    """ball_count × rpm × (clearance, damping) zipped in three pairs: 3 of the 9
    clearance × damping combinations run."""
    pairs = [(1e-5, 100.0), (2e-5, 200.0), (3e-5, 300.0)]
    rows = [(b, r, c, d) for b, r, (c, d) in itertools.product([8.0, 9.0], [300.0, 600.0], pairs)]
    b, r, c, d = np.array(rows).T
    return xr.Dataset(
        {"ball_count": ("case", b), "rpm": ("case", r), "clearance": ("case", c, {"units": "m"}),
         "damping": ("case", d, {"units": "N s m-1"}), "status": ("case", np.ones(len(rows), dtype="int8")),
         "m": ("case", b * r + 1e6 * c + d, {"units": "m s-2"})},
        coords={"case": np.arange(len(rows), dtype="int32")},
        attrs={"grid_axes": "ball_count,rpm,clearance,damping"},
    )


def test_zipped_axes_get_a_facet_per_combination_run(drawn, tmp_path):
    figures.metrics_view(zipped_study(), "m", "ball_count", "rpm", out=tmp_path / "m.png", dpi=40)
    shown = [ax for ax in drawn[-1].axes if ax.get_visible() and ax.get_title()]
    assert [ax.get_title() for ax in shown] == ["clearance 10 µm, damping 100 N s/m",
                                                "clearance 20 µm, damping 200 N s/m",
                                                "clearance 30 µm, damping 300 N s/m"]
    for ax in shown:
        assert np.isfinite(ax.collections[0].get_array()).all()


def test_a_reason_repeated_is_one_index_line():
    index = report.Index("t")
    for k in range(48):
        index.skipped(f"spectra of crank_moment, case {k}", "the file stores every 2th sample")
    index.skipped("orbit", "the study has no eccentricity_x")
    text_ = index.text()
    assert text_.count("not shown") == 2
    assert ("*48 figures not shown (the file stores every 2th sample): spectra of crank_moment, case 0; "
            "spectra of crank_moment, case 1; spectra of crank_moment, case 2; and 45 more.*") in text_
    assert "*orbit: not shown (the study has no eccentricity_x).*" in text_


def test_a_decimated_report_says_each_reason_once(decimated_diagnosis, tmp_path):
    """The decimated diagnosis study: the spectra the report cannot draw (their ideal
    spectrum needs the full rate) are one line, and the figures drawn follow the stored
    rate (docs: test_analysis_decimated.py)."""
    path = tmp_path / "decimated.h5"
    decimated_diagnosis.to_netcdf(path, engine="h5netcdf")
    report.report(path, tmp_path / "out", channels=["bearing_force", "crank_moment"], dpi=30)
    index = (tmp_path / "out" / "index.md").read_text(encoding="utf-8")
    lines = [line for line in index.splitlines() if "not shown" in line]
    assert len(lines) == len(set(lines)) == 1, lines
    # 8 constant-speed groups (4 fault labels × 2 speeds) × 2 channels
    assert lines[0].startswith("*16 figures not shown (the ideal mechanism's spectrum needs its full-rate series")


def test_channels_take_a_sensor_series(diagnosis_path, tmp_path):
    """`--channels accelerometer` draws the sensor's series per condition, without an ideal
    curve; a name that is no series is refused with the ones allowed."""
    out = tmp_path / "r"
    report.main([diagnosis_path, str(out), "--channels", "accelerometer", "--dpi", "30"])
    index = (out / "index.md").read_text(encoding="utf-8")
    panels = sorted(p.name for p in out.glob("panels_accelerometer_*.png"))
    assert len(panels) == 8  # 4 fault labels × 2 constant speeds
    assert "panels_accelerometer_crank_ground_900rpm_0um_outer_900rpm_900rpm.png" in panels
    assert "accelerometer against time" in index and "ideal mechanism dashed" not in index
    with pytest.raises(SystemExit, match=r"--channels housing: not a series of the file; allowed: "
                                         r"slider_acceleration, crank_moment, bearing_force, .*accelerometer"):
        report.main([diagnosis_path, str(out), "--channels", "housing"])


def cases_at(ds, keep):
    """{fault label: case} of the cases whose constant speed passes `keep` (NaN: run-up)."""
    return {text(ds["fault"].values[k]): k for k in range(ds.sizes["case"]) if keep(dg.constant_rpm(ds, k))}


def test_spectral_kurtosis_figure_draws_the_stored_values(diagnosis, drawn, tmp_path):
    cases = cases_at(diagnosis, lambda rpm: rpm == 600.0)
    dfig.spectral_kurtosis(diagnosis, "accelerometer", cases, tmp_path / "sk.png", dpi=40)
    # On its own frequencies: the STFT bins of `stft_segment` samples.
    freq = diagnosis["sk_frequency"].values
    assert diagnosis["accelerometer_spectral_kurtosis"].dims == ("case", "sk_frequency")
    assert len(freq) == int(diagnosis.attrs["stft_segment"]) // 2 + 1
    for ax, (label, case) in zip(drawn[-1].axes, cases.items()):
        x, y = ax.lines[0].get_data()
        np.testing.assert_array_equal(x, freq)
        np.testing.assert_array_equal(y, diagnosis["accelerometer_spectral_kurtosis"].values[case])
        band = ax.patches[0]
        low = float(diagnosis["accelerometer_envelope_band_low"].values[case])
        high = float(diagnosis["accelerometer_envelope_band_high"].values[case])
        assert band.get_x() == low and band.get_x() + band.get_width() == pytest.approx(high, rel=1e-12)
        assert ax.get_title().startswith(f"{label}: largest")


def test_rpm_order_map_of_the_outer_race_run_up(diagnosis, drawn, tmp_path):
    """The outer-race spall's run-up: the map spans the run-up's speeds and its mean over
    the speeds peaks (above order 1) at the BPFO order, to within its order step; the
    figure marks that order."""
    case = cases_at(diagnosis, np.isnan)["outer"]
    rpm, orders, amplitude = dfig.order_map(diagnosis, "bearing_force", case)
    bpfo = dg.fault_orders(diagnosis, case).bpfo
    assert rpm.min() < 450 and rpm.max() > 800 and np.all(np.diff(rpm) > 0)
    above = orders > 1
    peak = orders[above][np.argmax(amplitude.mean(axis=0)[above])]
    assert abs(peak - bpfo) <= orders[1], (peak, bpfo)
    dfig.rpm_order_map(diagnosis, "bearing_force", {"outer": case}, tmp_path / "m.png", dpi=40)
    ax = drawn[-1].axes[0]
    assert ax.get_xlabel() == "order (cycles per crank revolution)" and ax.get_ylabel() == "crank speed (rpm)"
    assert any(abs(line.get_xdata()[0] - bpfo) < 1e-12 for line in ax.lines)


def test_raw_spectrogram_stops_where_its_content_does(diagnosis, drawn, tmp_path):
    """Without a band the spectrogram shows the crank moment up to where 99.5 % of its
    power lies (a 1, 2, 5 step), not to f_s/2."""
    cases = cases_at(diagnosis, lambda rpm: rpm == 600.0)
    dfig.spectrogram(diagnosis, "crank_moment", cases, tmp_path / "s.png", dpi=40)
    top = drawn[-1].axes[0].get_ylim()[1]
    fs = float(diagnosis.attrs["sample_rate"])
    assert top < fs / 2
    for case in cases.values():
        _, x = dg.window_series(diagnosis, "crank_moment", case)
        power = np.abs(np.fft.rfft(x - x.mean())) ** 2
        freqs = np.fft.rfftfreq(x.size, 1 / fs)
        assert power[freqs > top].sum() < 0.005 * power.sum() * len(cases)
    assert top == dfig.content_top([dg.window_series(diagnosis, "crank_moment", c)[1] for c in cases.values()], fs)
    assert str(int(top))[0] in "125"


def test_a_study_without_defects_has_no_none_labels(smoke_path, drawn, tmp_path):
    """The smoke study has no defect: no legend, title or file name of its diagnosis
    figures reads `none`."""
    report.report(smoke_path, tmp_path, channels=["crank_moment"], dpi=30)
    words = []
    for fig in drawn:
        for ax in fig.axes:
            words.append(ax.get_title())
            legend = ax.get_legend()
            words += [t.get_text() for t in legend.get_texts()] if legend else []
    assert words and not [w for w in words if "none" in w.split(":")[0].split()], words
    assert "no defect" in " ".join(words)
    assert not [p.name for p in tmp_path.glob("*none*")]
