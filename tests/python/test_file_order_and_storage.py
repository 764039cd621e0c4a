"""What docs/result-file.md says of the variables' order and storage, on a file with
every dimension (replicates, whole revolutions, order spectra, envelope analysis):

- the coordinates `case`, `time`, `frequency`, `reference` come first; `replicate`,
  `revolution` and `order` each sit just before the first variable over them;
- the series, spectra (and spectral kurtoses, over `sk_frequency`) and reference
  series are chunked one row per chunk (filtered
  with the default compression); the `[case, replicate]`, `[case, revolution]` and
  `[case, order]` arrays and the 1-D numeric variables are chunked in whole rows of up
  to 65 536 values, uncompressed;
- every numeric variable carries the Fletcher-32 checksum filter; string variables
  (variable-length, which take no filter) carry `studyrun_crc32` instead.

Environment: STUDYRUN_BIN (the binary runs the study written here); else skip.
"""

import numpy as np
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


WHOLE_CHUNK_ELEMENTS = 65536


def whole_rows(shape):
    """The chunk shape docs/result-file.md gives a variable written whole."""
    cols = int(np.prod(shape[1:], dtype=np.int64)) if len(shape) > 1 else 1
    rows = min(max(WHOLE_CHUNK_ELEMENTS // max(cols, 1), 1), max(shape[0], 1))
    return (rows, *shape[1:])


def test_series_and_spectra_are_chunked_by_row_and_the_others_in_whole_rows(f):
    kinds = {"time": 0, "frequency": 0, "sk_frequency": 0, "replicate": 0, "revolution": 0, "order": 0}
    for name in f:
        var = f[name]
        if var.dtype.kind == "O":
            assert var.chunks is None and "studyrun_crc32" in var.attrs, name
            continue
        assert var.fletcher32, name
        if var.ndim == 1:
            assert var.chunks == whole_rows(var.shape) and var.compression is None, (name, var.chunks)
            continue
        first, second = dims(var)
        kinds[second] += 1
        if second in ("time", "frequency", "sk_frequency"):
            assert first in ("case", "reference"), name
            assert var.chunks == (1, var.shape[1]), (name, var.chunks)
            assert var.compression == "gzip" and var.shuffle, name
        else:
            assert first == "case" and second in ("replicate", "revolution", "order"), name
            assert var.chunks == whole_rows(var.shape) and var.compression is None, (name, var.chunks)
    assert all(count > 0 for count in kinds.values()), kinds
    assert any(name.endswith("_envelope_spectrum") for name in f)
