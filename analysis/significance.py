"""Which of the paper's differences are real: its comparisons with intervals.

    python analysis/significance.py STUDY.h5 [--metric slider_acceleration_rms_deviation]

STUDY.h5 is a study file with replicates (`replicates:` in the grid file, e.g.
studies/paper_replicates.yaml) over the paper's axes `location`, `rpm`,
`waviness_amplitude` and `ball_count`. For every case the metric's replicates
(`<metric>_replicates[case, replicate]`, docs/result-file.md#replicates) give a mean
and the file's 95 % Student t interval of the mean (`<metric>_mean`,
`<metric>_ci95`). Each of the paper's comparisons is printed as mean ± interval:

  - ball count 8 vs 9 vs 10 vs 11, per location, speed and waviness;
  - crank_ground vs crank_rod, per speed, waviness and ball count;
  - without vs with waviness, per location, speed and ball count;

then the paper's three findings, each stated as significant or not.

A difference between two cases is *significant* when Welch's two-sided t-test on
their replicates gives p < 0.05 (`scipy.stats.ttest_ind(equal_var=False)`) and the
difference exceeds `FLOOR` (1e-3) of the larger mean: the replicates of a
non-chaotic case agree to 1e-6 or better, so Welch's test alone would call
differences real that are far below the integrator's own metric error (at most
1.3e-4 on the paper's non-chaotic cases at the default tolerance,
docs/accuracy.md). Two cases whose replicates do not vary at all are compared by
the floor alone. The tests are per comparison, not corrected for multiplicity.
"""

import argparse
import itertools
import sys
from dataclasses import dataclass
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import h5py  # noqa: E402
import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

from analysis.studyfile import study_file_or_exit  # noqa: E402

ALPHA = 0.05
FLOOR = 1e-3
BALLS = (8, 9, 10, 11)
LOCATIONS = ("crank_ground", "crank_rod")


@dataclass
class Case:
    """One case of the study: its axes and the metric's replicate values."""

    location: str
    rpm: float
    waviness: float
    balls: int
    values: np.ndarray
    mean: float
    ci95: float
    chaotic: float


def load(path, metric):
    """The cases of the study file at `path` with the replicates of `metric`. Raises
    ValueError if the file has no replicates of `metric`."""
    with h5py.File(path, "r") as f:
        if "replicate" not in f:
            raise ValueError(f"{path}: no replicate dimension; run the study with `replicates:`")
        needed = [f"{metric}_replicates", f"{metric}_mean", f"{metric}_ci95"]
        if any(name not in f for name in needed):
            have = sorted(n[: -len("_replicates")] for n in f if n.endswith("_replicates"))
            raise ValueError(f"{path}: no replicates of {metric!r}; --metric takes one of {', '.join(have)}")
        location = [s.decode() if isinstance(s, bytes) else s for s in f["location"][()]]
        values = f[f"{metric}_replicates"][()]
        status = f["status"][()]
        chaotic = f["chaotic"][()] if "chaotic" in f else np.full(len(status), np.nan)
        cases = [
            Case(
                location=location[k],
                rpm=float(f["rpm"][k]),
                waviness=float(f["waviness_amplitude"][k]),
                balls=int(f["ball_count"][k]),
                values=values[k][~np.isnan(values[k])],
                mean=float(f[f"{metric}_mean"][k]),
                ci95=float(f[f"{metric}_ci95"][k]),
                chaotic=float(chaotic[k]),
            )
            for k in range(len(status))
            if status[k] == 1
        ]
    return cases


def compare(a, b):
    """(difference of the means b − a, Welch's p, significant) for two samples."""
    diff = float(np.mean(b) - np.mean(a))
    scale = max(abs(float(np.mean(a))), abs(float(np.mean(b))))
    above_floor = abs(diff) > FLOOR * scale
    if np.std(a) == 0 and np.std(b) == 0:
        return diff, (0.0 if above_floor else 1.0), above_floor
    p = float(stats.ttest_ind(a, b, equal_var=False).pvalue)
    return diff, p, bool(p < ALPHA and above_floor)


def below(a, b):
    """Whether case `a`'s metric is significantly below case `b`'s."""
    diff, _, sig = compare(b.values, a.values)
    return sig and diff < 0


def fmt(c):
    """`mean ± ci95` with the chaotic mark."""
    mark = " (chaotic)" if c.chaotic == 1 else ""
    return f"{c.mean:8.3f} ± {c.ci95:.2g}{mark}"


def index(cases):
    """The cases by (location, rpm, waviness, balls). Raises ValueError naming the
    combinations of the paper's grid (both locations × the file's speeds × its
    waviness amplitudes × 8–11 balls) that no successful case covers."""
    by = {(c.location, c.rpm, c.waviness, c.balls): c for c in cases}
    rpms = sorted({c.rpm for c in cases})
    wavs = sorted({c.waviness for c in cases})
    missing = [key for key in itertools.product(LOCATIONS, rpms, wavs, BALLS) if key not in by]
    if not cases or missing:
        shown = "; ".join(f"{loc}, {rpm:g} rpm, waviness {w * 1e6:g} um, {n} balls" for loc, rpm, w, n in missing[:4])
        more = f" and {len(missing) - 4} more" if len(missing) > 4 else ""
        raise ValueError(
            "the file is not on the paper's grid (locations crank_ground and crank_rod × speeds × waviness "
            f"amplitudes × ball counts {', '.join(map(str, BALLS))}, every case ok): "
            + (f"no successful case at {shown}{more}" if cases else "it has no successful case")
        )
    return by


def pair_line(label, a, b):
    """One comparison: both cases and the verdict; returns (b.mean > a.mean, significant)."""
    diff, p, sig = compare(a.values, b.values)
    verdict = "SIGNIFICANT" if sig else "not significant"
    print(f"    {label}: {fmt(a)} vs {fmt(b)}; difference {diff:+.3f} (p = {p:.2g}): {verdict}")
    return diff > 0, sig


def report(cases, metric):
    """Prints every comparison and the findings; returns the findings' verdicts."""
    by = index(cases)
    rpms = sorted({c.rpm for c in cases})
    wavs = sorted({c.waviness for c in cases})
    um = lambda w: f"{w * 1e6:g} um"  # noqa: E731
    print(f"metric: {metric}, mean ± 95 % interval over the replicates")
    print(f"significant: Welch p < {ALPHA} and |difference| > {FLOOR:g} of the larger mean\n")

    print("Ball count (8 vs 9 vs 10 vs 11):")
    worst8 = {}
    decreasing = {}
    best9 = {}
    for loc, rpm, w in itertools.product(LOCATIONS, rpms, wavs):
        group = [by[(loc, rpm, w, n)] for n in BALLS]
        print(f"  {loc}, {rpm:g} rpm, waviness {um(w)}: "
              + ", ".join(f"{n}: {fmt(c)}" for n, c in zip(BALLS, group)))
        for (i, a), (j, b) in itertools.combinations(enumerate(group), 2):
            pair_line(f"{BALLS[i]} vs {BALLS[j]}", a, b)
        # 8 significantly above every other count; 9 significantly below every other;
        # each count significantly below the one before.
        worst8[(loc, rpm, w)] = all(below(group[j], group[0]) for j in (1, 2, 3))
        best9[(loc, rpm, w)] = all(below(group[1], group[j]) for j in (0, 2, 3))
        decreasing[(loc, rpm, w)] = all(below(group[i + 1], group[i]) for i in range(3))

    print("\nLocation (crank_ground vs crank_rod):")
    rod_lower = {}
    for rpm, w, n in itertools.product(rpms, wavs, BALLS):
        up, s = pair_line(f"{rpm:g} rpm, {um(w)}, {n} balls",
                          by[("crank_ground", rpm, w, n)], by[("crank_rod", rpm, w, n)])
        rod_lower[(rpm, w, n)] = (not up) and s

    print("\nWaviness (off vs on):")
    wavier = {}
    for loc, rpm, n in itertools.product(LOCATIONS, rpms, BALLS):
        up, s = pair_line(f"{loc}, {rpm:g} rpm, {n} balls",
                          by[(loc, rpm, wavs[0], n)], by[(loc, rpm, wavs[-1], n)])
        wavier[(loc, rpm, n)] = up and s

    off, on = wavs[0], wavs[-1]
    count = lambda d, keep=lambda k: True: (  # noqa: E731
        sum(1 for k, v in d.items() if v and keep(k)), sum(1 for k in d if keep(k)))
    f1w = count(worst8, lambda k: k[2] == off)
    f1d = count(decreasing, lambda k: k[2] == off)
    f2a = count(wavier)
    f2w = count(worst8, lambda k: k[2] == on)
    f2b = count(best9, lambda k: k[2] == on)
    f3 = count(rod_lower, lambda k: k[1] == on)
    f3off = count(rod_lower, lambda k: k[1] == off)
    print("\nThe paper's findings (groups where the statement holds significantly):")
    print(f"  1. without waviness 8 balls is the worst: {f1w[0]} of {f1w[1]} groups; "
          f"the deviation falls significantly from each ball count to the next: {f1d[0]} of {f1d[1]}")
    print(f"  2a. waviness raises the deviation: {f2a[0]} of {f2a[1]} pairs")
    print(f"  2b. with waviness 8 balls is the worst: {f2w[0]} of {f2w[1]} groups; "
          f"9 balls the best: {f2b[0]} of {f2b[1]}")
    print(f"  3. crank_rod below crank_ground with waviness: {f3[0]} of {f3[1]} pairs "
          f"(without waviness: {f3off[0]} of {f3off[1]})")
    return {"1_worst8": f1w, "1_decreasing": f1d, "2a": f2a, "2b_worst8": f2w,
            "2b_best9": f2b, "3": f3, "3_off": f3off}


def figure(cases, metric, path, dpi=110):
    """The metric's mean ± 95 % interval against ball count, one panel per location
    and waviness amplitude, one line per speed; hollow markers are chaotic cases.
    Writes the PNG at `path` and returns it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    waviness = sorted({c.waviness for c in cases})
    speeds = sorted({c.rpm for c in cases})
    fig, axes = plt.subplots(
        len(waviness), len(LOCATIONS), figsize=(10, 3.4 * len(waviness)), squeeze=False, sharex=True
    )
    colours = dict(zip(speeds, plt.rcParams["axes.prop_cycle"].by_key()["color"]))
    for (i, w), (j, loc) in itertools.product(enumerate(waviness), enumerate(LOCATIONS)):
        ax = axes[i][j]
        for rpm in speeds:
            line = sorted((c for c in cases if c.location == loc and c.waviness == w and c.rpm == rpm),
                          key=lambda c: c.balls)
            if not line:
                continue
            x = [c.balls for c in line]
            y = [c.mean for c in line]
            err = [c.ci95 for c in line]
            colour = colours[rpm]
            ax.errorbar(x, y, yerr=err, capsize=4, marker="o", color=colour, label=f"{rpm:g} rpm")
            for c in line:
                if c.chaotic == 1:
                    ax.plot(c.balls, c.mean, "o", mfc="white", mec=colour, ms=9)
        ax.set_title(f"{loc}, waviness {w * 1e6:g} µm")
        ax.set_xticks(BALLS)
        ax.grid(alpha=0.3)
        if i == len(waviness) - 1:
            ax.set_xlabel("ball count")
        if j == 0:
            ax.set_ylabel("mean ± 95 % interval")
        ax.legend(fontsize=8)
    fig.suptitle(f"{metric} over the replicates; hollow markers: chaotic cases (replicates part)")
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("study", help="study file with replicates")
    parser.add_argument("--metric", default="slider_acceleration_rms_deviation")
    parser.add_argument("--figure", help="also write the metric per ball count as this PNG")
    args = parser.parse_args(argv)
    study_file_or_exit("significance", args.study, needs=("replicate",),
                       kind="a study file with replicates (`replicates:` in the grid file)")
    try:
        cases = load(args.study, args.metric)
        index(cases)
    except ValueError as e:
        raise SystemExit(f"significance: {e}") from None
    report(cases, args.metric)
    if args.figure:
        print("wrote", figure(cases, args.metric, args.figure))


if __name__ == "__main__":
    main()
