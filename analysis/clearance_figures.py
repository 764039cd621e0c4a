"""Figures of the clearance-joint benchmark (studies/clearance.yaml, docs/model.md
§3.10): the slider acceleration of dry journals of every clearance against the ideal
mechanism, the journal centre's orbit inside its clearance circle, and the joint's
contact force; and, of the bifurcation sweep (studies/clearance_bifurcation.yaml), the
Poincaré sections of the slider acceleration over crank speed for each clearance. Each
function writes one PNG and returns its path; it raises ValueError when the study lacks
what it needs.

`ds` is the flat study Dataset of `studyfile.open_study`; the cases drawn are the
successful `dry_clearance` cases at one crank speed `rpm` and friction coefficient
`friction`, one curve per radial clearance `journal_clearance`, largest first.

    python analysis/clearance_figures.py clearance.h5 docs/img [--rpm 5000] [--friction 0.01]
    python analysis/clearance_figures.py clearance_bifurcation.h5 docs/img --bifurcation

A missing or non-HDF5 file ends the program with a one-line message.
"""

import argparse
import math
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import numpy as np  # noqa: E402

from analysis.figures import _save, plt  # noqa: E402
from analysis.studyfile import (  # noqa: E402
    open_study,
    parameter_value,
    reference_for,
    study_file_or_exit,
    text,
)

DRY = "dry_clearance"
"""The `joint` label of a dry clearance joint."""


def dry_cases(ds, rpm, friction):
    """{radial clearance (m): case position} of the successful dry journals at `rpm`
    with friction coefficient `friction`, largest clearance first."""
    found = {}
    for case in range(ds.sizes["case"]):
        if text(ds["joint"].values[case]) != DRY or ds["status"].values[case] != 1:
            continue
        if parameter_value(ds, "rpm", case) == rpm and parameter_value(ds, "journal_friction_coefficient", case) == friction:
            found[parameter_value(ds, "journal_clearance", case)] = case
    if not found:
        raise ValueError(f"no successful {DRY} case at {rpm} rpm with friction coefficient {friction}")
    return dict(sorted(found.items(), reverse=True))


def _need(ds, *names):
    """Raise ValueError naming the first series of `names` the study does not store."""
    for name in names:
        if name not in ds:
            raise ValueError(f"the study stores no {name} series (see its `output.series`)")


def _label(clearance):
    """A curve's label: the radial clearance in mm."""
    return f"c = {clearance * 1e3:g} mm"


def _title(rpm, friction):
    """The cases a figure draws, for its title."""
    return f"dry journal at rod_slider, {rpm:g} rpm, μ = {friction:g}"


def slider_acceleration(ds, out, rpm, friction, dpi=150):
    """The slider acceleration (m/s²) of each clearance against the ideal mechanism's,
    over the stored time."""
    _need(ds, "slider_acceleration")
    cases = dry_cases(ds, rpm, friction)
    ideal = reference_for(ds, ["slider_acceleration"])["slider_acceleration"]
    t = ds["time"].values
    fig, axes = plt.subplots(len(cases), 1, sharex=True, squeeze=False, figsize=(8.0, 1.8 * len(cases) + 0.8))
    for ax, (clearance, case) in zip(axes[:, 0], cases.items()):
        ax.plot(t, ds["slider_acceleration"].values[case], lw=0.6, color="tab:red", label=_label(clearance))
        ax.plot(t, ideal.values[case], lw=1.0, color="black", ls="--", label="ideal joint")
        ax.set_ylabel("m/s²")
        ax.legend(loc="upper right", fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    fig.suptitle(f"Slider acceleration: {_title(rpm, friction)}")
    return _save(fig, out, dpi)


def orbit(ds, out, rpm, friction, dpi=150):
    """The journal centre's path relative to the bushing's, in units of its radial
    clearance, inside the clearance circle (|e| = c: contact begins)."""
    _need(ds, "eccentricity_x", "eccentricity_y")
    cases = dry_cases(ds, rpm, friction)
    fig, axes = plt.subplots(1, len(cases), squeeze=False, figsize=(3.2 * len(cases), 3.6))
    circle = np.linspace(0.0, 2.0 * math.pi, 361)
    for ax, (clearance, case) in zip(axes[0], cases.items()):
        ex = ds["eccentricity_x"].values[case] / clearance
        ey = ds["eccentricity_y"].values[case] / clearance
        ax.plot(np.cos(circle), np.sin(circle), color="black", lw=0.8)
        ax.plot(ex, ey, lw=0.5, color="tab:blue")
        ax.set_aspect("equal")
        ax.set_title(_label(clearance), fontsize=9)
        ax.set_xlabel("e_x / c")
    axes[0, 0].set_ylabel("e_y / c")
    fig.suptitle(f"Journal orbit in the clearance circle: {_title(rpm, friction)}")
    return _save(fig, out, dpi)


def contact_force(ds, out, rpm, friction, dpi=150):
    """|F| (N) at the joint for each clearance, with the ideal joint's, log scale."""
    _need(ds, "bearing_force")
    cases = dry_cases(ds, rpm, friction)
    t = ds["time"].values
    fig, ax = plt.subplots(figsize=(8.0, 3.6))
    for clearance, case in cases.items():
        ax.plot(t, ds["bearing_force"].values[case], lw=0.6, label=_label(clearance))
    ax.set_yscale("symlog", linthresh=1.0)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("|F| (N)")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"Contact force: {_title(rpm, friction)}", fontsize=10)
    return _save(fig, out, dpi)


def poincare(ds, case, series, last=0.5):
    """`series` (one value per stored time) of `case` at the sample nearest each whole
    crank revolution `k · 60 / rpm` in the `last` fraction of the stored time: its
    Poincaré section (a period-n motion gives n points, a chaotic one a spread)."""
    t = ds["time"].values
    period = 60.0 / parameter_value(ds, "rpm", case)
    dt = t[1] - t[0]
    first = t[0] + (1.0 - last) * (t[-1] - t[0])
    revolutions = np.arange(math.ceil(first / period), math.floor(t[-1] / period) + 1)
    index = np.rint((revolutions * period - t[0]) / dt).astype(int)
    return series[index[(index >= 0) & (index < len(t))]]


def bifurcation(ds, out, dpi=150):
    """Poincaré sections of the slider acceleration against crank speed, one panel per
    radial clearance (largest first), beside the ideal mechanism's (black bars); a point
    whose replicates part (`chaotic`) is drawn in red, with the number of such points in
    the panel's title."""
    _need(ds, "slider_acceleration", "chaotic")
    acceleration = ds["slider_acceleration"].values
    ideal = reference_for(ds, ["slider_acceleration"])["slider_acceleration"].values
    points = {}
    for case in range(ds.sizes["case"]):
        if text(ds["joint"].values[case]) == DRY and ds["status"].values[case] == 1:
            points.setdefault(parameter_value(ds, "journal_clearance", case), []).append(case)
    if not points:
        raise ValueError(f"no successful {DRY} case")
    fig, axes = plt.subplots(len(points), 1, sharex=True, squeeze=False, figsize=(7.0, 1.5 * len(points) + 0.9))
    for ax, (clearance, cases) in zip(axes[:, 0], sorted(points.items(), reverse=True)):
        chaotic = 0
        for case in cases:
            rpm = parameter_value(ds, "rpm", case)
            section = poincare(ds, case, acceleration[case]) / 1e3
            flag = bool(ds["chaotic"].values[case])
            chaotic += flag
            ax.plot(np.full(section.shape, rpm), section, ".", ms=3, color="tab:red" if flag else "tab:blue")
            ax.plot([rpm], [poincare(ds, case, ideal[case])[-1] / 1e3], "_", ms=14, color="black")
        ax.set_ylabel("km/s²")
        ax.set_title(f"{_label(clearance)}: {chaotic} of {len(cases)} speeds chaotic", fontsize=8)
    axes[-1, 0].set_xlabel("crank speed (rpm)")
    fig.suptitle("Poincaré sections of the slider acceleration, dry journal at rod_slider")
    return _save(fig, out, dpi)


FIGURES = {"slider_acceleration": slider_acceleration, "orbit": orbit, "contact_force": contact_force}
"""The figures, by the suffix of their file name."""


def draw(ds, outdir, rpm, friction, dpi=150):
    """Every figure of `FIGURES` into `outdir` as `clearance_<name>_<rpm>rpm_mu<friction>.png`;
    returns their paths."""
    stem = f"{rpm:g}rpm_mu{friction:g}"
    return [f(ds, f"{outdir}/clearance_{name}_{stem}.png", rpm, friction, dpi) for name, f in FIGURES.items()]


def main(argv=None):
    parser = argparse.ArgumentParser(description="Figures of the clearance-joint benchmark")
    parser.add_argument("study", help="the result of studyrun studies/clearance.yaml")
    parser.add_argument("outdir", help="directory of the PNGs")
    parser.add_argument("--rpm", type=float, default=5000.0, help="crank speed of the cases drawn (rpm)")
    parser.add_argument("--friction", type=float, default=0.01, help="friction coefficient of the cases drawn")
    parser.add_argument("--bifurcation", action="store_true", help="draw the bifurcation sweep's Poincaré sections instead")
    args = parser.parse_args(argv)
    study_file_or_exit("clearance_figures", args.study)
    with open_study(args.study) as ds:
        ds = ds.load()
        if args.bifurcation:
            print(bifurcation(ds, f"{args.outdir}/clearance_bifurcation.png"))
            return 0
        for path in draw(ds, args.outdir, args.rpm, args.friction):
            print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
