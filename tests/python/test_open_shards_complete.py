"""`analysis.studyfile.open_shards` checks that the shards are the whole study, as
`studyrun merge` does: a missing shard is refused naming it, a file given twice is
refused, and `partial=True` opens the files given alone.

Environment: STUDYRUN_BIN (the binary runs the study written here in three shards);
else skip.
"""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))

from analysis.studyfile import StudyFileError, _has_dask, open_shards  # noqa: E402
from study_run import studyrun_binary  # noqa: E402

GRID = """name: sharded
duration: 0.03
sample_rate: 5000
transient: "0.01 s"
grid:
  location: [ideal, crank_ground, crank_rod]
  ball_count: [8, 9]
"""
LAZY = [
    pytest.param(False, id="eager"),
    pytest.param(True, id="dask", marks=pytest.mark.skipif(not _has_dask(), reason="dask is not installed")),
]


@pytest.fixture(scope="module")
def shards(tmp_path_factory):
    """Shards 1/3, 2/3 and 3/3 of a six-case study (ids 0 3, 1 4, 2 5)."""
    binary = studyrun_binary()
    d = tmp_path_factory.mktemp("shards")
    grid = d / "sharded.yaml"
    grid.write_text(GRID)
    paths = []
    for k in (1, 2, 3):
        out = d / f"part_{k}.h5"
        subprocess.run([binary, str(grid), "--shard", f"{k}/3", "-o", str(out), "-q"], check=True)
        paths.append(str(out))
    return paths


@pytest.mark.parametrize("lazy", LAZY)
def test_all_shards_open_as_the_study(shards, lazy):
    with open_shards(shards[::-1], lazy=lazy) as ds:
        np.testing.assert_array_equal(ds["case"].values, np.arange(6))
        assert ds.attrs["file_cases"] == ds.attrs["study_cases"] == 6


@pytest.mark.parametrize("lazy", LAZY)
def test_a_missing_shard_is_refused_naming_it(shards, lazy):
    with pytest.raises(ValueError, match=r"the files hold 4 of the study's 6 cases: shard 2/3 is missing "
                                         r"\(given: part_1\.h5 = 1/3, part_3\.h5 = 3/3\); pass every shard, "
                                         r"or partial=True"):
        open_shards([shards[0], shards[2]], lazy=lazy)
    with pytest.raises(ValueError, match=r"2 of the study's 6 cases: shard 1/3, 3/3 are missing"):
        open_shards([shards[1]], lazy=lazy)
    with pytest.raises(ValueError, match="shard 3/3 is missing"):
        open_shards(str(Path(shards[0]).parent / "part_[12].h5"), lazy=lazy)


@pytest.mark.parametrize("lazy", LAZY)
def test_partial_opens_the_shards_given(shards, lazy):
    with open_shards([shards[2], shards[0]], lazy=lazy, partial=True) as ds:
        np.testing.assert_array_equal(ds["case"].values, [0, 2, 3, 5])
        assert ds.attrs["file_cases"] == 4 and ds.attrs["study_cases"] == 6
        assert ds.attrs["shard"] == ""


def test_a_file_given_twice_is_refused(shards):
    twice = str(Path(shards[0]).parent / "." / Path(shards[0]).name)
    with pytest.raises(ValueError, match=r"part_1\.h5 is given twice"):
        open_shards([shards[0], shards[1], shards[2], twice])


def test_a_missing_or_non_hdf5_file_is_refused(shards, tmp_path):
    with pytest.raises(StudyFileError, match=r"part_9\.h5: no such file"):
        open_shards([shards[0], str(tmp_path / "part_9.h5")])
    text = tmp_path / "part_2.h5"
    text.write_text("not HDF5")
    with pytest.raises(StudyFileError, match="not an HDF5 file"):
        open_shards([shards[0], str(text), shards[2]])
