"""What docs/result-file.md says of how each variable was made, and of what a file
leaves out:

- every spectrum-like variable carries its own `window` and `normalisation`; the
  amplitude spectra the study's `spectra.window`, the envelope, spectral-kurtosis and
  order spectra `hann` whatever it says; envelope spectra their `band`, the spectral
  kurtosis its `stft_segment` and `stft_hop`, order spectra `order_revolutions` and
  `order_samples`, equal to the root attributes of the same names;
- the `speed_*` parameters of a profile are stored only when some case runs it;
- a merge keeps every one of these attributes;
- shards open as one dataset with the one `xarray.open_mfdataset` call the README gives.

Environment: STUDYRUN_BIN (the binary runs the studies written here); else skip.
"""

import subprocess

import pytest

from study_run import run_grid, studyrun_binary, text

GRID = """name: provenance
duration: 0.25
sample_rate: 4000
transient: "0.05 s"
rpm: 600
spectra: {window: rectangular, orders: true}
envelope: {channels: [bearing_force], band: ["200 Hz", "900 Hz"], orders: true}
grid:
  location: [crank_ground, crank_rod]
"""

RAMP = """name: ramp
duration: 0.1
sample_rate: 4000
speed: {profile: ramp, from: 300, to: 600, over: "0.05 s"}
grid:
  location: [crank_ground, crank_rod]
"""


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """The study's file, its two shards and their merge, all in one directory."""
    directory = tmp_path_factory.mktemp("provenance")
    whole = run_grid(directory, "provenance", GRID)
    grid = directory / "provenance.yaml"
    parts = []
    for k in (1, 2):
        part = directory / f"part{k}.h5"
        subprocess.run(
            [studyrun_binary(), str(grid), "--shard", f"{k}/2", "-o", str(part), "-q"], check=True
        )
        parts.append(part)
    merged = directory / "merged.h5"
    subprocess.run([studyrun_binary(), "merge", str(merged), *map(str, parts)], check=True)
    return whole, parts, merged


def attributes(path):
    """{variable: {attribute: value}} of every variable of the file at `path`."""
    import h5py

    with h5py.File(path, "r") as f:
        return {name: {k: v for k, v in f[name].attrs.items()} for name in f}, dict(f.attrs)


def test_every_spectrum_says_how_it_was_made(study):
    variables, root = attributes(study[0])
    made = {k: v for k, v in variables.items() if "window" in v}
    assert set(made) == {
        "slider_acceleration_spectrum",
        "crank_moment_spectrum",
        "bearing_force_spectrum",
        "bearing_force_envelope_spectrum",
        "bearing_force_spectral_kurtosis",
        "slider_acceleration_order_spectrum",
        "crank_moment_order_spectrum",
        "bearing_force_order_spectrum",
        "bearing_force_envelope_order_spectrum",
    }
    for name, attrs in made.items():
        assert "normalisation" in attrs, name
        expected = text(root["spectrum_window"]) if name.endswith("_spectrum") and not (
            "envelope" in name or "order" in name
        ) else "hann"
        assert text(attrs["window"]) == expected, name
    assert text(root["spectrum_window"]) == "rectangular"
    assert text(made["bearing_force_envelope_spectrum"]["band"]) == "200 Hz to 900 Hz"
    assert text(made["bearing_force_envelope_spectrum"]["band"]) == text(root["envelope_band"])
    sk = made["bearing_force_spectral_kurtosis"]
    assert (sk["stft_segment"], sk["stft_hop"]) == (root["stft_segment"], root["stft_hop"])
    for name in ("bearing_force_order_spectrum", "bearing_force_envelope_order_spectrum"):
        assert made[name]["order_revolutions"] == root["order_revolutions"]
        assert made[name]["order_samples"] == root["order_samples"]


def test_a_merge_keeps_how_each_variable_was_made(study):
    whole, _, merged = study
    keys = ("window", "normalisation", "band", "stft_segment", "stft_hop")
    pick = lambda v: {n: {k: text(a[k]) for k in keys if k in a} for n, a in v.items()}
    assert pick(attributes(merged)[0]) == pick(attributes(whole)[0])


def test_speed_fields_are_stored_only_for_a_profile_some_case_runs(study, tmp_path):
    constant, _ = attributes(study[0])
    assert [n for n in constant if n.startswith("speed_")] == ["speed_profile"]
    ramp, _ = attributes(run_grid(tmp_path, "ramp", RAMP))
    assert sorted(n for n in ramp if n.startswith("speed_")) == [
        "speed_from",
        "speed_over",
        "speed_profile",
        "speed_to",
    ]


def test_shards_open_with_the_readme_call(study):
    import xarray as xr

    whole, parts, _ = study
    ds = xr.open_mfdataset(
        parts, engine="h5netcdf", decode_times=False, combine="nested", concat_dim="case",
        data_vars="minimal", coords="minimal", compat="override",
    ).sortby("case")
    with xr.open_dataset(whole, engine="h5netcdf", decode_times=False) as one:
        assert list(ds.case.values) == list(one.case.values)
        assert (ds.bearing_force_spectrum.values == one.bearing_force_spectrum.values).all()
