"""Render the figures of a study file into a directory, with an index.md that shows
them, one caption line each.

    python analysis/report.py STUDY.h5 OUTDIR

Metrics views (heatmaps over the grid axes), then for every combination of bearing
location, speed, waviness amplitude (and any other grid axis) the time-series
panels per ball count with the ideal mechanism, and the amplitude spectra with the
bearing's characteristic frequencies. What a study cannot show (no bearing cases,
no grid axis that varies, cases not told apart by the grid) is skipped and said so
in the index.
"""

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from analysis import figures  # noqa: E402
from analysis.studyfile import grid_axes, open_study, select_cases  # noqa: E402

METRIC_KINDS = ("rms_deviation", "peak_deviation")
GROUP_KEYS = ("location", "rpm", "waviness_amplitude")


class Index:
    """The sections of index.md: figures with captions, and notes on what was skipped."""

    def __init__(self, title):
        self.lines = [f"# {title}", ""]

    def section(self, heading):
        """Start a section."""
        self.lines += [f"## {heading}", ""]

    def figure(self, path, caption):
        """Show the PNG `path` (in the output directory) with a one-line caption."""
        self.lines += [f"![{path.stem}]({path.name})", "", caption, ""]

    def note(self, text):
        """A line of text, e.g. why something is not shown."""
        self.lines += [f"*{text}*", ""]

    def write(self, path):
        """Write index.md to `path`."""
        path.write_text("\n".join(self.lines), encoding="utf-8")


def parse_value(text):
    """A command-line parameter value: a number (file units) if it parses as one, else the string."""
    try:
        return float(text)
    except ValueError:
        return text


def restrict(ds, selections):
    """The cases matching NAME=VALUE selections (file units), as a Dataset."""
    params = {}
    for item in selections:
        name, sep, value = item.partition("=")
        if not sep or name not in ds:
            raise SystemExit(f"--select {item!r}: expected NAME=VALUE with NAME a case parameter")
        params[name] = parse_value(value)
    return ds.isel(case=select_cases(ds, **params)) if params else ds


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


def panel_groups(ds, cases):
    """[(parameters, ball counts)]: the distinct combinations of location, rpm,
    waviness_amplitude and the other grid axes (except ball_count) among `cases`,
    in file order, with the ball counts each has."""
    keys = list(GROUP_KEYS) + [a for a in grid_axes(ds) if a not in GROUP_KEYS and a != "ball_count"]
    groups = {}
    for case in cases:
        params = {}
        for key in keys:
            value = ds[key].values[case]
            params[key] = str(value) if key == "location" else float(value)
        groups.setdefault(tuple(params.items()), set()).add(int(ds["ball_count"].values[case]))
    return [(dict(key), sorted(counts)) for key, counts in groups.items()]


def slug(ds, params):
    """A file-name fragment for a parameter combination, e.g. crank_ground_300rpm_4um."""
    text = "_".join(figures.value_text(ds, k, v).replace(" ", "") for k, v in params.items())
    return text.replace("µ", "u").replace("/", "-")


def render_metrics(ds, cases, outdir, index, dpi):
    """The metrics views of the bearing cases into `outdir`, listed in `index`."""
    index.section("Vibration metrics (docs/model.md §6)")
    axes = varying_axes(ds, cases)
    if not axes:
        index.note("No grid axis varies among the bearing cases: no metrics view.")
        return
    x_axis, y_axis = metric_axes(axes)
    bearing = ds.isel(case=cases)
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
                index.note(f"{metric}: not shown ({e}).")
                continue
            index.figure(out, f"{metric} ({figures.unit_text(ds, metric)}) of the bearing cases {shape}, "
                              "transient ≤ t < duration; facets: the other grid axes; blank: failed or not run.")


def render_group(ds, params, counts, outdir, index, channels, dpi):
    """Panels and spectra of one parameter combination, up to 4 ball counts a figure."""
    text = figures.describe(ds, params)
    fixed = {k: v for k, v in params.items() if k not in GROUP_KEYS}
    chunks = [counts[i : i + figures.MAX_PANELS] for i in range(0, len(counts), figures.MAX_PANELS)]
    for chunk in chunks:
        balls = ", ".join(str(n) for n in chunk)
        name = slug(ds, params) + (f"_nb{chunk[0]}-{chunk[-1]}" if len(chunks) > 1 else "")
        args = (ds, params["location"], params["rpm"], params["waviness_amplitude"])
        for channel in channels:
            t0, t1 = figures.default_window(ds, params["rpm"])
            if channel not in ds:
                index.note(f"{channel}, {text}: not shown (the file does not store it: see `output.series`).")
                continue
            try:
                out = figures.paper_panels(*args, channel, outdir / f"panels_{channel}_{name}.png",
                                           select=fixed, ball_counts=chunk, dpi=dpi)
                index.figure(out, f"{figures.CHANNEL_TEXT[channel]} against time, t = {t0:g}–{t1:g} s, "
                                  f"N_b = {balls} (ideal mechanism dashed): {text}.")
                if int(ds.attrs.get("decimate", 1)) != 1:
                    index.note(f"spectra of {channel}, {text}: not shown (the ideal mechanism's spectrum "
                               "needs its full-rate series; the file stores every "
                               f"{int(ds.attrs['decimate'])}th sample, `output.decimate`).")
                elif f"{channel}_spectrum" in ds:
                    out = figures.spectra(*args, channel, outdir / f"spectrum_{channel}_{name}.png",
                                          select=fixed, ball_counts=chunk, dpi=dpi)
                    index.figure(out, f"amplitude spectra of {figures.CHANNEL_TEXT[channel]}, N_b = {balls}, "
                                      f"ideal mechanism grey, characteristic frequencies marked: {text}.")
            except (ValueError, KeyError) as e:
                # KeyError: an ideal-mechanism series the file does not store (`output.series`).
                index.note(f"{channel}, {text}: not shown ({e}).")


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
    groups = panel_groups(ds, cases)
    if len(groups) > max_groups:
        index.note(f"{len(groups)} parameter combinations; the first {max_groups} are shown "
                   "(raise --max-groups or narrow with --select).")
    if all(len(counts) == 1 for _, counts in groups):
        index.note("The study has one ball count per combination: one panel per figure.")
    for params, counts in groups[:max_groups]:
        render_group(ds, params, counts, outdir, index, channels, dpi)


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


def report(study, outdir, channels=figures.PANEL_CHANNELS, max_groups=16, dpi=90, selections=()):
    """Render all figures of the study file `study` into `outdir` and write
    `outdir/index.md`; returns the index's path."""
    outdir = Path(outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    with open_study(study) as full:
        ds = restrict(full, selections)
        cases = bearing_cases(ds)
        index = Index(f"Study `{ds.attrs.get('study_name', Path(study).stem)}`")
        index.lines += summary(ds, cases)
        render_metrics(ds, cases, outdir, index, dpi)
        render_series(ds, cases, outdir, index, channels, max_groups, dpi)
    path = outdir / "index.md"
    index.write(path)
    return path


def main(argv=None):
    """Command line: see --help."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", help="study file written by studyrun (.h5)")
    parser.add_argument("outdir", help="directory for the PNGs and index.md (created if missing)")
    parser.add_argument("--channels", nargs="+", choices=figures.PANEL_CHANNELS, default=list(figures.PANEL_CHANNELS),
                        help="channels of the time-series panels and spectra (default: all three)")
    parser.add_argument("--select", action="append", default=[], metavar="NAME=VALUE",
                        help="only cases with this parameter value, in the file's units "
                             "(e.g. rpm=300, waviness_amplitude=4e-6, location=crank_rod); repeatable")
    parser.add_argument("--max-groups", type=int, default=16,
                        help="at most this many parameter combinations get panels and spectra (default 16)")
    parser.add_argument("--dpi", type=int, default=90, help="resolution of the PNGs (default 90)")
    args = parser.parse_args(argv)
    path = report(args.study, args.outdir, args.channels, args.max_groups, args.dpi, args.select)
    print(path)


if __name__ == "__main__":
    main()
