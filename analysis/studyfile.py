"""Reading `studyrun` study files (flat netCDF-4 HDF5) with xarray.

A study file has the dimensions `case`, `time`, `frequency` and `reference`;
per-case parameters and metrics are `[case]`, series `[case, time]`, spectra
`[case, frequency]`, and the ideal mechanism's series `[reference, time]` with
`reference_index[case]` saying which reference each case is compared with.
Units are the file's: SI (m, kg, s, N, rad), crank speed in rpm.

Only h5py/xarray read the file; `studyrun` itself is never called.
"""

import math
import numpy as np
import pandas as pd
import xarray as xr

BEARING_LOCATIONS = ("crank_ground", "crank_rod")
"""Locations of the bearing in the slider-crank; `ideal` is the third, bearing-free one."""

IDEAL_CHANNELS = (
    "slider_acceleration",
    "crank_moment",
    "crank_ground_force_x",
    "crank_ground_force_y",
    "crank_rod_force_x",
    "crank_rod_force_y",
)
"""The series stored for the ideal mechanism as `reference_<channel>` ([reference, time])."""


def open_study(path):
    """Open a study file as an xarray Dataset (engine h5netcdf, read lazily).

    The variables keep the file's units (`units` attribute of each). Close the
    dataset (or use it in a `with` block) when done; `.load()` reads it all.
    """
    return xr.open_dataset(path, engine="h5netcdf")


def grid_axes(ds):
    """The study's grid axes in file order (root attribute `grid_axes`), [] if none."""
    return [axis for axis in str(ds.attrs.get("grid_axes", "")).split(",") if axis]


def unstack(ds):
    """Turn the `case` dimension into the grid's own dimensions.

    `unstack(ds).sel(ball_count=9, rpm=300)` then works; `location` becomes a
    string coordinate, numeric axes keep the file's units (e.g. waviness_amplitude
    in m, rpm in rpm). The grid axes come first, in file order, then time or
    frequency; coordinates are sorted ascending. The case ids become the variable `case_id` over the grid
    axes. Combinations a study did not run (zipped axes) are NaN.

    Raises ValueError if the study has no grid axes, or if the axes do not tell its
    cases apart (extra `cases:` that differ in a parameter that is not an axis).
    """
    axes = grid_axes(ds)
    if not axes:
        raise ValueError("the study has no grid axes (explicit cases only): nothing to unstack")
    index = pd.MultiIndex.from_arrays([ds[axis].values for axis in axes], names=axes)
    if not index.is_unique:
        raise ValueError(
            f"the grid axes {axes} do not identify the cases uniquely "
            "(cases added outside the grid?); select cases with select_cases() instead"
        )
    flat = ds.assign(case_id=ds["case"].astype("int64")).drop_vars("case")
    return flat.set_index(case=axes).unstack("case").transpose(*axes, ...)


def select_cases(ds, **params):
    """Positions along `case` whose parameters equal `params` (an array of int).

    Numbers are compared with a relative tolerance of 1e-9 in the file's units
    (e.g. `waviness_amplitude=4e-6` in m, `rpm=300` in rpm), NaN matching NaN (a
    both-races parameter where the races differ); strings exactly.
    """
    mask = np.ones(ds.sizes["case"], dtype=bool)
    for name, value in params.items():
        values = ds[name].values
        if values.dtype.kind in "USO":
            mask &= values == value
        else:
            mask &= np.isclose(values, value, rtol=1e-9, atol=0.0, equal_nan=True)
    return np.flatnonzero(mask)


def analysis_window(ds):
    """Boolean mask over `time`: the samples at transient <= t < duration (s), the
    window the stored metrics and spectra use. It is half-open (the last sample, at
    t = duration, is left out) so that a window of whole crank revolutions holds
    each crank phase once; its first sample is the first at or after the transient
    (to within 1e-9 of a sample interval), found by index as studyrun does."""
    n = ds.sizes["time"]
    start = max(0, math.ceil(float(ds.attrs["transient"]) * float(ds.attrs["sample_rate"]) - 1e-9))
    k = np.arange(n)
    return (k >= start) & (k < n - 1)


def _ideal_joint_force(ds, refs):
    """|F| (N) of the ideal mechanism's joint at each case's bearing location, NaN for
    `ideal` cases (they have no bearing). `refs` holds the per-case reference forces."""
    magnitude = {
        loc: np.hypot(refs[f"{loc}_force_x"], refs[f"{loc}_force_y"]) for loc in BEARING_LOCATIONS
    }
    location = ds["location"]
    force = xr.where(
        location == "crank_rod",
        magnitude["crank_rod"],
        xr.where(location == "crank_ground", magnitude["crank_ground"], np.nan),
    )
    return force.assign_attrs(
        units="N", long_name="ideal mechanism: |F| of the joint at the case's bearing location"
    )


def reference_for(ds, channels=None):
    """Each case's ideal-mechanism series (same speed and sample times), as a Dataset.

    `ds` is the flat study (dimension `case`). The result has variables
    `[case, time]` named like the case's own series: the `IDEAL_CHANNELS` (units of
    the file: m s-2, N m, N) and `bearing_force`, the ideal joint's |F| (N) at the
    case's bearing location (crank_ground: crank_ground_force_x/y; crank_rod:
    crank_rod_force_x/y; NaN for `ideal` cases), the quantity the stored
    bearing_force metrics compare with. `channels` limits the result to some of
    these names.
    """
    wanted = list(IDEAL_CHANNELS) + ["bearing_force"] if channels is None else list(channels)
    unknown = set(wanted) - set(IDEAL_CHANNELS) - {"bearing_force"}
    if unknown:
        raise ValueError(f"no ideal-mechanism series for {sorted(unknown)}")
    rows = ds["reference_index"].astype("int64")
    needed = set(wanted) & set(IDEAL_CHANNELS)
    if "bearing_force" in wanted:
        needed |= {f"{loc}_force_{c}" for loc in BEARING_LOCATIONS for c in "xy"}
    refs = {
        name: ds[f"reference_{name}"].isel(reference=rows).drop_vars("reference", errors="ignore")
        for name in sorted(needed)
    }
    out = {name: refs[name] for name in wanted if name in refs}
    if "bearing_force" in wanted:
        out["bearing_force"] = _ideal_joint_force(ds, refs)
    return xr.Dataset({name: out[name] for name in wanted})


def amplitude_spectrum(x, sample_rate):
    """One-sided amplitude spectrum as studyrun stores it: periodic Hann window,
    scaled so that a sinusoid of amplitude A on a bin reads A; mean not removed.

    `x` is a 1-D series sampled at `sample_rate` (Hz); returns (frequencies in Hz,
    amplitudes in the series' units).
    """
    x = np.asarray(x, dtype=float)
    n = len(x)
    window = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)
    amplitude = np.abs(np.fft.rfft(x * window)) / window.sum()
    amplitude[1 : (n + 1) // 2] *= 2
    return np.fft.rfftfreq(n, 1.0 / sample_rate), amplitude
