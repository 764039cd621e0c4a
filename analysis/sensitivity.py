"""Sensitivity of a study's metrics to its parameters: Sobol indices.

    python analysis/sensitivity.py STUDY.h5 --metric slider_acceleration_rms_deviation [--out DIR]

Two estimators, chosen by the study's design:

- A full cartesian grid (the grid axes of the file): exact main-effect (first-order)
  and total indices by variance decomposition over the grid, each axis taken as a
  factor uniform over its grid values (`grid_indices`). No sampling error, so no
  interval.
- A Saltelli design: first-order and total Sobol indices with bootstrap confidence
  intervals from SALib's estimators (Saltelli 2010 for S1, Jansen for ST;
  `saltelli_indices`). The interval is SALib's: estimate ± z·σ, σ the standard
  deviation of the estimate over `resamples` bootstrap resamples of the design's rows,
  z the normal quantile of the confidence level.

Indices are shares of the metric's variance: S_i = Var(E[Y | x_i]) / Var(Y) (the
part x_i explains alone) and ST_i = E[Var(Y | x_~i)] / Var(Y) (alone and through
its interactions). An additive metric has Σ S_i = 1 and S_i = ST_i; Σ S_i < 1
measures the interactions.

File layout of a Saltelli design (`design: {method: saltelli}` in the grid file;
docs/result-file.md), what `study_saltelli` reads:
  - root attributes `design_method` = "saltelli" and `design_parameters` = the design's
    parameter names, comma-separated, in the order of the sample matrix's columns;
  - optional root attribute `design_second_order` (0 or 1, default 1): whether the
    design has SALib's N(2D + 2) rows (studyrun's) or N(D + 2) rows;
  - one per-case variable per design parameter (the `[case]` parameter variable of
    that name, in the file's units) holding the case's design value;
  - the cases at one grid point, ordered by case id, are the rows of SALib's sample
    matrix in SALib's order: per base row A, then AB_1 … AB_D, then BA_1 … BA_D, then B.
  A design repeated at every grid point (and explicit case) is analysed one grid point
  at a time: the root attribute `design_rows` says how many cases one repetition
  holds, case id // design_rows is its grid point (`design_points`), and the indices
  are reported per point, named by the parameters that tell the points apart
  (`--select` one point to analyse it alone). `study_saltelli` checks the rows have
  the Saltelli structure (AB_j equals A but in column j, where it equals B) before
  analysing, so a file in another order is refused rather than misread.

Figures (matplotlib, Agg): one PNG per metric with the indices as bars and their
intervals as error bars (`plot_indices`).
"""

import argparse
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
import numpy as np  # noqa: E402

from analysis.report import restrict  # noqa: E402
from analysis.studyfile import grid_axes, open_study, study_file_or_exit, unstack  # noqa: E402


class Indices:
    """Sobol indices of one metric.

    `names`: the parameters; `first`, `total`: S_i and ST_i (dimensionless shares of the
    metric's variance); `first_conf`, `total_conf`: half-widths of their confidence
    intervals (NaN where exact); `conf_level`: the intervals' level (NaN where exact);
    `method`: "grid" or "saltelli"; `samples`: model evaluations used; `point`: the
    grid point of a design repeated over grid axes, {parameter: value in the file's
    units} ({} for a design run once, or the grid's indices).
    """

    def __init__(self, names, first, total, first_conf, total_conf, conf_level, method, samples, point=None):
        self.names = list(names)
        self.first = np.asarray(first, dtype=float)
        self.total = np.asarray(total, dtype=float)
        self.first_conf = np.asarray(first_conf, dtype=float)
        self.total_conf = np.asarray(total_conf, dtype=float)
        self.conf_level = float(conf_level)
        self.method = method
        self.samples = int(samples)
        self.point = dict(point or {})

    def point_text(self):
        """The grid point as 'name = value, …' ('' for none)."""
        return ", ".join(f"{k} = {v if isinstance(v, str) else f'{v:g}'}" for k, v in self.point.items())

    def table(self, metric):
        """The indices as text lines, one parameter a line."""
        exact = self.method == "grid"
        where = f" at {self.point_text()}" if self.point else ""
        head = f"{metric}{where}: " \
               f"{'exact, full grid' if exact else f'Saltelli design, {self.conf_level:.0%} intervals'}" \
               f" ({self.samples} cases)"
        lines = [head, f"  {'parameter':<28}{'S1':>18}{'ST':>18}"]
        for k, name in enumerate(self.names):
            if exact:
                s1, st = f"{self.first[k]:.4f}", f"{self.total[k]:.4f}"
            else:
                s1 = f"{self.first[k]:.4f} ± {self.first_conf[k]:.4f}"
                st = f"{self.total[k]:.4f} ± {self.total_conf[k]:.4f}"
            lines.append(f"  {name:<28}{s1:>18}{st:>18}")
        lines.append(f"  {'sum':<28}{self.first.sum():>18.4f}")
        return lines


def check_saltelli_rows(sample, second_order=True):
    """Raise ValueError unless the rows of `sample` ([rows, D]) have SALib's Saltelli
    layout: blocks of 2D + 2 rows (D + 2 without second order) A, AB_1 … AB_D,
    [BA_1 … BA_D,] B, where AB_j is A with column j from B and BA_j is B with column j
    from A. Returns the base sample count N."""
    sample = np.asarray(sample, dtype=float)
    if sample.ndim != 2:
        raise ValueError(f"the sample matrix must be 2-D [rows, parameters], not of shape {sample.shape}")
    d = sample.shape[1]
    step = 2 * d + 2 if second_order else d + 2
    if sample.shape[0] == 0 or sample.shape[0] % step:
        raise ValueError(
            f"{sample.shape[0]} rows for {d} parameters: a Saltelli design has a multiple of "
            f"{step} rows ({'2D + 2' if second_order else 'D + 2'})"
        )
    blocks = sample.reshape(-1, step, d)
    a, b = blocks[:, 0], blocks[:, -1]
    for j in range(d):
        expected = {"AB": a.copy(), "BA": b.copy()}
        expected["AB"][:, j] = b[:, j]
        expected["BA"][:, j] = a[:, j]
        found = {"AB": blocks[:, 1 + j]}
        if second_order:
            found["BA"] = blocks[:, 1 + d + j]
        for kind, rows in found.items():
            bad = np.flatnonzero(~np.all(rows == expected[kind], axis=1))
            if bad.size:
                raise ValueError(
                    f"the rows are not in SALib's Saltelli order: row {bad[0] * step + 1 + j + (d if kind == 'BA' else 0)} "
                    f"should be {kind}_{j + 1} (block {bad[0]}'s {'A' if kind == 'AB' else 'B'} with column {j + 1} "
                    f"from its {'B' if kind == 'AB' else 'A'})"
                )
    return blocks.shape[0]


def saltelli_indices(problem, sample, outputs, second_order=True, resamples=1000, conf_level=0.95, seed=0):
    """First-order and total Sobol indices with bootstrap intervals from a Saltelli design.

    `problem`: SALib's problem dict (at least `names`; `num_vars` and `bounds` are
    optional here); `sample`: the design's sample matrix [rows, D] in SALib's order
    (`SALib.sample.sobol.sample(problem, N, calc_second_order=second_order)`), checked
    with `check_saltelli_rows`; `outputs`: the model's output for each row, same order.
    `resamples` bootstrap resamples give the intervals at `conf_level`, seeded by `seed`
    (the same seed gives the same intervals). Returns `Indices`.

    Raises ValueError on a malformed design, a row count that does not match the
    outputs, or non-finite outputs (a failed case).
    """
    from SALib.analyze import sobol  # the estimators; imported here so the grid path does without

    names = list(problem["names"])
    sample = np.asarray(sample, dtype=float)
    outputs = np.asarray(outputs, dtype=float).ravel()
    if sample.ndim != 2 or sample.shape[1] != len(names):
        raise ValueError(f"the sample matrix has shape {sample.shape}, expected [rows, {len(names)}] for {names}")
    if outputs.size != sample.shape[0]:
        raise ValueError(f"{outputs.size} outputs for {sample.shape[0]} design rows")
    bad = np.flatnonzero(~np.isfinite(outputs))
    if bad.size:
        raise ValueError(f"{bad.size} outputs are not finite (failed cases?), first at rows {bad[:10].tolist()}")
    n = check_saltelli_rows(sample, second_order)
    if np.ptp(outputs) == 0:
        raise ValueError("the outputs are constant: their variance has no parts to apportion")
    result = sobol.analyze(
        {"num_vars": len(names), "names": names},
        outputs,
        calc_second_order=second_order,
        num_resamples=resamples,
        conf_level=conf_level,
        # a Generator (not the int) so that seed 0 also seeds: SALib tests `if seed:`
        seed=np.random.default_rng(seed),
    )
    return Indices(names, result["S1"], result["ST"], result["S1_conf"], result["ST_conf"],
                   conf_level, "saltelli", n * (2 * len(names) + 2 if second_order else len(names) + 2))


def grid_indices(values):
    """Exact main-effect (first-order) and total indices of a metric on a full cartesian grid.

    `values` is an xarray DataArray with one dimension per grid axis (e.g.
    `unstack(ds)[metric]`); each axis is a factor uniform over its values, so the means
    are plain means over the grid: S_i = Var(E[Y | x_i]) / Var(Y) and
    ST_i = E[Var(Y | x_~i)] / Var(Y), variances over the grid's cells (population
    variances). Axes of one value are left out (their indices are 0). Returns `Indices`.

    Raises ValueError if a grid cell is NaN (a failed case, or a combination the study
    did not run) or the metric is constant.
    """
    values = values.squeeze(drop=True)
    axes = list(values.dims)
    if not axes:
        raise ValueError("no grid axis varies: nothing to apportion")
    if values.isnull().any():
        missing = values.isnull().stack(cell=axes)
        cells = missing["cell"].values[missing.values][:5]
        raise ValueError(
            f"{values.name or 'the metric'} is NaN in {int(missing.sum())} of {missing.size} grid cells "
            f"(failed cases or combinations not run), e.g. {axes} = {[tuple(c) for c in cells]}; "
            "select a full grid first"
        )
    variance = float(values.var())
    if variance == 0:
        raise ValueError(f"{values.name or 'the metric'} is constant over the grid: no variance to apportion")
    first = [float(values.mean([a for a in axes if a != axis]).var()) / variance for axis in axes]
    total = [float(values.var(axis).mean()) / variance for axis in axes]
    nan = np.full(len(axes), np.nan)
    return Indices(axes, first, total, nan, nan, np.nan, "grid", values.size)


def study_grid(ds, metric):
    """`grid_indices` of the study's `metric` over its grid axes (the flat Dataset `ds`)."""
    if metric not in ds:
        raise ValueError(f"no metric {metric!r} in the file")
    return grid_indices(unstack(ds)[metric].load())


def design_points(ds):
    """[(point, positions)] of the file's design repetitions, in case-id order: the
    cases of each grid point (case id // `design_rows`; the whole file without that
    attribute) as positions along `case`, and the point as {parameter: value} of the
    per-case variables (grid axes and parameters, not the design's own) that are the
    same within each repetition and differ between them ({} for a single one)."""
    ids = ds["case"].values.astype(np.int64)
    rows = int(ds.attrs.get("design_rows", 0)) or None
    block = ids // rows if rows else np.zeros(ids.size, dtype=np.int64)
    blocks = np.unique(block)
    design = set(str(ds.attrs.get("design_parameters", "")).split(",")) | {"design_row"}
    candidates = list(dict.fromkeys(grid_axes(ds) + [
        str(v) for v in ds.data_vars if ds[v].attrs.get("studyrun_role") == "parameter"]))
    naming = []
    for name in candidates:
        if name in design or name not in ds or ds[name].dims != ("case",):
            continue
        values = ds[name].values
        keys = np.array([str(v) for v in values])  # NaN equal to NaN, as text
        within = [set(keys[block == b]) for b in blocks]
        if all(len(w) == 1 for w in within) and len(set.union(*within)) > 1:
            naming.append((name, [values[block == b][0] for b in blocks]))
    out = []
    for k, b in enumerate(blocks):
        point = {name: (str(v[k]) if isinstance(v[k], (str, bytes)) else float(v[k])) for name, v in naming}
        out.append((point, np.flatnonzero(block == b)))
    return out


def study_saltelli_points(ds, metric, resamples=1000, conf_level=0.95, seed=0):
    """`study_saltelli` at each grid point of a design repeated over grid axes
    (`design_points`): [Indices], each with its `point`."""
    out = []
    for point, positions in design_points(ds):
        indices = study_saltelli(ds.isel(case=positions), metric, resamples, conf_level, seed, whole=False)
        indices.point = point
        out.append(indices)
    return out


def study_saltelli(ds, metric, resamples=1000, conf_level=0.95, seed=0, whole=True):
    """`saltelli_indices` of the study's `metric` from the study's Saltelli design (the
    layout in this module's docstring): the parameters named by `design_parameters`,
    their per-case values as the sample matrix and the cases in case-id order. With
    `whole`, raises ValueError if the file repeats the design at several grid points
    (use `study_saltelli_points`, or select one point first)."""
    if str(ds.attrs.get("design_method", "")) != "saltelli":
        raise ValueError("the file has no Saltelli design (root attribute design_method is not 'saltelli')")
    if metric not in ds:
        raise ValueError(f"no metric {metric!r} in the file")
    names = [p for p in str(ds.attrs.get("design_parameters", "")).split(",") if p]
    missing = [p for p in names if p not in ds]
    if not names or missing:
        raise ValueError(f"design_parameters {names} name no per-case variables {missing}")
    if whole:
        points = design_points(ds)
        if len(points) > 1:
            shown = "; ".join(", ".join(f"{k} = {v}" for k, v in p.items()) or "?" for p, _ in points[:4])
            raise ValueError(f"the design is repeated at {len(points)} grid points ({shown}"
                             f"{', ...' if len(points) > 4 else ''}): analyse each alone "
                             "(study_saltelli_points, or select one point)")
    ds = ds.sortby("case")
    sample = np.column_stack([ds[p].values.astype(float) for p in names])
    second_order = bool(int(ds.attrs.get("design_second_order", 1)))
    return saltelli_indices({"names": names}, sample, ds[metric].values, second_order, resamples, conf_level, seed)


def plot_indices(indices, metric, out, dpi=90):
    """Bars of S1 and ST per parameter, with their intervals as error bars (none where
    exact); writes the PNG `out` and returns its path."""
    k = np.arange(len(indices.names))
    width = 0.38
    fig, ax = plt.subplots(figsize=(max(5.0, 1.3 * len(k) + 2), 4.2))
    exact = indices.method == "grid"
    for shift, values, conf, label in (
        (-width / 2, indices.first, indices.first_conf, "first order $S_i$"),
        (width / 2, indices.total, indices.total_conf, "total $S_{Ti}$"),
    ):
        ax.bar(k + shift, values, width, label=label,
               yerr=None if exact else conf, capsize=None if exact else 4)
    ax.set_xticks(k, indices.names, rotation=20 if len(k) > 4 else 0)
    ax.set_ylabel("share of the variance")
    ax.set_ylim(min(0.0, float(np.nanmin(indices.first - np.nan_to_num(indices.first_conf)))) - 0.02,
                max(1.0, float(np.nanmax(indices.total + np.nan_to_num(indices.total_conf)))) + 0.05)
    ax.axhline(0, color="black", linewidth=0.6)
    how = "exact, full grid" if exact else f"Saltelli design, {indices.conf_level:.0%} bootstrap intervals"
    where = f" at {indices.point_text()}" if indices.point else ""
    ax.set_title(f"{metric}{where}\n{how}; Σ S_i = {indices.first.sum():.3f}", fontsize=10)
    ax.legend(fontsize=9)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    out = Path(out)
    fig.savefig(out, dpi=dpi)
    plt.close(fig)
    return out


def analyse(study, metrics, method="auto", outdir=None, selections=(), resamples=1000, conf_level=0.95,
            seed=0, dpi=90):
    """Indices of each metric of the study file `study` ({metric: [Indices]}: one per
    grid point of a Saltelli design repeated over grid axes, each naming its `point`;
    else one); with `outdir`, one PNG per metric and point there
    (`sensitivity_<metric>.png`, or `sensitivity_<metric>_<k>.png` for point k of
    several). `method`: "grid", "saltelli", or "auto" (the Saltelli design if the file
    has one, else the grid)."""
    results = {}
    with open_study(study) as full:
        ds = restrict(full, selections)
        if method == "auto":
            method = "saltelli" if str(ds.attrs.get("design_method", "")) == "saltelli" else "grid"
        if method == "grid" and not grid_axes(ds):
            raise ValueError("the study has no grid axes: no grid indices")
        for metric in metrics:
            if method == "grid":
                results[metric] = [study_grid(ds, metric)]
            else:
                results[metric] = study_saltelli_points(ds, metric, resamples, conf_level, seed)
    if outdir is not None:
        outdir = Path(outdir)
        outdir.mkdir(parents=True, exist_ok=True)
        for metric, points in results.items():
            for k, indices in enumerate(points):
                name = f"sensitivity_{metric}.png" if len(points) == 1 else f"sensitivity_{metric}_{k}.png"
                plot_indices(indices, metric, outdir / name, dpi)
    return results


def main(argv=None):
    """Command line: see --help."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("study", help="study file written by studyrun (.h5)")
    parser.add_argument("--metric", action="append", required=True,
                        help="a [case] metric of the file, e.g. slider_acceleration_rms_deviation; repeatable")
    parser.add_argument("--method", choices=("auto", "grid", "saltelli"), default="auto",
                        help="grid: exact indices over the grid axes; saltelli: the file's Saltelli design; "
                             "auto (default): the design if the file has one, else the grid")
    parser.add_argument("--select", action="append", default=[], metavar="NAME=VALUE",
                        help="only cases with this parameter value, in the file's units "
                             "(e.g. location=crank_rod); repeatable")
    parser.add_argument("--out", help="directory for one PNG per metric (created if missing)")
    parser.add_argument("--resamples", type=int, default=1000, help="bootstrap resamples (default 1000)")
    parser.add_argument("--conf-level", type=float, default=0.95, help="level of the intervals (default 0.95)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the bootstrap (default 0)")
    parser.add_argument("--dpi", type=int, default=90, help="resolution of the PNGs (default 90)")
    args = parser.parse_args(argv)
    study_file_or_exit("sensitivity", args.study)
    try:
        results = analyse(args.study, args.metric, args.method, args.out, args.select, args.resamples,
                          args.conf_level, args.seed, args.dpi)
    except ValueError as e:
        raise SystemExit(f"sensitivity: {e}") from e
    for metric, points in results.items():
        for indices in points:
            print("\n".join(indices.table(metric)))


if __name__ == "__main__":
    main()
