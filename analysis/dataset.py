"""Machine-learning data sets from a study file: fixed-length windows of chosen series
with each case's labels and parameters, split into train, validation and test by case.

    from analysis.dataset import make_splits, torch_dataset
    splits = make_splits(open_study("study.h5"), ["slider_acceleration"], length=256, hop=128,
                         labels=["location"], fractions=(0.7, 0.15, 0.15), seed=0)
    splits["train"].x          # [windows, channels, length]: NumPy, channels first
    splits["train"].labels["location"], splits["train"].codes["location"]
    torch_dataset(splits["train"], target="location")   # optional, needs PyTorch

A series of N samples gives ⌊(N − L)/H⌋ + 1 windows of length L at hop H (none when
N < L), starting at samples 0, H, 2H, … of the series: by default of its analysed
window (transient ≤ t < duration, the samples the file's metrics use). Cases are
assigned to splits whole, so no case is in two splits: the case ids (the file's `case`
coordinate, so a merged file and its shards split alike) are shuffled by a generator
seeded with `seed`, then cut at the fractions; with `stratify="fault"` each fault class
is cut on its own, so that every class is in every split when it has a case for each.
Only `ok` cases are used.

Windows are cut from the series as stored: a file whose grid has `output.decimate: k`
stores every k-th sample (rate `series_sample_rate`), so L and H count stored samples.
A file without series (`output.series: none`) has nothing to window: `make_splits`
says so.

`make_joint_splits` windows several studies together, e.g. a simulated study and a
study of measured recordings (docs/grid-file.md, Recordings), each through its own
series, into one data set whose labels share one class list.

PyTorch is imported only by `torch_dataset`, never on import of this module, and is
not a requirement of the analysis package.
"""

import warnings

import numpy as np

from analysis.studyfile import analysis_window, series_rate

SPLITS = ("train", "validation", "test")
"""The splits, in the order of `fractions`."""


def window_count(n, length, hop):
    """Windows of `length` samples at `hop` in a series of `n` samples: ⌊(n − length)/hop⌋ + 1, 0 if n < length."""
    if length < 1 or hop < 1:
        raise ValueError(f"window length {length} and hop {hop} must be at least 1")
    return 0 if n < length else (n - length) // hop + 1


def windows(series, length, hop):
    """The windows of the last axis of `series` ([..., n] → [..., windows, length]), a
    read-only view: window k is `series[..., k*hop : k*hop + length]`."""
    series = np.asarray(series)
    count = window_count(series.shape[-1], length, hop)
    if count == 0:
        return np.empty(series.shape[:-1] + (0, length), dtype=series.dtype)
    view = np.lib.stride_tricks.sliding_window_view(series, length, axis=-1)
    return view[..., : (count - 1) * hop + 1 : hop, :]


def _check_fractions(fractions):
    """The three split fractions as floats; ValueError unless non-negative and summing to 1."""
    fractions = tuple(float(f) for f in fractions)
    if len(fractions) != 3 or min(fractions) < 0 or abs(sum(fractions) - 1) > 1e-9:
        raise ValueError(f"fractions {fractions}: expected three non-negative numbers (train, validation, test) "
                         "summing to 1")
    return fractions


def split_cases(case_ids, fractions=(0.7, 0.15, 0.15), seed=0):
    """{split: sorted case ids}: the distinct `case_ids` shuffled by
    `numpy.random.default_rng(seed)` (from sorted order, so the file's order does not
    matter) and cut into train, validation and test of round(fraction × cases) cases
    (test takes the rest). `fractions` are three non-negative numbers summing to 1."""
    fractions = _check_fractions(fractions)
    ids = np.unique(np.asarray(case_ids))
    shuffled = np.random.default_rng(seed).permutation(ids)
    n_train = round(fractions[0] * ids.size)
    n_val = min(round(fractions[1] * ids.size), ids.size - n_train)
    cuts = np.split(shuffled, [n_train, n_train + n_val])
    return {name: np.sort(part) for name, part in zip(SPLITS, cuts)}


class StratifyWarning(UserWarning):
    """A class of the stratifying label has too few cases to be in every split."""


def stratified_counts(count, fractions):
    """How many of a class's `count` cases go to train, validation and test: one to each
    split of positive fraction while the count lasts (in that order), then each further
    case to the split furthest below its share fraction × count (the earlier on a tie),
    so that every class is in every split that has a share whenever it has a case for
    each."""
    target = np.asarray(fractions, dtype=float) * count
    counts = np.zeros(3, dtype=int)
    counts[np.flatnonzero(target > 0)[:count]] = 1
    for _ in range(count - counts.sum()):
        counts[int(np.argmax(target - counts))] += 1
    return counts


def stratified_split(case_ids, classes, fractions=(0.7, 0.15, 0.15), seed=0):
    """{split: sorted case ids} with each class of `classes` (one value per case id,
    e.g. the `fault` label) split on its own: its ids shuffled by one
    `numpy.random.default_rng(seed)` (classes in sorted order, each from sorted ids) and
    cut at `stratified_counts`, so that every class is in every split of positive
    fraction when it has a case for each. A class with fewer cases than that is put in
    the first splits and a StratifyWarning names it, its count and the splits it misses."""
    fractions = _check_fractions(fractions)
    ids = np.asarray(case_ids)
    classes = np.asarray(classes)
    if ids.shape != classes.shape or np.unique(ids).size != ids.size:
        raise ValueError(f"{ids.size} case ids (each once) need one class each, got {classes.size}")
    rng = np.random.default_rng(seed)
    parts = {name: [] for name in SPLITS}
    short = []
    for value in np.unique(classes):
        members = rng.permutation(np.sort(ids[classes == value]))
        counts = stratified_counts(members.size, fractions)
        for name, chunk in zip(SPLITS, np.split(members, np.cumsum(counts)[:2])):
            parts[name].append(chunk)
        missing = [name for name, f, c in zip(SPLITS, fractions, counts) if f > 0 and c == 0]
        if missing:
            short.append(f"{value!s} has {members.size} case{'s' if members.size != 1 else ''}, "
                         f"none in {' or '.join(missing)}")
    if short:
        need = int((np.asarray(fractions) > 0).sum())
        warnings.warn(f"stratified split: every class needs {need} cases to be in every split; "
                      + "; ".join(short), StratifyWarning, stacklevel=3)
    return {name: np.sort(np.concatenate(chunks)).astype(ids.dtype) for name, chunks in parts.items()}


class WindowSet:
    """The windows of one split, all arrays along the first axis (one row per window).

    `x`: [windows, channels, length] series values in the file's units (channels in
    `channels` order); `case`: the case id of each window; `start`: the sample index
    of its first value within the series (`time[start]` is its start time);
    `labels`: {name: [windows]} each case's value of the named per-case variables (as
    stored: strings or numbers); `codes`: {name: [windows] int64} for the string labels,
    the index into `classes[name]` (the sorted values over all the file's cases, so
    codes agree between splits); `parameters`: [windows, P] the numeric per-case
    parameters named in `parameter_names` (file units).
    """

    def __init__(self, x, case, start, labels, codes, classes, parameters, parameter_names, channels):
        self.x = x
        self.case = case
        self.start = start
        self.labels = labels
        self.codes = codes
        self.classes = classes
        self.parameters = parameters
        self.parameter_names = list(parameter_names)
        self.channels = list(channels)

    def __len__(self):
        return self.x.shape[0]


def _per_case(ds, names, what):
    """Check every name is a [case] variable of `ds`, else say which are available."""
    bad = [n for n in names if n not in ds or ds[n].dims != ("case",)]
    if bad:
        available = sorted(v for v in ds.data_vars if ds[v].dims == ("case",))
        raise ValueError(f"{what} {bad} are not per-case variables of the file; available: {available}")


def _default_parameters(ds):
    """The numeric per-case parameter variables (`studyrun_role` = parameter)."""
    return [v for v in ds.data_vars
            if ds[v].attrs.get("studyrun_role") == "parameter" and ds[v].dims == ("case",)
            and ds[v].dtype.kind in "fiu"]


def make_splits(ds, channels, length, hop, labels=("location",), parameters=None,
                fractions=(0.7, 0.15, 0.15), seed=0, analysed_only=True, dtype=np.float32, stratify=None):
    """{split: WindowSet} for "train", "validation" and "test" from the flat study `ds`.

    `channels`: series (`[case, time]` variables) stacked as the windows' channels;
    `length`, `hop`: window length L and hop H in samples; `labels`: per-case variables
    carried with each window (e.g. location, any parameter, a fault label); `parameters`:
    numeric per-case variables as the `parameters` array (default: every numeric
    parameter of the file); `fractions`, `seed`: the split (`split_cases`);
    `stratify`: a per-case variable (e.g. "fault") whose every value is put in every
    split when it has enough cases (`stratified_split`, which warns naming a class that
    has not);
    `analysed_only`: window the analysed window (transient ≤ t < duration) rather than
    the whole series; `dtype`: of `x`.

    Failed and pending cases are left out. Raises ValueError on an unknown channel,
    label or parameter (naming the ones available), or NaN in a chosen channel of an ok
    case (e.g. `bearing_force` of an `ideal` case: select the cases first).
    """
    channels, labels = list(channels), list(labels)
    if "time" not in ds.dims:
        raise ValueError("the file stores no series (its grid file has `output.series: none`), and windows "
                         f"need them: run the study with `output.series` naming {channels or 'the series'}")
    bad = [c for c in channels if c not in ds or ds[c].dims != ("case", "time")]
    if not channels or bad:
        available = sorted(v for v in ds.data_vars if ds[v].dims == ("case", "time"))
        raise ValueError(f"channels {bad or channels} are not series of the file; available: {available}")
    _per_case(ds, labels, "labels")
    parameters = _default_parameters(ds) if parameters is None else list(parameters)
    _per_case(ds, parameters, "parameters")
    window_count(ds.sizes["time"], length, hop)  # checks length and hop

    classes = {n: np.unique(ds[n].values) for n in labels if ds[n].dtype.kind in "USO"}
    ok = np.flatnonzero(ds["status"].values == 1) if "status" in ds else np.arange(ds.sizes["case"])
    mask = analysis_window(ds) if analysed_only else np.ones(ds.sizes["time"], dtype=bool)
    time_index = np.flatnonzero(mask)
    per_series = window_count(time_index.size, length, hop)
    starts = time_index[0] + hop * np.arange(per_series) if per_series else np.empty(0, dtype=int)

    # Each chosen variable read once, for the ok cases: series [cases, channels, samples].
    sub = ds.isel(case=ok)
    ids = sub["case"].values
    series = np.stack([sub[c].values[:, mask] for c in channels], axis=1)
    nan_cases = ids[np.isnan(series).any(axis=(1, 2))]
    if nan_cases.size:
        raise ValueError(f"the channels {channels} hold NaN in cases {nan_cases.tolist()} "
                         "(ideal cases without a bearing?); select the cases first")
    case_labels = {n: sub[n].values for n in labels}
    case_params = np.column_stack([sub[p].values.astype(float) for p in parameters]) if parameters else \
        np.empty((ids.size, 0))
    position = {int(i): k for k, i in enumerate(ids)}

    out = {}
    if stratify is None:
        assignment = split_cases(ids, fractions, seed)
    else:
        _per_case(ds, [stratify], "stratify")
        assignment = stratified_split(ids, np.array([str(v) for v in sub[stratify].values]), fractions, seed)
    for name, cases in assignment.items():
        rows = np.array([position[int(c)] for c in cases], dtype=int)
        # [cases, channels, windows, L] -> [cases, windows, channels, L] -> [cases * windows, channels, L]
        x = windows(series[rows], length, hop).transpose(0, 2, 1, 3).reshape(-1, len(channels), length)
        label_values = {n: np.repeat(v[rows], per_series) for n, v in case_labels.items()}
        codes = {n: np.searchsorted(classes[n], label_values[n]).astype(np.int64) for n in classes}
        out[name] = WindowSet(x.astype(dtype), np.repeat(cases, per_series), np.tile(starts, rows.size),
                              label_values, codes, classes, np.repeat(case_params[rows], per_series, axis=0),
                              parameters, channels)
    return out


def make_joint_splits(studies, length, hop, labels=("fault",), fractions=(0.7, 0.15, 0.15), seed=0,
                      analysed_only=True, dtype=np.float32, stratify=None):
    """{split: WindowSet} of several studies windowed together, labels aligned.

    `studies`: (name, ds, channel) triples, e.g. ("simulated", sim, "acc") and
    ("measured", rec, "vibration"): each study's windows are cut from its own series
    `channel` as `make_splits` cuts them (its cases split on their own, so each study
    is in every split), then stacked, the studies in the given order. The result's one
    channel is named after each study's series joined by `|`; its labels are `labels`
    (per-case variables every study has, e.g. `fault`) and `study` (the name), their
    classes the union over the studies, so that a code means one class whichever
    study a window comes from; `case` holds each window's case id in its own study.
    No parameters are carried (the studies' parameters differ). Raises ValueError when
    the studies' series are sampled at different rates (a window of L samples would
    not span one time), and as `make_splits` does.
    """
    studies = list(studies)
    if not studies:
        raise ValueError("no study to window")
    rates = {name: series_rate(ds) for name, ds, _ in studies}
    if len(set(rates.values())) > 1:
        raise ValueError(f"the studies' series are sampled at different rates {rates} (Hz): windows of "
                         f"{length} samples would span different times; run them at one sample rate")
    parts = [(name, make_splits(ds, [channel], length, hop, labels=labels, parameters=[], fractions=fractions,
                                seed=seed, analysed_only=analysed_only, dtype=dtype, stratify=stratify))
             for name, ds, channel in studies]
    channel = "|".join(channel for _, _, channel in studies)
    classes = {n: np.unique(np.concatenate([p[SPLITS[0]].classes[n] for _, p in parts]))
               for n in parts[0][1][SPLITS[0]].classes}
    classes["study"] = np.unique([name for name, _, _ in studies])
    out = {}
    for split in SPLITS:
        sets = [(name, p[split]) for name, p in parts]
        values = {n: np.concatenate([w.labels[n] for _, w in sets]) for n in labels}
        values["study"] = np.concatenate([np.full(len(w), name) for name, w in sets])
        codes = {n: np.searchsorted(classes[n], values[n]).astype(np.int64) for n in classes}
        out[split] = WindowSet(np.concatenate([w.x for _, w in sets]), np.concatenate([w.case for _, w in sets]),
                               np.concatenate([w.start for _, w in sets]), values, codes, classes,
                               np.empty((sum(len(w) for _, w in sets), 0)), [], [channel])
    return out


def torch_dataset(windowset, target):
    """A `torch.utils.data.Dataset` over one split: item k is (x, y) with x the float32
    tensor [channels, length] of window k and y its `target` label (the int64 class
    code for a string label, else the float32 value). Imports PyTorch here; raises
    ImportError saying so if it is not installed."""
    try:
        import torch
        from torch.utils.data import Dataset
    except ImportError as e:
        raise ImportError(
            "torch_dataset needs PyTorch, which is not installed (it is not in analysis/requirements.txt): "
            "install it (`pip install torch`) or use the NumPy arrays of the WindowSet"
        ) from e
    if target not in windowset.labels:
        raise ValueError(f"target {target!r} is not one of the labels {sorted(windowset.labels)}")
    x = torch.from_numpy(np.ascontiguousarray(windowset.x, dtype=np.float32))
    if target in windowset.codes:
        y = torch.from_numpy(windowset.codes[target])
    else:
        y = torch.from_numpy(np.asarray(windowset.labels[target], dtype=np.float32))

    class Windows(Dataset):
        """The windows of one split as (x, y) tensors."""

        def __len__(self):
            return x.shape[0]

        def __getitem__(self, k):
            return x[k], y[k]

    return Windows()
