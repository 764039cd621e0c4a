"""Shared fixtures of the analysis tests.

Environment:
  STUDYRUN_SMOKE_FILE  the result of `studyrun studies/smoke.yaml` (.ci/run makes it); unset: skip.
  STUDYRUN_PAPER_FILE  optional, the result of `studyrun studies/paper.yaml`; unset: skip those tests.
  STUDYRUN_SHARD_FILES optional, colon-separated shard files of the smoke study
                       (`studyrun studies/smoke.yaml --shard K/N`); unset: skip those tests.
  STUDYRUN_MERGED_FILE optional, `studyrun merge` of those shards; unset: skip that comparison.
  STUDYRUN_DIAGNOSIS_FILE optional, the result of `studyrun studies/diagnosis.yaml`; unset: the
                       tests run that study with STUDYRUN_BIN (the studyrun binary), or skip.
  STUDYRUN_BIN         the studyrun binary: runs the diagnosis study decimated by 2 (and other
                       small studies the tests write); unset: skip those tests.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402

REPO = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(REPO))  # `import analysis...` from any working directory

from analysis.studyfile import open_study  # noqa: E402


def study_path(variable, how):
    """The absolute path of the study file named by the environment `variable` (relative
    to the working directory), or skip saying `how` to make it."""
    value = os.environ.get(variable)
    if not value:
        pytest.skip(f"{variable} is not set: run `{how}` and point it at the file")
    assert os.path.isfile(value), f"{variable}={value} does not exist"
    return os.path.abspath(value)


@pytest.fixture(scope="package")
def smoke_path():
    return study_path("STUDYRUN_SMOKE_FILE", "studyrun studies/smoke.yaml -o smoke.h5")


@pytest.fixture(scope="package")
def paper_path():
    return study_path("STUDYRUN_PAPER_FILE", "studyrun studies/paper.yaml -o paper.h5")


@pytest.fixture(scope="package")
def shard_paths():
    value = os.environ.get("STUDYRUN_SHARD_FILES")
    if not value:
        pytest.skip(
            "STUDYRUN_SHARD_FILES is not set: run `studyrun studies/smoke.yaml --shard 1/2 -o s1.h5` "
            "(and 2/2) and set it to s1.h5:s2.h5"
        )
    paths = [p for p in value.split(os.pathsep) if p]
    for p in paths:
        assert os.path.isfile(p), f"STUDYRUN_SHARD_FILES: {p} does not exist"
    return [os.path.abspath(p) for p in paths]


@pytest.fixture(scope="package")
def merged_path():
    return study_path("STUDYRUN_MERGED_FILE", "studyrun merge merged.h5 s1.h5 s2.h5")


@pytest.fixture(scope="package")
def diagnosis_path(tmp_path_factory):
    if os.environ.get("STUDYRUN_DIAGNOSIS_FILE"):
        return study_path("STUDYRUN_DIAGNOSIS_FILE", "studyrun studies/diagnosis.yaml -o diagnosis.h5")
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("neither STUDYRUN_DIAGNOSIS_FILE nor STUDYRUN_BIN is set")
    out = tmp_path_factory.mktemp("diagnosis") / "diagnosis.h5"
    subprocess.run([binary, str(REPO / "studies/diagnosis.yaml"), "-o", str(out), "-j", "2", "--force", "-q"],
                   check=True)
    return str(out)


@pytest.fixture(scope="package")
def decimated_diagnosis(tmp_path_factory):
    """studies/diagnosis.yaml with `output: {decimate: 2}` (series stored at 10 kHz of the
    20 kHz output), run with STUDYRUN_BIN, loaded."""
    binary = os.environ.get("STUDYRUN_BIN")
    if not binary:
        pytest.skip("STUDYRUN_BIN is not set")
    folder = tmp_path_factory.mktemp("decimated")
    grid = folder / "decimated.yaml"
    grid.write_text((REPO / "studies/diagnosis.yaml").read_text() + "output: {decimate: 2}\n")
    out = folder / "decimated.h5"
    subprocess.run([binary, str(grid), "-o", str(out), "-j", "2", "--force", "-q"], check=True)
    with open_study(out) as ds:
        yield ds.load()


@pytest.fixture(scope="package")
def diagnosis(diagnosis_path):
    with open_study(diagnosis_path) as ds:
        yield ds.load()


@pytest.fixture(scope="package")
def smoke(smoke_path):
    with open_study(smoke_path) as ds:
        yield ds.load()


@pytest.fixture(scope="package")
def paper(paper_path):
    with open_study(paper_path) as ds:
        yield ds


@pytest.fixture(scope="package")
def installed(tmp_path_factory):
    """The package installed from a copy of pyproject.toml and analysis/ (so the build
    leaves nothing in the repository) into a target folder: (site folder, bin folder)."""
    root = tmp_path_factory.mktemp("install")
    source = root / "source"
    shutil.copytree(REPO / "analysis", source / "analysis", ignore=shutil.ignore_patterns("tests", "__pycache__"))
    shutil.copy(REPO / "pyproject.toml", source)
    (source / "docs").mkdir()
    shutil.copy(REPO / "docs" / "analysis.md", source / "docs")
    site = root / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation", "--no-index",
                    "--target", str(site), str(source)], check=True, capture_output=True)
    return site, site / "bin"


def check_png(path, min_kb=15, min_pixels=300):
    """`path` is a PNG of more than `min_kb` KB that matplotlib reads back as an image at
    least `min_pixels` wide and high with more than one colour; returns its pixels."""
    assert path.is_file(), path
    assert path.stat().st_size > min_kb * 1024, f"{path}: {path.stat().st_size} bytes"
    image = mpimg.imread(path)
    assert image.ndim == 3 and image.shape[2] in (3, 4), image.shape
    assert image.shape[0] >= min_pixels and image.shape[1] >= min_pixels, image.shape
    assert np.ptp(image[..., :3]) > 0.5, "the image is blank"
    return image


@pytest.fixture
def assert_png():
    """The PNG check `check_png`."""
    return check_png


@pytest.fixture
def drawn(monkeypatch):
    """Every figure the plots of `figures` and `diagnosis_figures` save, kept open and
    drawn, for the tests to read: a list filled as they save."""
    from analysis import diagnosis_figures, figures

    kept = []

    def keeper(save):
        def keep(fig, out, dpi):
            fig.canvas.draw()
            kept.append(fig)
            return save(fig, out, dpi)

        return keep

    for module in (figures, diagnosis_figures):
        monkeypatch.setattr(module, "_save", keeper(module._save))
    return kept
