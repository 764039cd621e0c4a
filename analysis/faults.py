"""The fault study's spectra at the defect pass frequencies (docs/faults.md).

Reads a file of `studies/faults.yaml`, and for every case with a defect finds the
pass frequency of its surface (docs/model.md §2.9, §7.3; mean race speeds as in
analysis/frequencies.py):

- outer race: N_b f_out (BPFO), inner race: N_b f_in (BPFI),
- ball: 2 f_spin = 2 (d_o / D) f_out with D = (d_o − d_i)/2 (the ball defect meets
  the outer and the inner race once per spin revolution),

and the one-sided amplitude of the bearing force spectrum there (the largest of the
bins within ±1 bin of each of the first three harmonics), beside the healthy bearing's
at the same location. Prints a Markdown table and writes one figure of the spectra.

    python analysis/faults.py faults.h5 --figure docs/img/faults_spectra.png
"""

import argparse
import math
import sys
from pathlib import Path

if __package__ in (None, ""):  # run as a script: make `analysis` importable
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from analysis.frequencies import race_speeds  # noqa: E402
from analysis.studyfile import BEARING_LOCATIONS, constant_rpm, open_study, study_file_or_exit, text  # noqa: E402

CHANNEL = "bearing_force"
RACES = ("outer", "inner", "ball")


def pass_frequency(race, location, rpm, balls, d_i, d_o):
    """The defect pass frequency (Hz) of a defect on `race` ("outer", "inner", "ball")."""
    omega_i, omega_o = race_speeds(location, rpm)
    omega_m = (omega_i * d_i + omega_o * d_o) / (d_i + d_o)
    f_in = abs(omega_i - omega_m) / (2 * math.pi)
    f_out = abs(omega_m - omega_o) / (2 * math.pi)
    if race == "outer":
        return balls * f_out
    if race == "inner":
        return balls * f_in
    ball_diameter = 0.5 * (d_o - d_i)
    return 2 * d_o / ball_diameter * f_out


def read(path):
    """The constant-speed bearing cases of a fault study file as a list of dicts, with
    spectra. A speed profile that runs as a constant speed (a ramp from a speed to the
    same speed, docs/model.md §1.5) counts as that speed (`studyfile.constant_rpm`); a
    run-up's lines sweep with the speed, and `ideal` cases have no bearing: both are
    left out. Raises ValueError if the file lacks the fault labels or the bearing force
    spectrum, or has no constant-speed bearing case with a defect."""
    with open_study(path) as full:
        needed = ["fault", "defect_race", f"{CHANNEL}_spectrum"]
        missing = [name for name in needed if name not in full]
        if missing:
            raise ValueError(f"{path}: no {', '.join(missing)}: expected a file of studies/faults.yaml "
                             f"(a study with defects whose `spectra.channels` include {CHANNEL})")
        ds = full[[name for name in full.data_vars if full[name].dims == ("case",)] + [f"{CHANNEL}_spectrum"]].load()
        freq = ds["frequency"].values
        cases = []
        for k in range(ds.sizes["case"]):
            rpm = constant_rpm(ds, k)
            location = text(ds["location"].values[k])
            if location not in BEARING_LOCATIONS or not np.isfinite(rpm) or int(ds["status"].values[k]) != 1:
                continue
            cases.append(
                {
                    "location": location,
                    "fault": text(ds["fault"].values[k]),
                    "race": text(ds["defect_race"].values[k]),
                    "width": float(ds["defect_width"].values[k]),
                    "depth": float(ds["defect_depth"].values[k]),
                    "rpm": rpm,
                    "balls": int(ds["ball_count"].values[k]),
                    "d_i": float(ds["inner_race_diameter"].values[k]),
                    "d_o": float(ds["outer_race_diameter"].values[k]),
                    "wall": float(ds["wall_time"].values[k]),
                    "spectrum": ds[f"{CHANNEL}_spectrum"].values[k],
                }
            )
    if not any(c["fault"] != "none" for c in cases):
        raise ValueError(f"{path}: no successful constant-speed bearing case with a defect (every such case has "
                         "fault none): expected a file of studies/faults.yaml")
    return freq, cases


def amplitude_near(freq, spectrum, f0):
    """Largest amplitude within ±1 bin of `f0`."""
    k = int(np.argmin(np.abs(freq - f0)))
    return float(spectrum[max(k - 1, 0) : k + 2].max())


def table(freq, cases):
    """Markdown rows: per defect case, its pass frequency and the spectrum there."""
    healthy = {c["location"]: c for c in cases if c["fault"] == "none"}
    rows = [
        "| location | fault | width (mm) | pass frequency (Hz) | amplitude at 1×, 2×, 3× (N) | healthy bearing there (N) |",
        "|---|---|---|---|---|---|",
    ]
    for c in cases:
        if c["fault"] == "none":
            continue
        fp = pass_frequency(c["race"], c["location"], c["rpm"], c["balls"], c["d_i"], c["d_o"])
        h = healthy.get(c["location"])
        got = [amplitude_near(freq, c["spectrum"], m * fp) for m in (1, 2, 3)]
        ref = [amplitude_near(freq, h["spectrum"], m * fp) for m in (1, 2, 3)] if h else []
        rows.append(
            f"| {c['location']} | {c['fault']} | {1e3 * c['width']:.1f} | {fp:.2f} | "
            + ", ".join(f"{a:.1f}" for a in got)
            + " | "
            + ", ".join(f"{a:.1f}" for a in ref)
            + " |"
        )
    return "\n".join(rows)


def figure(freq, cases, path, f_max=250.0):
    """Spectra of the bearing force: one row per location, one column per race, the
    two widths and the healthy bearing, the pass frequency and its harmonics marked."""
    locations = sorted({c["location"] for c in cases})
    fig, axes = plt.subplots(len(locations), 3, figsize=(13, 3.2 * len(locations)), sharex=True)
    axes = np.atleast_2d(axes)
    band = freq <= f_max
    for i, loc in enumerate(locations):
        healthy = [c for c in cases if c["location"] == loc and c["fault"] == "none"]
        for j, race in enumerate(RACES):
            ax = axes[i, j]
            for h in healthy:
                ax.semilogy(freq[band], h["spectrum"][band], color="0.6", lw=0.8, label="none")
            for c in cases:
                if c["location"] == loc and c["fault"] == race:
                    ax.semilogy(freq[band], c["spectrum"][band], lw=0.9, label=f"{race}, {1e3 * c['width']:.1f} mm")
            any_case = next(c for c in cases if c["location"] == loc)
            fp = pass_frequency(race, loc, any_case["rpm"], any_case["balls"], any_case["d_i"], any_case["d_o"])
            for m in range(1, int(f_max / fp) + 1):
                ax.axvline(m * fp, color="k", ls=":", lw=0.7)
            ax.set_title(f"{loc}: {race} defect, pass frequency {fp:.2f} Hz (dotted)", fontsize=9)
            ax.set_ylim(1e-2, None)
            if i == len(locations) - 1:
                ax.set_xlabel("frequency (Hz)")
            if j == 0:
                ax.set_ylabel(f"{CHANNEL} amplitude (N)")
            ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("file", help="a result file of studies/faults.yaml")
    p.add_argument("--figure", help="write the spectra figure here (PNG)")
    a = p.parse_args(argv)
    study_file_or_exit("faults", a.file)
    try:
        freq, cases = read(a.file)
    except ValueError as e:
        raise SystemExit(f"faults: {e}") from None
    print(table(freq, cases))
    print(f"\ncases: {len(cases)}, wall time per case: " + ", ".join(f"{c['wall']:.2f}" for c in cases) + " s")
    if a.figure:
        print("wrote", figure(freq, cases, a.figure))


if __name__ == "__main__":
    main()
