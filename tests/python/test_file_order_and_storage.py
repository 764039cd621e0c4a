"""What docs/result-file.md says of the variables' order and storage, on a file with
every dimension (replicates, whole revolutions, order spectra, envelope analysis):

- the coordinates `case`, `time`, `frequency`, `reference` come first; `replicate`,
  `revolution` and `order` each sit just before the first variable over them;
- the series, spectra and reference series are chunked one row per chunk (filtered
  with the default compression); the `[case, replicate]`, `[case, revolution]` and
  `[case, order]` arrays and the 1-D variables are contiguous.

Environment: STUDYRUN_BIN (the binary runs the study written here); else skip.
"""

import pytest

from study_run import opened_run

GRID = """name: layout
duration: 0.25
sample_rate: 4000
transient: "0.05 s"
rpm: 600
replicates: {count: 2, perturbation: "1 nm", seed: 1}
spectra: {orders: true}
envelope: {channels: [bearing_force], band: auto}
grid:
  location: [crank_ground, crank_rod]
"""


@pytest.fixture(scope="module")
def f(tmp_path_factory):
    yield from opened_run(tmp_path_factory, "layout", GRID)


def dims(var):
    """The names of the dimension scales attached to `var` (netCDF-4 dimensions)."""
    return tuple(d[0].name.lstrip("/") for d in var.dims)


def test_the_late_coordinates_sit_before_their_first_variable(f):
    names = list(f)
    assert names[:4] == ["case", "time", "frequency", "reference"]
    for coordinate in ("replicate", "revolution", "order"):
        assert coordinate in f, coordinate
        first = next(k for k, n in enumerate(names) if f[n].ndim == 2 and dims(f[n])[1] == coordinate)
        assert names.index(coordinate) == first - 1, (coordinate, names[first - 1 : first + 1])
        # Mid-file: after the per-case metrics, not among the first coordinates.
        assert names.index(coordinate) > names.index("wall_time")


def test_series_and_spectra_are_chunked_by_row_and_the_other_2d_arrays_contiguous(f):
    kinds = {"time": 0, "frequency": 0, "replicate": 0, "revolution": 0, "order": 0}
    for name in f:
        var = f[name]
        if var.ndim == 1:
            assert var.chunks is None, name
            continue
        first, second = dims(var)
        kinds[second] += 1
        if second in ("time", "frequency"):
            assert first in ("case", "reference"), name
            assert var.chunks == (1, var.shape[1]), (name, var.chunks)
            assert var.compression == "gzip" and var.shuffle, name
        else:
            assert first == "case" and second in ("replicate", "revolution", "order"), name
            assert var.chunks is None and var.compression is None, (name, var.chunks)
    assert all(count > 0 for count in kinds.values()), kinds
    assert any(name.endswith("_envelope_spectrum") for name in f)
