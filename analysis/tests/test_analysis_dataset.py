"""analysis/dataset.py: window counts and contents, splits by case (disjoint, seeded,
reproducible), labels aligned with windows, PyTorch only on request; on a synthetic
study and on the smoke study."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

from analysis.dataset import (SPLITS, StratifyWarning, make_splits, split_cases, stratified_counts, torch_dataset,
                              window_count, windows)
from analysis.studyfile import analysis_window, open_shards, open_study, select_cases

REPO = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("n, length, hop", [(100, 10, 5), (100, 10, 3), (10, 10, 1), (9, 10, 1), (101, 1, 1),
                                            (50, 7, 50)])
def test_window_count_formula_and_contents(n, length, hop):
    series = np.arange(n, dtype=float) ** 2
    got = windows(series, length, hop)
    expected = 0 if n < length else (n - length) // hop + 1
    assert window_count(n, length, hop) == expected
    assert got.shape == (expected, length)
    for k in range(expected):
        np.testing.assert_array_equal(got[k], series[k * hop : k * hop + length])
    if expected:  # the last window ends inside the series and another would not fit
        assert (expected - 1) * hop + length <= n < expected * hop + length


def test_window_arguments_are_checked():
    with pytest.raises(ValueError, match="hop 0"):
        window_count(10, 3, 0)


def synthetic_study(cases=20, samples=101, seed=0):
    """A flat study with `cases` cases, two channels whose values encode (case, sample),
    a string label, a numeric parameter, and one failed case."""
    rng = np.random.default_rng(seed)
    ids = rng.permutation(np.arange(100, 100 + cases)).astype("int32")  # file order is not id order
    k = np.arange(samples)
    a = ids[:, None] * 1000.0 + k[None, :]
    status = np.ones(cases, dtype="int8")
    status[3] = 2
    ds = xr.Dataset(
        {
            "slider_acceleration": (("case", "time"), a),
            "crank_moment": (("case", "time"), -a),
            "location": ("case", np.where(ids % 3 == 0, "crank_rod", "crank_ground").astype(object)),
            "fault": ("case", np.array(["none", "outer", "inner", "ball"], dtype=object)[ids % 4]),
            "rpm": ("case", ids * 10.0, {"studyrun_role": "parameter"}),
            "clearance": ("case", ids * 1e-6, {"studyrun_role": "parameter"}),
            "status": ("case", status),
        },
        coords={"case": ids, "time": k / 1000.0},
        attrs={"transient": 0.02, "sample_rate": 1000.0},
    )
    return ds


def test_synthetic_windows_labels_and_splits():
    ds = synthetic_study()
    length, hop = 16, 5
    splits = make_splits(ds, ["slider_acceleration", "crank_moment"], length, hop, labels=["location", "fault", "rpm"],
                         fractions=(0.6, 0.2, 0.2), seed=3)
    analysed = np.flatnonzero(analysis_window(ds))
    assert analysed[0] == 20 and analysed[-1] == 99  # transient 0.02 s at 1 kHz; the last sample left out
    per_case = (analysed.size - length) // hop + 1
    failed = int(ds["case"].values[3])
    seen = []
    for name in SPLITS:
        s = splits[name]
        cases = np.unique(s.case)
        seen.append(set(cases.tolist()))
        assert failed not in seen[-1]
        assert len(s) == per_case * cases.size == s.x.shape[0]
        assert s.x.shape[1:] == (2, length) and s.x.dtype == np.float32
        assert s.parameter_names == ["rpm", "clearance"]
        for w in range(len(s)):
            row = int(np.flatnonzero(ds["case"].values == s.case[w])[0])
            window = ds["slider_acceleration"].values[row, s.start[w] : s.start[w] + length]
            np.testing.assert_array_equal(s.x[w, 0], window)
            np.testing.assert_array_equal(s.x[w, 1], -window)
            # the value encodes its case and sample: the window is that case's, at that start
            assert s.x[w, 0, 0] == s.case[w] * 1000 + s.start[w]
            assert s.labels["location"][w] == ds["location"].values[row]
            assert s.labels["fault"][w] == ds["fault"].values[row]
            assert s.labels["rpm"][w] == 10.0 * s.case[w]
            assert s.classes["fault"][s.codes["fault"][w]] == s.labels["fault"][w]
            np.testing.assert_array_equal(s.parameters[w], [10.0 * s.case[w], 1e-6 * s.case[w]])
        assert set(s.start.tolist()) == set((analysed[0] + hop * np.arange(per_case)).tolist())
        assert "rpm" not in s.codes  # numeric labels are kept as values
    # no case in two splits, every ok case in one, sizes from the fractions
    assert not (seen[0] & seen[1]) and not (seen[0] & seen[2]) and not (seen[1] & seen[2])
    assert set.union(*seen) == set(ds["case"].values.tolist()) - {failed}
    assert [len(c) for c in seen] == [11, 4, 4]  # 19 ok cases: round(11.4), round(3.8), the rest
    # the classes are the file's, the same in every split
    assert list(splits["test"].classes["fault"]) == ["ball", "inner", "none", "outer"]


def test_whole_series_when_asked():
    ds = synthetic_study(cases=4)
    s = make_splits(ds, ["slider_acceleration"], 20, 20, labels=[], fractions=(1, 0, 0), analysed_only=False)
    assert len(s["train"]) == 3 * ((101 - 20) // 20 + 1) and len(s["validation"]) == 0 == len(s["test"])
    assert s["train"].start.min() == 0 and s["train"].x.shape == (15, 1, 20)


def test_split_is_reproducible_with_a_seed_and_independent_of_order():
    ids = np.arange(1000, 1050)
    a = split_cases(ids, (0.7, 0.1, 0.2), seed=11)
    b = split_cases(np.random.default_rng(0).permutation(ids), (0.7, 0.1, 0.2), seed=11)
    c = split_cases(ids, (0.7, 0.1, 0.2), seed=12)
    for name in SPLITS:
        np.testing.assert_array_equal(a[name], b[name])
    assert [a[n].size for n in SPLITS] == [35, 5, 10]
    assert not np.array_equal(a["train"], c["train"])
    ds = synthetic_study()
    x1 = make_splits(ds, ["crank_moment"], 8, 8, seed=5)
    x2 = make_splits(ds.isel(case=np.arange(ds.sizes["case"])[::-1]), ["crank_moment"], 8, 8, seed=5)
    for name in SPLITS:
        order = np.lexsort((x2[name].start, x2[name].case))
        np.testing.assert_array_equal(np.lexsort((x1[name].start, x1[name].case)), np.arange(len(x1[name])))
        np.testing.assert_array_equal(x1[name].x, x2[name].x[order])


def fault_study(counts, seed=0):
    """A synthetic study (`synthetic_study`'s channels) whose `fault` classes have the
    given numbers of cases, every case ok."""
    ds = synthetic_study(cases=sum(counts.values()), seed=seed)
    labels = np.concatenate([[name] * n for name, n in counts.items()]).astype(object)
    return ds.assign(fault=("case", labels), status=("case", np.ones(ds.sizes["case"], dtype="int8")))


def test_stratified_splits_hold_every_fault_class():
    """28 cases (4 healthy, 4 outer, 10 inner, 10 ball) in 70/15/15: the plain split of
    seed 0 leaves the healthy and outer classes out of validation; stratified by fault
    every split holds every class, each class cut by `stratified_counts`, and the cases
    of the plain split are the same set."""
    counts = {"none": 4, "outer": 4, "inner": 10, "ball": 10}
    ds = fault_study(counts)
    plain = make_splits(ds, ["crank_moment"], 16, 16, labels=["fault"], seed=0)
    assert not {"none", "outer"} & set(plain["validation"].labels["fault"])
    splits = make_splits(ds, ["crank_moment"], 16, 16, labels=["fault"], seed=0, stratify="fault")
    per_case = len(splits["train"]) // np.unique(splits["train"].case).size
    for k, name in enumerate(SPLITS):
        found = dict(zip(*np.unique(splits[name].labels["fault"], return_counts=True)))
        assert {c: n // per_case for c, n in found.items()} == \
            {c: int(stratified_counts(n, (0.7, 0.15, 0.15))[k]) for c, n in counts.items()}
    cases = [set(np.unique(splits[n].case).tolist()) for n in SPLITS]
    assert not (cases[0] & cases[1] or cases[0] & cases[2] or cases[1] & cases[2])
    assert set.union(*cases) == set(ds["case"].values.tolist())
    again = make_splits(ds.isel(case=np.arange(28)[::-1]), ["crank_moment"], 16, 16, labels=["fault"], seed=0,
                        stratify="fault")
    for name in SPLITS:
        np.testing.assert_array_equal(np.unique(again[name].case), np.unique(splits[name].case))


def test_stratified_counts_give_each_positive_split_a_case_first():
    assert stratified_counts(3, (0.7, 0.15, 0.15)).tolist() == [1, 1, 1]
    assert stratified_counts(10, (0.7, 0.15, 0.15)).tolist() == [7, 2, 1]
    assert stratified_counts(28, (0.7, 0.15, 0.15)).sum() == 28
    assert stratified_counts(4, (0.5, 0.5, 0.0)).tolist() == [2, 2, 0]


def test_a_class_too_small_for_every_split_is_named():
    ds = fault_study({"none": 2, "outer": 6, "inner": 6})
    with pytest.warns(StratifyWarning, match=r"needs 3 cases to be in every split; none has 2 cases, none in test"):
        splits = make_splits(ds, ["crank_moment"], 16, 16, labels=["fault"], stratify="fault")
    assert "none" in set(splits["train"].labels["fault"]) and "none" in set(splits["validation"].labels["fault"])
    with pytest.raises(ValueError, match=r"stratify \['defect_race'\] are not per-case variables"):
        make_splits(ds, ["crank_moment"], 16, 16, stratify="defect_race")


def test_bad_requests_are_named():
    ds = synthetic_study()
    with pytest.raises(ValueError, match=r"channels \['bearing_force'\] are not series of the file; available: "
                                         r"\['crank_moment', 'slider_acceleration'\]"):
        make_splits(ds, ["bearing_force"], 8, 4)
    with pytest.raises(ValueError, match=r"labels \['ball_count'\] are not per-case variables"):
        make_splits(ds, ["crank_moment"], 8, 4, labels=["ball_count"])
    with pytest.raises(ValueError, match="summing to 1"):
        make_splits(ds, ["crank_moment"], 8, 4, fractions=(0.5, 0.2, 0.2))
    ds["crank_moment"][0, 50] = np.nan
    with pytest.raises(ValueError, match=rf"NaN in cases \[{int(ds['case'][0])}\]"):
        make_splits(ds, ["crank_moment"], 8, 4, fractions=(1, 0, 0))


def test_import_does_not_import_torch():
    code = "import sys; import analysis.dataset; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_torch_missing_gives_a_clear_error(monkeypatch):
    splits = make_splits(synthetic_study(), ["crank_moment"], 8, 4)
    monkeypatch.setitem(sys.modules, "torch", None)  # `import torch` raises ImportError
    with pytest.raises(ImportError, match="torch_dataset needs PyTorch, which is not installed"):
        torch_dataset(splits["train"], "location")


def test_torch_dataset_items():
    pytest.importorskip("torch")
    splits = make_splits(synthetic_study(), ["crank_moment"], 8, 4, labels=["fault", "rpm"])
    s = splits["train"]
    data = torch_dataset(s, "fault")
    assert len(data) == len(s)
    x, y = data[5]
    np.testing.assert_array_equal(x.numpy(), s.x[5])
    assert int(y) == s.codes["fault"][5]
    assert float(torch_dataset(s, "rpm")[5][1]) == s.labels["rpm"][5]


def test_smoke_study_windows(smoke):
    rows = select_cases(smoke, location="crank_rod")
    ds = smoke.isel(case=rows)
    length, hop = 128, 64
    splits = make_splits(ds, ["slider_acceleration", "bearing_force"], length, hop,
                         labels=["location", "ball_count", "waviness_amplitude"], fractions=(0.5, 0.25, 0.25), seed=1)
    analysed = np.flatnonzero(analysis_window(ds))
    per_case = (analysed.size - length) // hop + 1
    cases = [set(np.unique(splits[n].case).tolist()) for n in SPLITS]
    assert sum(len(c) for c in cases) == int((ds["status"].values == 1).sum()) == rows.size
    assert not (cases[0] & cases[1]) and not (cases[0] & cases[2]) and not (cases[1] & cases[2])
    for name in SPLITS:
        s = splits[name]
        assert len(s) == per_case * len(cases[SPLITS.index(name)])
        assert s.parameters.shape == (len(s), len(s.parameter_names)) and "clearance" in s.parameter_names
        for w in (0, len(s) // 2, len(s) - 1):
            row = int(np.flatnonzero(ds["case"].values == s.case[w])[0])
            for c, channel in enumerate(s.channels):
                expected = ds[channel].values[row, s.start[w] : s.start[w] + length].astype(np.float32)
                np.testing.assert_array_equal(s.x[w, c], expected)
            assert s.labels["ball_count"][w] == ds["ball_count"].values[row]
            assert s.labels["location"][w] == "crank_rod"
            k = s.parameter_names.index("waviness_amplitude")
            assert s.parameters[w, k] == s.labels["waviness_amplitude"][w] or np.isnan(s.parameters[w, k])
    with pytest.raises(ValueError, match="NaN in cases"):  # the ideal cases have no bearing force
        make_splits(smoke, ["bearing_force"], length, hop)


def test_shards_split_as_the_merged_file(shard_paths, merged_path):
    with open_shards(shard_paths, lazy=False) as shards, open_study(merged_path) as merged:
        a = make_splits(shards, ["slider_acceleration"], 200, 100, seed=9)
        b = make_splits(merged, ["slider_acceleration"], 200, 100, seed=9)
    for name in SPLITS:
        np.testing.assert_array_equal(a[name].case, b[name].case)
        np.testing.assert_array_equal(a[name].x, b[name].x)
