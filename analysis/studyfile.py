"""Reading `studyrun` study files (flat netCDF-4 HDF5) with xarray.

A study file has the dimensions `case`, `time`, `frequency` and `reference`;
per-case parameters and metrics are `[case]`, series `[case, time]`, spectra
`[case, frequency]`, and the ideal mechanism's series `[reference, time]` with
`reference_index[case]` saying which reference each case is compared with.
Units are the file's: SI (m, kg, s, N, rad), crank speed in rpm. `time` is a CF time
coordinate (units `seconds since 1970-01-01 00:00:00`, a nominal date): the helpers here open
files with `decode_times=False`, so it stays seconds from the start of the simulation
(plain `xr.open_dataset` decodes it to datetimes).

open_study opens one file; open_shards opens the shard files of one study
(`studyrun ... --shard K/N`) as one Dataset ordered by case id, as `studyrun merge`
would combine them. A path that is missing or not an HDF5 file raises StudyFileError
(a ValueError) with a one-line message; the command-line scripts exit with it through
study_file_or_exit.

Only h5py/xarray read the file; `studyrun` itself is never called.
"""

import functools
import glob
import math
import os

import h5py
import numpy as np
import pandas as pd
import xarray as xr

OPEN_OPTIONS = {"engine": "h5netcdf", "decode_times": False}
"""How xarray opens a study file here: through h5netcdf, `time` in seconds."""

NUMBER_UNITS = {"stiffness": "N/m^1.5"}
"""The unit of a variable's numbers where its `units` state another quantity: the file
holds the Hertz stiffness K as the force at 1 m of deflection (N), whose number is K in
N/m^1.5 (UDUNITS has no half powers)."""

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


class StudyFileError(ValueError):
    """A path that cannot be read as the study file wanted; the message names the path
    and says what is wrong (missing, not HDF5, a variable the file lacks)."""


def check_study_file(path, needs=(), kind="a study file written by studyrun"):
    """Raise StudyFileError unless `path` is an existing HDF5 file that holds every
    variable or dimension named in `needs`; `kind` says what file is expected, in the
    message (e.g. "an accuracy file of `studyrun accuracy GRID.yaml`")."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise StudyFileError(f"{path}: no such file; expected {kind}")
    if not os.path.isfile(path):
        raise StudyFileError(f"{path}: not a file; expected {kind}")
    try:
        hdf5 = h5py.is_hdf5(path)
    except OSError as e:
        raise StudyFileError(f"{path}: cannot be read ({e.strerror or e})") from e
    if not hdf5:
        raise StudyFileError(f"{path}: not an HDF5 file; expected {kind}")
    if needs:
        try:
            with h5py.File(path, "r") as f:
                missing = [name for name in needs if name not in f]
        except OSError as e:
            raise StudyFileError(f"{path}: an HDF5 file that cannot be opened ({e})") from e
        if missing:
            raise StudyFileError(f"{path}: no {', '.join(missing)}: not {kind}")


def study_file_or_exit(program, path, needs=(), kind="a study file written by studyrun"):
    """`check_study_file` for a command line: returns `path` if it passes, else exits
    with status 1 and the one-line message `program: reason` (no traceback)."""
    try:
        check_study_file(path, needs, kind)
    except StudyFileError as e:
        raise SystemExit(f"{program}: {e}") from None
    return path


def open_study(path):
    """Open a study file as an xarray Dataset (engine h5netcdf, read lazily).

    The variables keep the file's units (`units` attribute of each); `time` is in
    seconds from the start of the simulation (not decoded to dates). Close the
    dataset (or use it in a `with` block) when done; `.load()` reads it all. Raises
    StudyFileError if the path `path` does not exist or is not an HDF5 file (an open
    file object is passed to xarray as it is).
    """
    if isinstance(path, (str, os.PathLike)):
        check_study_file(path)
    return xr.open_dataset(path, **OPEN_OPTIONS)


def number_units(ds, name):
    """The unit the numbers of variable `name` are in: its `units` (`1` if none), but
    N/m^1.5 for the stiffness (NUMBER_UNITS)."""
    return NUMBER_UNITS.get(name, str(ds[name].attrs.get("units", "1")))


def text(value):
    """A string parameter's value as str (h5py gives variable-length UTF-8 as bytes)."""
    return value.decode() if isinstance(value, bytes) else str(value)


def parameter_value(ds, name, case):
    """The float value of parameter `name` of `case`, NaN if the file lacks it."""
    return float(ds[name].values[case]) if name in ds else math.nan


def constant_rpm(ds, case):
    """The crank speed (rpm) of a constant-speed case, NaN for a speed that varies:
    `rpm`, or a ramp whose `speed_from` equals `speed_to`, or a sine of amplitude 0
    (each runs as the constant drive, docs/model.md §1.5; studyrun stores their speed
    as `rpm`, a file with `rpm` NaN there is read the same). `ds` is the flat study (an
    xarray Dataset) and `case` a position along `case`."""
    rpm = parameter_value(ds, "rpm", case)
    if math.isfinite(rpm):
        return rpm
    profile = text(ds["speed_profile"].values[case]) if "speed_profile" in ds else "constant"
    if profile == "ramp" and parameter_value(ds, "speed_from", case) == parameter_value(ds, "speed_to", case):
        return parameter_value(ds, "speed_from", case)
    if profile == "sine" and parameter_value(ds, "speed_amplitude", case) == 0.0:
        return parameter_value(ds, "speed_mean", case)
    return math.nan


def _has_dask():
    try:
        import dask  # noqa: F401
    except ImportError:
        return False
    return True


def _same(a, b):
    """Attribute values equal (arrays element-wise, NaN equal to NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        if a.shape != b.shape or a.dtype.kind != b.dtype.kind:
            return False
        return bool(np.array_equal(a, b, equal_nan=a.dtype.kind in "fc"))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return type(a) is type(b) and a == b


def _combine_shard_attrs(attrs_list, context=None):
    """Attributes of the shards combined: kept where every shard has the same value,
    `history` the shards' distinct lines in order, `shard` empty where the shards
    differ (as in a merged file), the rest (`created`, `file_cases`, ...) dropped. Raises ValueError if `study_fingerprint` differs (other studies)."""
    fingerprints = {str(a["study_fingerprint"]) for a in attrs_list if "study_fingerprint" in a}
    if len(fingerprints) > 1:
        raise ValueError(
            f"the files are shards of different studies (study_fingerprint {sorted(fingerprints)})"
        )
    keys = list(dict.fromkeys(k for a in attrs_list for k in a))
    out = {}
    for key in keys:
        values = [a[key] for a in attrs_list if key in a]
        if key == "history":
            lines = (line for v in values for line in str(v).splitlines() if line.strip())
            out[key] = "\n".join(dict.fromkeys(lines))
        elif len(values) == len(attrs_list) and all(_same(values[0], v) for v in values[1:]):
            out[key] = values[0]
        elif key == "shard":
            out[key] = ""  # several shards together: no one shard (as `studyrun merge` writes)
    return out


def _attribute(path, name):
    """Root attribute `name` of the HDF5 file `path` as a Python scalar or str, None if
    absent (netCDF tools may store a text attribute as bytes or a one-element array)."""
    with h5py.File(path, "r") as f:
        if name not in f.attrs:
            return None
        value = f.attrs[name]
    if isinstance(value, np.ndarray):
        value = value.reshape(-1)[0] if value.size == 1 else value
    if isinstance(value, (bytes, np.bytes_)):
        return value.decode()
    return value.item() if isinstance(value, np.generic) else value


def _shard_numbers(paths):
    """{path: (K, N)} of the files whose `shard` attribute is `K/N`."""
    out = {}
    for path in paths:
        k, sep, n = str(_attribute(path, "shard") or "").partition("/")
        if sep and k.strip().isdigit() and n.strip().isdigit():
            out[path] = (int(k), int(n))
    return out


def _check_complete(paths, case_ids, study_cases):
    """Raise ValueError unless the case ids of the files `paths` are every case of the
    study (0 .. study_cases − 1), as `studyrun merge` requires, naming the shards
    (`shard` = K/N) or the case ids missing."""
    if study_cases is None:
        raise ValueError(
            f"{paths[0]} has no study_cases attribute, so whether the shards are complete cannot be "
            "checked; pass partial=True to open these files alone"
        )
    missing = np.setdiff1d(np.arange(int(study_cases)), case_ids)
    if missing.size == 0:
        return
    numbers = _shard_numbers(paths)
    given = ", ".join(f"{os.path.basename(p)} = {k}/{n}" for p, (k, n) in numbers.items())
    counts = {n for _, n in numbers.values()}
    if len(counts) == 1:
        n = counts.pop()
        absent = sorted({int(i) % n + 1 for i in missing})
        what = "shard " + ", ".join(f"{k}/{n}" for k in absent) + (" is" if len(absent) == 1 else " are")
        what += f" missing (given: {given})"
    else:
        shown = ", ".join(str(int(i)) for i in missing[:10]) + (", ..." if missing.size > 10 else "")
        what = f"case ids {shown} are in none of them" + (f" (given: {given})" if given else "")
    raise ValueError(
        f"the files hold {len(case_ids)} of the study's {int(study_cases)} cases: {what}; "
        "pass every shard, or partial=True to open these alone"
    )


TIME_REWRITE_TOLERANCE = 2e-9
"""How far (s) a tool's rewrite may have moved a time: decoding `time` to datetime64[ns]
(xarray's default) truncates to the nanosecond, and writing it back keeps that."""


def written_times(ds):
    """`ds` with `time` put back to the times studyrun writes, `j·decimate / sample_rate`,
    when every time is within TIME_REWRITE_TOLERANCE of them (as `studyrun merge` reads
    them); otherwise, or without `time`, `ds` as it is."""
    if "time" not in ds.coords or "sample_rate" not in ds.attrs or "decimate" not in ds.attrs:
        return ds
    steps = np.arange(ds.sizes["time"], dtype=np.int64) * int(ds.attrs["decimate"])
    written = steps.astype(np.float64) / float(ds.attrs["sample_rate"])
    if not np.all(np.abs(ds["time"].values - written) <= TIME_REWRITE_TOLERANCE):
        return ds
    # Rebuilt in the file's variable order (assign_coords would move `time` last).
    time = ds.variables["time"].copy(data=written)
    out = xr.Dataset(
        {name: time if name == "time" else var for name, var in ds.variables.items()}, attrs=ds.attrs
    )
    return out.set_coords([name for name in ds.coords if name not in out.coords])


# The attribute holding the checksum of a string variable's strings in its own file:
# studyrun checks it when it reads the file; a set of shards opened together has no
# one file whose strings it sums.
STRINGS_CHECKSUM = "studyrun_crc32"


def _shard_part(ds, refs=None):
    """One shard as open_shards combines it: written_times, its string variables
    without their file's STRINGS_CHECKSUM, and, with `refs` (_shard_references), the
    references of every shard in place of its own (a shard holds those its cases use),
    `reference_index` pointing into them."""
    ds = written_times(ds)
    for var in ds.variables.values():
        var.attrs.pop(STRINGS_CHECKSUM, None)
    if refs is not None and "reference_index" in ds:
        index = ds["reference_index"]
        ids = ds["reference"].values[index.values.astype("int64")]
        rows = np.searchsorted(refs["reference"].values, ids)
        ds = ds.reindex(reference=refs["reference"].values)
        for name, var in refs.data_vars.items():
            ds[name] = var
        ds["reference"] = refs["reference"]
        ds["reference_index"] = index.copy(data=rows.astype(index.dtype))
    return ds


def _shard_references(paths):
    """The `[reference]` and `[reference, ...]` variables of every shard, each
    reference once, in id order; ValueError if two shards disagree on one."""
    parts = []
    for path in paths:
        with xr.open_dataset(path, **OPEN_OPTIONS) as part:
            names = [n for n, v in part.data_vars.items() if "reference" in v.dims]
            refs = written_times(part[names].load())
            for var in refs.variables.values():
                var.attrs.pop(STRINGS_CHECKSUM, None)
            parts.append(refs)
    every = xr.concat(parts, dim="reference", data_vars="all", coords="minimal", join="exact",
                      combine_attrs="override")
    ids, first, inverse = np.unique(
        every["reference"].values, return_index=True, return_inverse=True)
    refs = every.isel(reference=first)
    for name, var in every.data_vars.items():
        kept, have = refs[name].values[inverse], var.values
        same = (kept == have) | (pd.isnull(kept) & pd.isnull(have))
        if not np.all(same):
            raise ValueError(f"the shards hold different `{name}` for one reference")
    return refs


def open_shards(paths, lazy=None, partial=False):
    """Open the shard files of one study (`studyrun ... --shard K/N`) as one Dataset
    ordered by case id: the variables and values `studyrun merge` would write, without
    writing a merged file.

    `paths` is a list of files in any order, or a glob pattern (`"part*.h5"`). Variables
    over `case` are concatenated and sorted by case id; the `reference` runs (a shard
    holds those its cases use) are gathered by id, `reference_index` pointing into
    them; the others (`time`, `frequency`) must be the same in every shard and are
    kept once (times
    a tool's datetime round trip moved by a nanosecond are put back: written_times;
    the checksum of each file's strings, STRINGS_CHECKSUM, is dropped). Root
    attributes that every shard has alike are kept, `history` holds the shards' lines,
    `file_cases` becomes the number of cases opened and `shard` is empty, as in a
    merged file (`created` and other differing attributes are dropped).

    As `studyrun merge` does, the files must hold every case of the study (the root
    attribute `study_cases`) once: a missing shard is refused with the shards (or case
    ids) missing named. `partial=True` opens the files given even so, e.g. the shards
    finished so far; `file_cases` then says how many cases the Dataset holds.

    `lazy`: read the data on demand through dask (`xr.open_mfdataset`); the default is
    to do so when dask is installed, else every shard is read into memory. Close the
    result (or use it in a `with` block) when done.

    Raises StudyFileError (a ValueError) for a missing or non-HDF5 file, and ValueError
    if no file matches, a file is given twice, the files are shards of different
    studies (`study_fingerprint`), a case id is in more than one file, the reference
    runs, times or frequencies differ between files, or (without `partial`) cases of
    the study are in none of the files.

    (`xr.open_mfdataset(paths)` with its defaults fails on shards with "non monotonic
    global index": shard K of N holds the ids K-1, K-1+N, ..., which interleave.)
    """
    if isinstance(paths, (str, os.PathLike)):
        pattern = os.fspath(paths)
        paths = sorted(glob.glob(pattern))
        if not paths:
            raise ValueError(f"no shard file matches {pattern!r}")
    paths = [os.fspath(p) for p in paths]
    if not paths:
        raise ValueError("no shard files given")
    seen = {}
    for path in paths:
        check_study_file(path, kind="a shard file written by studyrun --shard K/N")
        real = os.path.realpath(path)
        if real in seen:
            raise ValueError(f"{path} is given twice (also as {seen[real]})")
        seen[real] = path
    if lazy is None:
        lazy = _has_dask()
    combine = dict(
        concat_dim="case",
        data_vars="minimal",
        coords="minimal",
        compat="equals",
        join="exact",
        combine_attrs=_combine_shard_attrs,
    )
    try:
        refs = _shard_references(paths)
        part_of = functools.partial(_shard_part, refs=refs)
        if lazy:
            ds = xr.open_mfdataset(
                paths, combine="nested", preprocess=part_of, **OPEN_OPTIONS, **combine
            )
        else:
            parts = []
            for path in paths:
                with xr.open_dataset(path, **OPEN_OPTIONS) as part:
                    parts.append(part_of(part.load()))
            ds = xr.combine_nested(parts, **combine)
    except ValueError as e:
        if "study_fingerprint" in str(e):
            raise
        raise ValueError(
            f"the files are not shards of one study (times, frequencies or reference runs differ): {e}"
        ) from e
    ids, counts = np.unique(ds["case"].values, return_counts=True)
    if (counts > 1).any():
        ds.close()
        raise ValueError(f"case ids in more than one file: {ids[counts > 1].tolist()}")
    if not partial:
        try:
            _check_complete(paths, ids, ds.attrs.get("study_cases"))
        except ValueError:
            ds.close()
            raise
    out = ds.sortby("case")
    out.attrs["file_cases"] = np.int64(out.sizes["case"])
    # The shards' files together are no one shard: like a merged file, say none.
    out.attrs["shard"] = ""
    out.set_close(ds.close)
    return out


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
    both-races parameter where the races differ); strings exactly. Raises ValueError
    for a name the file has no per-case variable of, and for a string given for a
    numeric parameter (units are not parsed: give the number in the file's unit).
    """
    mask = np.ones(ds.sizes["case"], dtype=bool)
    for name, value in params.items():
        if name not in ds or ds[name].dims != ("case",):
            raise ValueError(f"{name!r} is not a per-case variable of the study")
        values = ds[name].values
        if values.dtype.kind in "USO":
            mask &= values == value
        elif isinstance(value, (str, bytes)):
            units = number_units(ds, name)
            raise ValueError(
                f"{name} is a number in the file's unit ({units}), not {value!r}: give a plain number "
                f"in that unit (units are not parsed), e.g. {name}={float(values[0]):g}"
            )
        else:
            mask &= np.isclose(values, value, rtol=1e-9, atol=0.0, equal_nan=True)
    return np.flatnonzero(mask)


def series_rate(ds):
    """The sample rate (Hz) of the stored series: the root attribute
    `series_sample_rate`, else `sample_rate / decimate` (`decimate` 1 when absent). A
    file whose grid has `output.decimate: k` stores every k-th output sample, so its
    series are sampled at `sample_rate / k`, while its spectra, metrics and envelope
    analysis are of the full-rate series (docs/result-file.md)."""
    if "series_sample_rate" in ds.attrs:
        return float(ds.attrs["series_sample_rate"])
    return float(ds.attrs["sample_rate"]) / int(ds.attrs.get("decimate", 1))


def analysis_window(ds):
    """Boolean mask over `time`: the stored samples at transient <= t < duration (s),
    the window the stored metrics and spectra use. It is half-open (the last sample
    of the output, at t = duration, is left out) so that a window of whole crank
    revolutions holds each crank phase once; its first sample is the first at or
    after the transient (to within 1e-9 of a sample interval), found by index as
    studyrun does. A file whose series keep every k-th sample (`decimate` attribute,
    `output.decimate` of the grid) stores output samples 0, k, 2k, ...: the mask
    keeps those inside the window. Raises ValueError for a file without series."""
    if "time" not in ds.dims:
        raise ValueError("the file stores no series (its grid file has `output.series: none`): "
                         "no time window; run the study with `output.series` naming the series")
    n = ds.sizes["time"]
    rate = float(ds.attrs["sample_rate"])
    decimate = int(ds.attrs.get("decimate", 1))
    # Output samples per case; a file always records its duration, a hand-made dataset may not.
    full = round(float(ds.attrs["duration"]) * rate) + 1 if "duration" in ds.attrs else (n - 1) * decimate + 1
    start = max(0, math.ceil(float(ds.attrs["transient"]) * rate - 1e-9))
    k = np.arange(n) * decimate
    return (k >= start) & (k < full - 1)


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

    Raises ValueError naming the `reference_<channel>` series needed that the file
    does not store (a grid whose `output.series` leaves their channels out).
    """
    wanted = list(IDEAL_CHANNELS) + ["bearing_force"] if channels is None else list(channels)
    unknown = set(wanted) - set(IDEAL_CHANNELS) - {"bearing_force"}
    if unknown:
        raise ValueError(f"no ideal-mechanism series for {sorted(unknown)}")
    rows = ds["reference_index"].astype("int64")
    needed = set(wanted) & set(IDEAL_CHANNELS)
    if "bearing_force" in wanted:
        needed |= {f"{loc}_force_{c}" for loc in BEARING_LOCATIONS for c in "xy"}
    absent = sorted(name for name in needed if f"reference_{name}" not in ds)
    if absent:
        have = [c for c in IDEAL_CHANNELS if f"reference_{c}" in ds]
        if all(f"reference_{loc}_force_{c}" in ds for loc in BEARING_LOCATIONS for c in "xy"):
            have.append("bearing_force")
        raise ValueError(
            f"the file does not store the ideal mechanism's {', '.join('reference_' + n for n in absent)}: "
            f"its grid's `output.series` leaves out {', '.join(absent)}; run the study with `output.series` "
            f"naming them, or ask for the channels it has (channels={have})"
        )
    refs = {
        name: ds[f"reference_{name}"].isel(reference=rows).drop_vars("reference", errors="ignore")
        for name in sorted(needed)
    }
    out = {name: refs[name] for name in wanted if name in refs}
    if "bearing_force" in wanted:
        out["bearing_force"] = _ideal_joint_force(ds, refs)
    return xr.Dataset({name: out[name] for name in wanted})


SPECTRUM_WINDOWS = ("hann", "rectangular")
"""The windows of the stored `<channel>_spectrum` (the grid's `spectra.window`)."""


def spectrum_window(ds):
    """The window of the file's `<channel>_spectrum` variables: its root attribute
    `spectrum_window` (`hann` or `rectangular`); `hann`, studyrun's default, when the
    attribute is absent. Raises ValueError for another value."""
    window = str(ds.attrs.get("spectrum_window", "hann")).strip()
    if window not in SPECTRUM_WINDOWS:
        raise ValueError(f"spectrum_window {window!r}: expected one of {', '.join(SPECTRUM_WINDOWS)}")
    return window


def amplitude_spectrum(x, sample_rate, window="hann"):
    """One-sided amplitude spectrum as studyrun stores it: the `window` (`hann`,
    periodic, or `rectangular`: pass `spectrum_window(ds)` to match a file's
    `<channel>_spectrum`), scaled so that a sinusoid of amplitude A on a bin reads A;
    mean not removed.

    `x` is a 1-D series sampled at `sample_rate` (Hz); returns (frequencies in Hz,
    amplitudes in the series' units). The envelope, order and short-time spectra
    (docs/model.md §7.4–§7.9) use the Hann window whatever the file's `spectra.window`.
    """
    x = np.asarray(x, dtype=float)
    n = len(x)
    if window == "hann":
        weights = 0.5 - 0.5 * np.cos(2 * np.pi * np.arange(n) / n)
    elif window == "rectangular":
        weights = np.ones(n)
    else:
        raise ValueError(f"window {window!r}: expected one of {', '.join(SPECTRUM_WINDOWS)}")
    amplitude = np.abs(np.fft.rfft(x * weights)) / weights.sum()
    amplitude[1 : (n + 1) // 2] *= 2
    return np.fft.rfftfreq(n, 1.0 / sample_rate), amplitude
