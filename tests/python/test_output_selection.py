"""`output: {series, decimate}` read from Python: a file that stores a decimated
selection, and one that stores no series (no `time` dimension), open in xarray (h5netcdf,
and netCDF-C through netCDF4 when installed) with the same metrics and spectra as the
full-rate file; the analysis helpers follow the stored samples, and those that need
series say so naming `output.series`.

Environment: STUDYRUN_BIN (the binary runs small studies written here); else skip.
"""

import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis.dataset import make_splits  # noqa: E402
from analysis.studyfile import analysis_window, open_study  # noqa: E402
from study_run import run_grid  # noqa: E402

GRID = """name: {name}
duration: 0.05
sample_rate: 10000
transient: "0.012 s"
grid:
  location: [crank_ground, crank_rod]
  ball_count: [8, 9]
{output}"""

VARIANTS = {
    "full": "",
    "dec": "output: {series: [slider_acceleration, bearing_force], decimate: 3}\n",
    "none": "output: {series: none}\n",
}


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("output")
    return {
        name: run_grid(d, name, GRID.format(name=name, output=output))
        for name, output in VARIANTS.items()
    }


def test_decimated_series_are_the_full_series_at_every_third_sample(files):
    with open_study(files["full"]) as full, open_study(files["dec"]) as dec:
        assert dec.attrs["decimate"] == 3
        assert dec.attrs["series_sample_rate"] == pytest.approx(10000 / 3, rel=1e-15)
        series = sorted(v for v in dec.data_vars if dec[v].dims == ("case", "time"))
        assert series == ["bearing_force", "slider_acceleration"]
        assert sorted(v for v in dec.data_vars if dec[v].dims == ("reference", "time")) == [
            "reference_slider_acceleration"
        ]
        np.testing.assert_array_equal(dec["time"].values, full["time"].values[::3])
        for name in series:
            np.testing.assert_array_equal(dec[name].values, full[name].values[:, ::3])
        for name in [v for v in full.data_vars if full[v].dims == ("case", "frequency")]:
            np.testing.assert_array_equal(dec[name].values, full[name].values)
        # The analysed window of the stored samples is the full window's every third sample.
        full_k = np.flatnonzero(analysis_window(full))
        np.testing.assert_array_equal(np.flatnonzero(analysis_window(dec)) * 3, full_k[full_k % 3 == 0])
        splits = make_splits(dec, ["slider_acceleration"], length=16, hop=8, labels=["location"])
        assert sum(len(s) for s in splits.values()) > 0


def test_a_file_without_series_opens_and_says_what_it_lacks(files):
    with open_study(files["full"]) as full, open_study(files["none"]) as none:
        assert "time" not in none.dims and "time" not in none.coords
        assert not [v for v in none.data_vars if "time" in none[v].dims]
        for name in [v for v in full.data_vars if full[v].dims in (("case",), ("case", "frequency"))]:
            if name != "wall_time":
                np.testing.assert_array_equal(none[name].values, full[name].values, err_msg=name)
        with pytest.raises(ValueError, match="output.series"):
            make_splits(none, ["slider_acceleration"], length=16, hop=8)
        with pytest.raises(ValueError, match="output.series"):
            analysis_window(none)
    with xr.open_dataset(files["none"], engine="h5netcdf") as ds:
        assert ds.sizes["case"] == 4 and "frequency" in ds.dims
    netcdf4 = pytest.importorskip("netCDF4")
    with netcdf4.Dataset(files["none"]) as nc:
        assert "time" not in nc.dimensions
        assert nc.variables["slider_acceleration_spectrum"].dimensions == ("case", "frequency")


def test_the_report_skips_the_series_views_of_a_file_without_series(files, tmp_path):
    pytest.importorskip("matplotlib")
    from analysis import report

    index = report.report(files["none"], tmp_path, dpi=40).read_text()
    assert "output.series: none" in index
