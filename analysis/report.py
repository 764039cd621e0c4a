"""Render the figures of a study file into a directory, with an index.md that shows
them, one caption line each.

    python analysis/report.py STUDY.h5 OUTDIR

Metrics views (heatmaps over the grid axes), then for every combination of bearing
location, speed, waviness amplitude (and any other grid axis) the time-series
panels per ball count with the ideal mechanism, and the amplitude spectra with the
bearing's characteristic frequencies. Then the diagnosis figures (docs/diagnosis.md):
the journal centre's orbits, envelope spectra with the fault lines per fault label, a
spectrogram, a waterfall over the crank speed, order spectra of run-ups, the fast
kurtogram and heatmaps of the condition indicators. What a study cannot show (no
bearing cases, no grid axis that varies, cases not told apart by the grid, no
`envelope:`, no varying speed) is skipped and said so in the index.

A case whose speed profile runs as a constant speed (a ramp from a speed to the same
speed, a sine of amplitude 0: docs/model.md §1.5) is shown at that speed, with its
panels and spectra. A bearing without a defect (`fault` none, or a zero-depth defect)
is shown as healthy: `defect_race` none and its other defect parameters not
applicable; the metrics views put it in the `none` row beside the defects of every
defect width (angle, depth) and the diagnosis figures in every condition it shares
with them.

A missing or non-HDF5 file, or a `--select` that is malformed or matches no case,
ends the program with a one-line message.
"""

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from analysis import figures  # noqa: E402
from analysis import diagnosis_figures as dfig  # noqa: E402
from analysis.studyfile import (  # noqa: E402
    constant_rpm,
    grid_axes,
    number_units,
    open_study,
    select_cases,
    study_file_or_exit,
    text,
)

METRIC_KINDS = ("rms_deviation", "peak_deviation")
SPEED_KEYS = ("rpm", "speed_from", "speed_to", "speed_over", "speed_mean", "speed_amplitude", "speed_frequency")
FAULT_KEYS = ("defect_race", "fault")
INDICATORS = ("rms", "peak", "crest_factor", "kurtosis", "skewness", "impulse_factor", "shape_factor",
              "clearance_factor", "envelope_band_kurtosis", "envelope_energy_ftf", "envelope_energy_bpfo",
              "envelope_energy_bpfi", "envelope_energy_2bsf")
"""Per-channel condition indicators of an `envelope:` study (docs/model.md §7.7)."""
GROUP_KEYS = ("location", "rpm", "waviness_amplitude")
DEFECT_PARAMETERS = ("defect_race", "defect_angle", "defect_width", "defect_depth")
"""The first defect's parameters (docs/result-file.md): not applicable to a bearing without one."""
NO_DEFECT = "no defect"
"""The label of the cases in the diagnosis figures of a study without any defect (its
`fault` labels, all `none`, would tell nothing)."""


class Skipped:
    """One line of index.md: what is not shown for one reason (every figure skipped for
    that reason, listed where the first was)."""

    SHOWN = 3
    """Names listed before the count of the rest."""

    def __init__(self, reason, what):
        self.reason = reason
        self.whats = [what]

    def __str__(self):
        if len(self.whats) == 1:
            return f"*{self.whats[0]}: not shown ({self.reason}).*"
        listed = "; ".join(self.whats[: self.SHOWN])
        rest = len(self.whats) - self.SHOWN
        return (f"*{len(self.whats)} figures not shown ({self.reason}): {listed}"
                + (f"; and {rest} more" if rest > 0 else "") + ".*")


class Index:
    """The sections of index.md: figures with captions, and notes on what was skipped."""

    def __init__(self, title):
        self.lines = [f"# {title}", ""]
        self.skips = {}

    def section(self, heading):
        """Start a section."""
        self.lines += [f"## {heading}", ""]

    def figure(self, path, caption):
        """Show the PNG `path` (in the output directory) with a one-line caption."""
        self.lines += [f"![{path.stem}]({path.name})", "", caption, ""]

    def note(self, text):
        """A line of text, e.g. what the study cannot show."""
        self.lines += [f"*{text}*", ""]

    def skipped(self, what, reason):
        """Say that `what` is not shown because of `reason`: one line per reason, naming
        every figure it holds back."""
        if reason in self.skips:
            self.skips[reason].whats.append(what)
        else:
            self.skips[reason] = Skipped(reason, what)
            self.lines += [self.skips[reason], ""]

    def text(self):
        """The text of index.md."""
        return "\n".join(str(line) for line in self.lines)

    def write(self, path):
        """Write index.md to `path`."""
        path.write_text(self.text(), encoding="utf-8")


def _values_text(ds, name, cases=None):
    """The distinct values of per-case variable `name` (among `cases`), for a message."""
    values = ds[name].values if cases is None else ds[name].values[cases]
    if values.dtype.kind in "USO":
        shown = sorted({text(v) for v in values})
    else:
        shown = [f"{v:g}" for v in np.unique(values.astype(float))]
    return ", ".join(shown[:20]) + (", ..." if len(shown) > 20 else "") if shown else "(no case)"


def parse_selection(ds, item):
    """(NAME, value) of a `--select NAME=VALUE`: VALUE as text for a string variable,
    else a plain number in the file's unit. Raises ValueError saying what is allowed."""
    name, sep, value = item.partition("=")
    name, value = name.strip(), value.strip()
    if not sep or not name or name not in ds or ds[name].dims != ("case",):
        axes = ", ".join(["location"] + [a for a in grid_axes(ds) if a != "location"])
        raise ValueError(f"--select {item!r}: expected NAME=VALUE with NAME a case parameter "
                         f"(e.g. {axes})")
    if ds[name].dtype.kind in "USO":
        return name, value
    try:
        return name, float(value)
    except ValueError:
        units = number_units(ds, name)
        raise ValueError(f"--select {item!r}: {name} takes a plain number in the file's unit {units} "
                         f"(units are not parsed); the file has {_values_text(ds, name)}") from None


def restrict(ds, selections):
    """The cases matching NAME=VALUE selections (file units), as a Dataset. Raises
    ValueError for a malformed selection and for selections no case matches, naming
    the values the file has."""
    params = dict(parse_selection(ds, item) for item in selections)
    if not params:
        return ds
    cases = select_cases(ds, **params)
    if cases.size == 0:
        for name, value in params.items():
            if select_cases(ds, **{name: value}).size == 0:
                shown = value if isinstance(value, str) else f"{value:g}"
                raise ValueError(f"--select {name}={shown}: no case has {name} {shown}; "
                                 f"the file has {_values_text(ds, name)}")
        others = {name: select_cases(ds, **{k: v for k, v in params.items() if k != name}) for name in params}
        found = "; ".join(f"{name} is {_values_text(ds, name, rows)}" for name, rows in others.items())
        raise ValueError(f"--select {' '.join(selections)}: no case matches them all; among the cases "
                         f"the other selections keep, {found}")
    return ds.isel(case=cases)


def no_defect(ds):
    """Boolean per case: the bearing has no defect. Its `fault` label is `none` where
    the file has the label, else its `defect_depth` is 0 or NaN (a zero-depth defect is
    no defect, docs/grid-file.md); without either variable, no case has a defect."""
    if "fault" in ds:
        return np.array([text(v) == dfig.HEALTHY for v in ds["fault"].values], dtype=bool)
    if "defect_depth" in ds:
        depth = ds["defect_depth"].values
        return (depth == 0) | np.isnan(depth)
    return np.ones(ds.sizes["case"], dtype=bool)


def mark_healthy(ds):
    """`ds` with the defect parameters of the cases without a defect (`no_defect`)
    marked not applicable: `defect_race` `none`, the numeric ones NaN (shown as n/a),
    as studyrun stores them; a file that gives its healthy cases the race, angle and
    width of a zero-depth defect (which describe nothing) is shown the same way."""
    healthy = no_defect(ds)
    if not healthy.any():
        return ds
    changed = {}
    for name in DEFECT_PARAMETERS:
        if name not in ds or ds[name].dims != ("case",):
            continue
        values = ds[name].values.copy()
        if values.dtype.kind in "USO":
            values = values.astype(object)
            values[healthy] = dfig.HEALTHY
        else:
            values = values.astype(float)
            values[healthy] = np.nan
        changed[name] = ds[name].copy(data=values)
    return ds.assign(changed)


def with_constant_rpm(ds):
    """`ds` with `rpm` set for the cases whose speed profile runs as a constant speed
    (`studyfile.constant_rpm`: a ramp from a speed to the same speed, a sine of
    amplitude 0), so that they are selected and drawn at that speed like a constant
    `rpm`; speeds that vary keep `rpm` NaN."""
    rpm = np.array([constant_rpm(ds, case) for case in range(ds.sizes["case"])], dtype=float)
    return ds.assign(rpm=ds["rpm"].copy(data=rpm))


def healthy_beside_defects(ds):
    """For the metrics views: the flat `ds` (after `mark_healthy`) with each case
    without a defect repeated at every combination of the numeric defect grid axes
    (`defect_width`, `defect_angle`, `defect_depth`) that the cases with a defect
    have, so that it fills the `defect_race` `none` row of each of their facets (its
    own NaN cannot be a grid coordinate). Healthy copies that coincide on every grid
    axis are kept once. Returns (the Dataset, the count of healthy cases left out)."""
    axes = grid_axes(ds)
    numeric = [a for a in axes if a in DEFECT_PARAMETERS and a != "defect_race" and a in ds]
    healthy = no_defect(ds)
    if not numeric or healthy.all() or not healthy.any():
        return ds, 0
    sick, well = np.flatnonzero(~healthy), np.flatnonzero(healthy)
    combos = list(dict.fromkeys(zip(*(ds[a].values[sick].tolist() for a in numeric))))
    rows = np.concatenate([sick] + [well] * len(combos))
    out = ds.isel(case=rows)
    for j, name in enumerate(numeric):
        values = out[name].values.astype(float).copy()
        values[len(sick):] = np.repeat([combo[j] for combo in combos], len(well))
        out = out.assign({name: out[name].copy(data=values)})
    keep, seen, shown = list(range(len(sick))), set(), set()
    for k, key in enumerate(zip(*(out[a].values.tolist() for a in axes))):
        if k >= len(sick) and key not in seen:
            seen.add(key)
            keep.append(k)
            shown.add(int(rows[k]))
    return out.isel(case=keep), len(well) - len(shown)


def bearing_cases(ds):
    """Positions of the successful cases with a bearing (location not `ideal`)."""
    ok = (ds["status"].values == 1) & (ds["location"].values != "ideal")
    return np.flatnonzero(ok)


def varying_axes(ds, cases):
    """The grid axes with more than one value among `cases`, in file order."""
    return [a for a in grid_axes(ds) if len(np.unique(ds[a].values[cases])) > 1]


def metric_axes(axes):
    """(x, y) for the metrics views: ball_count and rpm if they vary, else the first
    varying axes; y is None when only one axis varies."""
    preferred = [a for a in ("ball_count", "rpm") if a in axes]
    ordered = preferred + [a for a in axes if a not in preferred]
    return ordered[0], (ordered[1] if len(ordered) > 1 else None)


def panel_keys(ds):
    """The parameters a panel group fixes: location, rpm, waviness_amplitude and the
    other grid axes except ball_count."""
    return list(GROUP_KEYS) + [a for a in grid_axes(ds) if a not in GROUP_KEYS and a != "ball_count"]


def _params(ds, case, keys):
    """({key: value} of `case`, the same as a hashable tuple with NaN as the text 'nan'
    so that NaN groups with NaN: a parameter not applicable, or differing per race)."""
    params = {}
    for key in keys:
        value = ds[key].values[case]
        params[key] = str(value) if ds[key].dtype.kind in "USO" else float(value)
    same = tuple((k, "nan" if isinstance(v, float) and np.isnan(v) else v) for k, v in params.items())
    return params, same


def panel_groups(ds, cases):
    """[(parameters, ball counts)]: the distinct combinations of location, rpm,
    waviness_amplitude and the other grid axes (except ball_count) among `cases`,
    in file order, with the ball counts each has."""
    keys = panel_keys(ds)
    groups = {}
    for case in cases:
        params, same = _params(ds, case, keys)
        groups.setdefault(same, (params, set()))[1].add(int(ds["ball_count"].values[case]))
    return [(params, sorted(counts)) for params, counts in groups.values()]


def cases_repeat(count):
    """'case without a defect repeats' or 'cases without a defect repeat', for `count`."""
    return "case without a defect repeats" if count == 1 else "cases without a defect repeat"


def healthy_repeats(ds, cases):
    """Positions among `cases` of the cases without a defect whose panel parameters and
    ball count repeat an earlier such case's (after `mark_healthy` they differ only in
    the zero-depth defect, which is no defect: the same run)."""
    keys = panel_keys(ds) + ["ball_count"]
    healthy = no_defect(ds)
    seen, out = set(), []
    for case in cases:
        if healthy[case]:
            same = _params(ds, case, keys)[1]
            if same in seen:
                out.append(int(case))
            seen.add(same)
    return out


def slug(ds, params):
    """A file-name fragment for a parameter combination, e.g. crank_ground_300rpm_4um."""
    words = "_".join(figures.value_text(ds, k, v).replace(" ", "") for k, v in params.items())
    return words.replace("µ", "u").replace("/", "-")


def render_metrics(ds, cases, outdir, index, dpi):
    """The metrics views of the bearing cases into `outdir`, listed in `index`."""
    index.section("Vibration metrics (docs/model.md §6)")
    metrics = [f"{channel}_{kind}" for channel in figures.PANEL_CHANNELS for kind in METRIC_KINDS]
    needed = [n for n in grid_axes(ds) + ["status", "fault", "defect_depth"] + metrics if n in ds]
    bearing, repeated = healthy_beside_defects(ds[needed].isel(case=cases))
    axes = varying_axes(bearing, np.arange(bearing.sizes["case"]))
    if not axes:
        index.note("No grid axis varies among the bearing cases: no metrics view.")
        return
    if repeated:
        index.note(f"{repeated} {cases_repeat(repeated)} another's grid values: the first is shown.")
    x_axis, y_axis = metric_axes(axes)
    healthy_note = ""
    if "defect_race" in axes and no_defect(bearing).any():
        healthy_note = "; defect_race none: the bearing without a defect"
        repeated_over = [a for a in axes if a in DEFECT_PARAMETERS and a != "defect_race"]
        if repeated_over:
            healthy_note += f", shown at every {' and '.join(repeated_over)}"
    for channel in figures.PANEL_CHANNELS:
        for kind in METRIC_KINDS:
            metric = f"{channel}_{kind}"
            if metric not in ds:
                continue
            out = outdir / f"metrics_{metric}.png"
            shape = f"over {x_axis} × {y_axis}" if y_axis else f"against {x_axis}"
            try:
                figures.metrics_view(bearing, metric, x_axis, y_axis, out=out, dpi=dpi)
            except ValueError as e:
                index.skipped(metric, str(e))
                continue
            index.figure(out, f"{metric} ({figures.unit_text(ds, metric)}) of the bearing cases {shape}, "
                              "transient ≤ t < duration; facets: the other grid axes; blank: failed or not run"
                              + healthy_note + ".")


def render_group(ds, params, counts, outdir, index, channels, dpi):
    """Panels and spectra of one parameter combination, up to 4 ball counts a figure."""
    words = figures.describe(ds, params)
    fixed = {k: v for k, v in params.items() if k not in GROUP_KEYS}
    chunks = [counts[i : i + figures.MAX_PANELS] for i in range(0, len(counts), figures.MAX_PANELS)]
    for chunk in chunks:
        balls = ", ".join(str(n) for n in chunk)
        name = slug(ds, params) + (f"_nb{chunk[0]}-{chunk[-1]}" if len(chunks) > 1 else "")
        args = (ds, params["location"], params["rpm"], params["waviness_amplitude"])
        for channel in channels:
            t0, t1 = figures.default_window(ds, params["rpm"])
            if channel not in ds:
                index.skipped(f"{channel}, {words}", "the file does not store it: see `output.series`")
                continue
            try:
                out = figures.paper_panels(*args, channel, outdir / f"panels_{channel}_{name}.png",
                                           select=fixed, ball_counts=chunk, dpi=dpi)
                ideal = " (ideal mechanism dashed)" if channel in figures.PANEL_CHANNELS else ""
                index.figure(out, f"{figures.channel_text(channel)} against time, t = {t0:g}–{t1:g} s, "
                                  f"N_b = {balls}{ideal}: {words}.")
                if int(ds.attrs.get("decimate", 1)) != 1 and channel in figures.PANEL_CHANNELS:
                    index.skipped(f"spectra of {channel}, {words}", "the ideal mechanism's spectrum needs its "
                                  f"full-rate series; the file stores every {int(ds.attrs['decimate'])}th sample, "
                                  "`output.decimate`")
                elif f"{channel}_spectrum" in ds:
                    out = figures.spectra(*args, channel, outdir / f"spectrum_{channel}_{name}.png",
                                          select=fixed, ball_counts=chunk, dpi=dpi)
                    grey = ", ideal mechanism grey" if channel in figures.PANEL_CHANNELS else ""
                    index.figure(out, f"amplitude spectra of {figures.channel_text(channel)}, N_b = {balls}{grey}, "
                                      f"characteristic frequencies marked: {words}.")
            except ValueError as e:  # e.g. an ideal-mechanism series the file does not store
                index.skipped(f"{channel}, {words}", str(e))


def render_series(ds, cases, outdir, index, channels, max_groups, dpi):
    """Time-series panels and spectra of every parameter combination (at most max_groups)."""
    index.section("Time series and spectra per ball count")
    if "time" not in ds.dims:
        index.note("The file stores no series (its grid file has `output.series: none`): "
                   "no time-series panels or spectra; the metrics above are complete.")
        return
    if cases.size == 0:
        index.note("The study has no successful case with a bearing (crank_ground or crank_rod): "
                   "no time-series panels or spectra.")
        return
    repeats = healthy_repeats(ds, cases)
    if repeats:
        index.note(f"{len(repeats)} {cases_repeat(len(repeats))} another's parameters: the first is shown.")
        ds = ds.isel(case=[int(c) for c in cases if int(c) not in repeats])
        cases = np.arange(ds.sizes["case"])
    groups = panel_groups(ds, cases)
    profiled = [params for params, _ in groups if not np.isfinite(params["rpm"])]
    if profiled:
        index.note(f"{len(profiled)} combinations run a `speed:` profile whose speed varies: no panels or "
                   "spectra here; the diagnosis section shows them.")
        groups = [(params, counts) for params, counts in groups if np.isfinite(params["rpm"])]
    if len(groups) > max_groups:
        index.note(f"{len(groups)} parameter combinations; the first {max_groups} are shown "
                   "(raise --max-groups or narrow with --select).")
    if groups and all(len(counts) == 1 for _, counts in groups):
        index.note("The study has one ball count per combination: one panel per figure.")
    for params, counts in groups[:max_groups]:
        render_group(ds, params, counts, outdir, index, channels, dpi)


def speed_text(ds, case):
    """'600 rpm' for a constant speed, else the profile, e.g. 'run-up 300→900 rpm'."""
    rpm = constant_rpm(ds, case)
    if np.isfinite(rpm):
        return f"{rpm:g} rpm"
    profile = text(ds["speed_profile"].values[case])
    if profile == "ramp":
        low, high = (float(ds[k].values[case]) for k in ("speed_from", "speed_to"))
        return f"{'run-up' if high > low else 'run-down'} {low:g}→{high:g} rpm"
    if profile == "sine":
        return f"sine {float(ds['speed_mean'].values[case]):g} ± {float(ds['speed_amplitude'].values[case]):g} rpm"
    return f"{profile} speed"


def speed_key(ds, case):
    """Sort key of a case's speed: constant speeds first, by rpm, then ramps by (from,
    to), sines by (mean, amplitude), other profiles last."""
    rpm = constant_rpm(ds, case)
    if np.isfinite(rpm):
        return (0, rpm, 0.0)
    profile = text(ds["speed_profile"].values[case])
    pairs = {"ramp": ("speed_from", "speed_to"), "sine": ("speed_mean", "speed_amplitude")}
    if profile in pairs:
        return (1 if profile == "ramp" else 2,) + tuple(float(ds[k].values[case]) for k in pairs[profile])
    return (3, 0.0, 0.0)


def value_keys(ds, axis, cases):
    """Sort keys of the values of per-case variable `axis` at `cases`: numbers by value
    (NaN, not applicable, last), text in order of first appearance among `cases`."""
    values = ds[axis].values[cases]
    if values.dtype.kind in "USO":
        first = {v: k for k, v in enumerate(dict.fromkeys(text(v) for v in values))}
        return [(0, first[text(v)]) for v in values]
    return [(1, 0.0) if np.isnan(v) else (0, float(v)) for v in values.astype(float)]


def axis_labels(ds, axis, cases):
    """(title, [label], [sort key]) of grid axis `axis` at `cases`, for a heatmap axis: a
    speed axis (SPEED_KEYS) shows each case's speed, a profile by its profile
    (`speed_text`, e.g. 'run-up 300→900 rpm'), ordered by `speed_key`; another axis its
    values with their unit, numbers in numeric order (`value_keys`)."""
    if axis in SPEED_KEYS:
        return "speed", [speed_text(ds, c) for c in cases], [speed_key(ds, c) for c in cases]
    return (figures.PARAMETER_TEXT.get(axis, axis), [figures.value_text(ds, axis, v) for v in ds[axis].values[cases]],
            value_keys(ds, axis, cases))


def conditions(ds, cases):
    """{condition: {fault label: case}} of the successful bearing `cases`: a condition
    is the case's speed with the grid axes that vary among them (other than the
    speed's and the defect's race); the fault label is the `fault` variable. A case
    without a defect (`no_defect`) has no defect width, angle or depth: it joins every
    condition that agrees with it on the other axes (one of its own if none does). The
    conditions are ordered by those axes' values (`value_keys`), then by speed
    (`speed_key`). In a study without any defect among `cases` the label is NO_DEFECT.
    Returns also the count of cases left out because an earlier one had the same pair."""
    axes = [a for a in varying_axes(ds, cases) if a not in SPEED_KEYS + FAULT_KEYS]
    if "location" in ds and len(np.unique(ds["location"].values[cases])) > 1 and "location" not in axes:
        axes.insert(0, "location")
    defect_axes = [a for a in axes if a in DEFECT_PARAMETERS]
    healthy = no_defect(ds)
    keys = {a: dict(zip(cases, value_keys(ds, a, cases))) for a in axes}
    sort_key = {}

    def label_of(case):
        return dfig.fault_label(ds, case) if not healthy[cases].all() else NO_DEFECT

    def place(case, skip=()):
        return ", ".join([(f"{figures.PARAMETER_TEXT.get(a, a)} " if a != "location" else "")
                          + figures.value_text(ds, a, ds[a].values[case]) for a in axes if a not in skip]
                         + [speed_text(ds, case)])

    out, general, dropped = {}, {}, 0
    later = [int(c) for c in cases if defect_axes and healthy[c]]
    for case in cases:
        if defect_axes and healthy[case]:
            continue
        name = place(case)
        general.setdefault(name, place(case, defect_axes))
        sort_key.setdefault(name, tuple(keys[a][case] for a in axes) + speed_key(ds, case))
        group = out.setdefault(name, {})
        label = label_of(case)
        if label in group:
            dropped += 1
        else:
            group[label] = int(case)
    for case in later:
        own = place(case, defect_axes)
        joined = False
        for name in [n for n, g in general.items() if g == own] or [own]:
            sort_key.setdefault(name, tuple(keys[a][case] for a in axes) + speed_key(ds, case))
            group = out.setdefault(name, {})
            label = label_of(case)
            if label not in group:
                group[label] = case
                joined = True
        dropped += not joined
    return {name: out[name] for name in sorted(out, key=sort_key.get)}, dropped


def envelope_channels(ds):
    """The channels of the study's `envelope:` (those with an envelope spectrum)."""
    return [str(n)[: -len("_envelope_spectrum")] for n in ds.data_vars if str(n).endswith("_envelope_spectrum")]


def sensor_series(ds):
    """The sensors' measured series (`<name>` beside `<name>_clean`, docs/result-file.md)."""
    return [str(n) for n in ds.data_vars if f"{n}_clean" in ds and ds[n].dims == ("case", "time")]


def _draw(index, what, draw, caption):
    """Run `draw()` (which writes a PNG and returns its path) and show it, or note why not."""
    try:
        index.figure(draw(), caption)
    except ValueError as e:
        index.skipped(what, str(e))


def render_diagnosis(ds, cases, outdir, index, max_groups, dpi):
    """The diagnosis figures (analysis/diagnosis_figures.py) of the bearing cases."""
    index.section("Diagnosis: orbit, envelope, time–frequency and order analysis, kurtogram, indicators")
    index.lines += ["Which series: the first envelope channel whose series the file stores, else the first sensor "
                    "series, else bearing_force.", ""]
    if cases.size == 0:
        index.note("No successful bearing case: no diagnosis figures.")
        return
    groups, dropped = conditions(ds, cases)
    if dropped:
        index.note(f"{dropped} cases share a condition and fault label with an earlier case: the first is shown.")
    names = list(groups)[:max_groups]
    if len(groups) > max_groups:
        index.note(f"{len(groups)} conditions; the first {max_groups} are shown (raise --max-groups or use --select).")
    constant = [n for n in names if all(np.isfinite(constant_rpm(ds, c)) for c in groups[n].values())]
    varying = [n for n in names if n not in constant]
    channels = envelope_channels(ds)
    sensors = sensor_series(ds)
    with_series = [c for c in channels if c in ds]
    series = (with_series or sensors or ["bearing_force"])[0]

    for start in range(0, len(names), dfig.MAX_PANELS):
        chunk = {n: groups[n] for n in names[start : start + dfig.MAX_PANELS]}
        _draw(index, "orbit", lambda: dfig.orbit(ds, chunk, outdir / f"orbit_{start // dfig.MAX_PANELS}.png", dpi=dpi),
              "journal centre orbit (eccentricity y against x, µm) over the analysed window, one panel per "
              "condition, one curve per fault label; dashed: the clearance circle of radius P_d/2.")

    if not channels:
        index.note("The study has no `envelope:`: no envelope spectra, waterfall, kurtogram band or indicators.")
    for channel in channels + [s for s in sensors if s not in channels]:
        stored = channel in channels
        what = f"the sensor series {channel} (noise included)" if channel in sensors else channel
        band = ("in the band the file records" if stored
                else "each in the band of its fast kurtogram recomputed from the series")
        for name in constant:
            out = outdir / f"envelope_{channel}_{slug_text(name)}.png"
            _draw(index, f"envelope spectra of {channel}, {name}",
                  lambda: dfig.envelope_spectra(ds, channel, groups[name], out, dpi=dpi),
                  f"envelope spectra of {what} at {name}, {band}, one panel per fault label (healthy grey); "
                  "dashed: FTF, BPFO, BPFI, BSF, 2·BSF; dotted: shaft sidebands ±k·f_shaft around the panel's "
                  "fault line.")
        if stored and not constant:
            index.note(f"{channel}: no constant-speed condition, no envelope spectra with fault lines.")

    shown = varying or constant[:1]
    for name in shown:
        out = outdir / f"spectrogram_{series}_{slug_text(name)}.png"
        _draw(index, f"spectrogram, {name}", lambda: dfig.spectrogram(ds, series, groups[name], out, dpi=dpi),
              f"spectrogram of the squared envelope of {series} in its band at {name}, one panel per fault label; "
              "dashed and dotted: 1× and 2× the panel's fault line following the crank speed."
              if f"{series}_envelope_band_low" in ds else
              f"spectrogram of {series} at {name}, from 0 to where 99.5 % of its power lies, one panel per fault "
              "label (dB re the panel's largest).")
    if not varying:
        index.note("No run-up or other varying speed: the spectrogram of the first condition only, no order spectra.")

    speeds = {constant_rpm(ds, c) for g in constant for c in groups[g].values()}
    for channel in channels:
        if len(speeds) < 2 and not varying:
            index.note(f"{channel}: one constant speed only: no waterfall over the crank speed.")
            continue
        by_fault = {}
        for name in names:
            for label, case in groups[name].items():
                if case not in by_fault.setdefault(label, []):  # a healthy case joins several conditions
                    by_fault[label].append(case)
        out = outdir / f"waterfall_{channel}.png"
        _draw(index, f"waterfall of {channel}",
              lambda: dfig.waterfall(ds, channel, dict(list(by_fault.items())[: dfig.MAX_PANELS]), out, dpi=dpi),
              f"envelope spectra of {channel} stacked over the crank speed (rpm), one panel per fault label: "
              "constant speeds as stored, run-ups in 0.2 s segments, each scaled to its largest; "
              "dashed: the lines at order × rpm/60.")

    for name in varying:
        out = outdir / f"orders_{series}_{slug_text(name)}.png"
        _draw(index, f"order spectra, {name}", lambda: dfig.order_spectra(ds, series, groups[name], out, dpi=dpi),
              f"order spectra of {series} at {name} (amplitude against cycles per crank revolution), one panel "
              "per fault label; dashed: the orders of FTF, BPFO, BPFI, BSF, 2·BSF.")
        out = outdir / f"rpm_orders_{series}_{slug_text(name)}.png"
        _draw(index, f"rpm–order map, {name}", lambda: dfig.rpm_order_map(ds, series, groups[name], out, dpi=dpi),
              f"rpm–order map of {series} at {name}: short-time spectra"
              + (" of the squared envelope in its band" if f"{series}_envelope_band_low" in ds else "")
              + " in 0.2 s segments, each read at orders of its mean crank speed (dB re the panel's largest), one "
              "panel per fault label; dashed: the orders of FTF, BPFO, BPFI, 2·BSF, which stay put as the speed "
              "sweeps.")

    for channel in channels:
        if constant or varying:
            name = (constant or varying)[0]
            out = outdir / f"spectral_kurtosis_{channel}_{slug_text(name)}.png"
            _draw(index, f"spectral kurtosis of {channel}, {name}",
                  lambda: dfig.spectral_kurtosis(ds, channel, groups[name], out, dpi=dpi),
                  f"spectral kurtosis of {channel} as stored (docs/model.md §7.5) at {name}, one panel per fault "
                  "label; shaded: the band the file records.")

    if with_series and names:
        first, channel = names[0], with_series[0]
        for label, case in groups[first].items():
            out = outdir / f"kurtogram_{channel}_{slug_text(first)}_{slug_text(label)}.png"
            _draw(index, f"kurtogram, {first}, {label}", lambda: dfig.kurtogram(ds, channel, case, out, dpi=dpi),
                  f"fast kurtogram of {channel} recomputed from the series ({first}, {label}): "
                  "kurtosis per band and level; white: its largest, cyan dashed: the band the file records.")

    render_indicators(ds, cases, channels, outdir, index, dpi)


def render_indicators(ds, cases, channels, outdir, index, dpi):
    """Heatmaps of the condition indicators over two grid axes if they tell the cases
    apart, else over fault label × condition; numbers in numeric order, speeds by
    `axis_labels`."""
    if not channels:
        return
    sub = ds.isel(case=cases)
    all_cases = np.arange(len(cases))
    axes = varying_axes(sub, all_cases)
    pairs = []
    if len(axes) >= 2:
        x_axis, y_axis = metric_axes(axes)
        pairs.append((axis_labels(sub, x_axis, all_cases), axis_labels(sub, y_axis, all_cases)))
    groups = conditions(sub, all_cases)[0]
    condition = {case: name for name, g in groups.items() for case in g.values()}
    rank = {name: k for k, name in enumerate(groups)}
    faults = [dfig.fault_label(sub, c) for c in all_cases]
    named = [condition.get(c, "(repeated)") for c in all_cases]
    pairs.append((("fault", faults, list(all_cases)),  # fault labels as they first come
                  ("condition", named, [rank.get(n, len(rank)) for n in named])))
    for channel in channels:
        names = [f"{channel}_{i}" for i in INDICATORS if f"{channel}_{i}" in ds]
        out = outdir / f"indicators_{channel}.png"
        for x, y in pairs:
            try:
                path = dfig.indicator_heatmaps(sub, names, x, y, out, dpi=dpi)
            except ValueError as e:
                reason = e
                continue
            index.figure(path, f"condition indicators of {channel} (docs/model.md §7.7) over {x[0]} × {y[0]}, "
                               "one colour scale a panel; blank: no such case or failed.")
            break
        else:
            index.skipped(f"indicators of {channel}", str(reason))


def slug_text(text):
    """A file-name fragment of a condition's text, e.g. crank_ground_N_b8_run-up300-900rpm."""
    out = text.replace("→", "-").replace("±", "pm").replace("µ", "u").replace(", ", "_").replace(" ", "")
    return out.replace("/", "-")


def summary(ds, cases):
    """Lines describing the study: name, axes, case counts, analysis window."""
    status = ds["status"].values
    ideal = int((ds["location"].values == "ideal").sum())
    return [
        f"{ds.attrs.get('study_description', '')}",
        "",
        f"- grid axes: {', '.join(grid_axes(ds)) or 'none (explicit cases)'}",
        f"- cases: {ds.sizes['case']} ({int((status == 1).sum())} ok, {int((status == 2).sum())} failed, "
        f"{ideal} ideal); {cases.size} successful bearing cases shown",
        f"- analysis window {float(ds.attrs['transient']):g} s ≤ t < {float(ds.attrs['duration']):g} s, "
        f"sample rate {float(ds.attrs['sample_rate']):g} Hz",
        "",
    ]


def check_channels(ds, channels):
    """Raise ValueError unless each of `channels` is a `[case, time]` series of `ds` or
    one of PANEL_CHANNELS (a panel channel the file does not store is said so in the
    index), naming the series allowed."""
    series = [str(n) for n in ds.data_vars if ds[n].dims == ("case", "time")]
    allowed = list(dict.fromkeys(list(figures.PANEL_CHANNELS) + series))
    bad = [c for c in channels if c not in allowed]
    if bad:
        raise ValueError(f"--channels {bad[0]}: not a series of the file; allowed: {', '.join(allowed)}")


def is_recordings_file(path):
    """Whether the study file `path` is a recordings study's (docs/result-file.md,
    Recordings: it has `recording_file`)."""
    with open_study(path) as ds:
        return "recording_file" in ds


def recording_groups(ds):
    """{'<rpm> rpm': {fault label: case}} of the ok cases at a constant speed, the first
    case of each label per speed."""
    groups = {}
    for case in np.flatnonzero(ds["status"].values == 1):
        rpm = constant_rpm(ds, case)
        if np.isfinite(rpm):
            groups.setdefault(f"{rpm:g} rpm", {}).setdefault(dfig.fault_label(ds, case), int(case))
    return groups


def render_recordings(ds, outdir, index, dpi, simulated=None):
    """The figures of a recordings study, drawn as a simulated study's diagnosis is:
    per envelope channel and constant speed the envelope spectra with the fault lines,
    and per case of the first speed its kurtogram with the band chosen; with a
    `simulated` study file open, per fault label a measured case beside a simulated
    case of that fault (its first envelope channel)."""
    index.section("Recordings: envelope spectra, kurtogram, measured beside simulated")
    channels = envelope_channels(ds)
    groups = recording_groups(ds)
    if not channels or not groups:
        index.note("No `envelope:` or no ok recording at a constant speed: no envelope figures.")
        return
    for channel in channels:
        for name, cases in groups.items():
            out = outdir / f"envelope_{channel}_{slug_text(name)}.png"
            _draw(index, f"envelope spectra of {channel}, {name}",
                  lambda: dfig.envelope_spectra(ds, channel, cases, out, dpi=dpi),
                  f"envelope spectra of the recordings' {channel} at {name}, in the band the file records, one "
                  "panel per fault label (healthy grey); dashed: FTF, BPFO, BPFI, BSF, 2·BSF from the bearing's "
                  "geometry; dotted: shaft sidebands around the panel's fault line.")
        first = next(iter(groups))
        for label, case in groups[first].items():
            out = outdir / f"kurtogram_{channel}_{slug_text(first)}_{slug_text(label)}.png"
            _draw(index, f"kurtogram, {label}", lambda: dfig.kurtogram(ds, channel, case, out, dpi=dpi),
                  f"fast kurtogram of the recording's {channel} ({first}, {label}); white: its largest kurtosis, "
                  "cyan dashed: the band the file records (band: as the grid's envelope.band chose it).")
    if simulated is None:
        return
    s_channels = envelope_channels(simulated)
    s_cases = [c for c in np.flatnonzero(simulated["status"].values == 1)
               if np.isfinite(constant_rpm(simulated, c)) and (
                   "location" not in simulated or text(simulated["location"].values[c]) != "ideal")]
    for label, case in next(iter(groups.values())).items():
        match = [c for c in s_cases if dfig.fault_label(simulated, c) == label]
        if not s_channels or not match:
            index.note(f"{label}: no simulated case of this fault with an envelope channel to set beside it.")
            continue
        out = outdir / f"measured_simulated_{slug_text(label)}.png"
        _draw(index, f"measured beside simulated, {label}",
              lambda: dfig.measured_beside_simulated((ds, channels[0], case),
                                                     (simulated, s_channels[0], int(match[0])), out, dpi=dpi),
              f"fault {label}: the measured recording's envelope spectrum (left) beside the simulated case's "
              f"(right, {s_channels[0]}), each with its own characteristic lines.")


def report(study, outdir, channels=figures.PANEL_CHANNELS, max_groups=16, dpi=90, selections=(), simulated=None):
    """Render all figures of the study file `study` into `outdir` and write
    `outdir/index.md`; returns the index's path. `channels`: the series of the panels
    and spectra, each a PANEL_CHANNELS entry (with the ideal mechanism's) or any other
    series the file stores, e.g. a sensor's (alone). A recordings study's file
    (`is_recordings_file`) gets `render_recordings`, with the simulated study file
    `simulated` (if given) set beside it fault by fault."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    if is_recordings_file(study):
        with open_study(study) as full:
            ds = restrict(full, selections)
            index = Index(f"Study `{ds.attrs.get('study_name', Path(study).stem)}` (recordings)")
            index.lines += [ds.attrs.get("study_description", ""), "",
                            f"- recordings: {ds.sizes['case']}, analysed {ds.sizes['time'] - 1} samples at "
                            f"{float(ds.attrs['sample_rate']):g} Hz", ""]
            if simulated is None:
                render_recordings(ds, outdir, index, dpi)
            else:
                with open_study(simulated) as sim:
                    render_recordings(ds, outdir, index, dpi, sim)
        path = outdir / "index.md"
        index.write(path)
        return path
    with open_study(study) as full:
        check_channels(full, channels)
        ds = with_constant_rpm(mark_healthy(restrict(full, selections)))
        cases = bearing_cases(ds)
        index = Index(f"Study `{ds.attrs.get('study_name', Path(study).stem)}`")
        index.lines += summary(ds, cases)
        render_metrics(ds, cases, outdir, index, dpi)
        render_series(ds, cases, outdir, index, channels, max_groups, dpi)
        render_diagnosis(ds, cases, outdir, index, max_groups, dpi)
    path = outdir / "index.md"
    index.write(path)
    return path


def main(argv=None):
    """Command line: see --help."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", help="study file written by studyrun (.h5)")
    parser.add_argument("outdir", help="directory for the PNGs and index.md (created if missing)")
    parser.add_argument("--channels", nargs="+", default=list(figures.PANEL_CHANNELS),
                        help="series of the time-series panels and spectra: slider_acceleration, crank_moment, "
                             "bearing_force (with the ideal mechanism's; the default) or any other series the file "
                             "stores, e.g. a sensor's")
    parser.add_argument("--select", action="append", default=[], metavar="NAME=VALUE",
                        help="only cases with this parameter value, in the file's units "
                             "(e.g. rpm=300, waviness_amplitude=4e-6, location=crank_rod); repeatable")
    parser.add_argument("--max-groups", type=int, default=16,
                        help="at most this many parameter combinations get panels and spectra (default 16)")
    parser.add_argument("--dpi", type=int, default=90, help="resolution of the PNGs (default 90)")
    parser.add_argument("--simulated", metavar="FILE",
                        help="for a recordings study: a simulated study file whose cases are set beside the "
                             "recordings of the same fault")
    args = parser.parse_args(argv)
    study_file_or_exit("report", args.study)
    try:
        path = report(args.study, args.outdir, args.channels, args.max_groups, args.dpi, args.select,
                      args.simulated)
    except ValueError as e:
        raise SystemExit(f"report: {e}") from None
    print(path)


if __name__ == "__main__":
    main()
