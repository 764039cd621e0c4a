"""Work-precision diagram of a `studyrun accuracy` file: error against cost, log-log,
one line per integrator (in the style of the SciML work-precision benchmarks).

    python analysis/work_precision.py ACCURACY.h5 OUT.png [--error metric|max|rms]
        [--channel slider_acceleration] [--cost wall_time|rhs_evals]

Each point is one setting (a tolerance, or an RK4 step) aggregated over the
non-chaotic cases of the grid (--chaotic: all cases): the cost is the mean over cases, the error the worst case (--stat max,
default) or the median (--stat median). Errors are relative: `metric` is the relative
error of the RMS deviation from the ideal mechanism (what a user reads), `max` and
`rms` the pointwise error relative to the channel's range up to each case's
predictability horizon.
"""

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from analysis.studyfile import OPEN_OPTIONS, study_file_or_exit  # noqa: E402

ACCURACY_VARIABLES = ("method", "rtol", "step", "horizon")
"""Per-case variables only an accuracy file has (which integrator, its tolerance or step,
the horizon)."""

MARKERS = {"dopri5": "o", "tsit5": "D", "dop853": "v", "sdirk4": "s", "rk4": "^"}


def settings(ds):
    """Each row's setting: the step (s) of rk4, the relative tolerance of the others."""
    return np.where(ds.method.values == "rk4", ds.step.values, ds.rtol.values)


def points(ds, error="metric", channel="slider_acceleration", cost="wall_time", stat="max", chaotic=False):
    """{method: (settings, mean cost, aggregated error)}, sorted by setting (loosest first).

    Only non-chaotic cases (horizon = the whole run) unless `chaotic`: on a chaotic
    case a short-window metric is not reproducible, whatever the integrator.
    """
    var = f"{error}_error_{channel}"
    ok = ds.status.values == 1
    if not chaotic:
        ok &= ds.horizon.values >= ds.attrs.get("duration", ds.horizon.values.max()) - 1e-12
    out = {}
    setting = settings(ds)
    for method in np.unique(ds.method.values):
        rows = (ds.method.values == method) & ok
        ladder = np.unique(setting[rows])[::-1]
        costs, errs = [], []
        for s in ladder:
            sel = rows & (setting == s)
            costs.append(float(np.mean(ds[cost].values[sel])))
            e = ds[var].values[sel]
            errs.append(float(np.max(e) if stat == "max" else np.median(e)))
        out[str(method)] = (ladder, np.array(costs), np.array(errs))
    return out


def plot(ds, out, error="metric", channel="slider_acceleration", cost="wall_time", stat="max", chaotic=False):
    """Writes the diagram to `out` (PNG) and returns the path."""
    fig, ax = plt.subplots(figsize=(6.4, 4.6), dpi=100)
    for method, (settings, costs, errs) in points(ds, error, channel, cost, stat, chaotic).items():
        ax.loglog(costs, errs, marker=MARKERS.get(method, "x"), label=method)
        for s, c, e in zip(settings, costs, errs):
            label = f"{s * 1e6:g} µs" if method == "rk4" else f"{s:.0e}"
            ax.annotate(label, (c, e), fontsize=7, xytext=(3, 3), textcoords="offset points")
    ax.axhline(0.01, color="grey", lw=0.8, ls="--")
    ax.set_xlabel({"wall_time": "wall time per case (s)", "rhs_evals": "RHS evaluations per case"}[cost])
    what = {"metric": "relative metric error", "max": "max |error| / range", "rms": "RMS error / range"}[error]
    ax.set_ylabel(f"{what}, {stat} over {'all' if chaotic else 'non-chaotic'} cases")
    ax.set_title(f"{ds.attrs.get('title', 'work-precision')}\n{channel}", fontsize=9)
    ax.grid(True, which="both", lw=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out)
    plt.close(fig)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("file", help="result of `studyrun accuracy GRID.yaml`")
    p.add_argument("out", help="PNG to write")
    p.add_argument("--error", choices=["metric", "max", "rms"], default="metric")
    p.add_argument("--channel", default="slider_acceleration", choices=["slider_acceleration", "crank_moment", "bearing_force"])
    p.add_argument("--cost", choices=["wall_time", "rhs_evals"], default="wall_time")
    p.add_argument("--stat", choices=["max", "median"], default="max")
    p.add_argument("--chaotic", action="store_true", help="include chaotic cases (horizon shorter than the run)")
    a = p.parse_args(argv)
    study_file_or_exit("work_precision", a.file, needs=ACCURACY_VARIABLES + (f"{a.error}_error_{a.channel}",),
                       kind="an accuracy file (from `studyrun accuracy GRID.yaml`)")
    with xr.open_dataset(a.file, **OPEN_OPTIONS) as ds:
        print(plot(ds.load(), a.out, a.error, a.channel, a.cost, a.stat, a.chaotic))


if __name__ == "__main__":
    main()
