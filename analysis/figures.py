"""Figures of a study file (matplotlib, Agg backend). Each function writes one PNG
and returns its path.

`ds` is always the flat study Dataset of `studyfile.open_study` (dimension
`case`); parameter values are given in the file's units (waviness_amplitude in m,
rpm in rev/min); figures show lengths in µm or mm.
"""

import itertools
import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)
import numpy as np  # noqa: E402
from matplotlib.colors import LogNorm, Normalize  # noqa: E402
from matplotlib.ticker import FuncFormatter, NullFormatter, NullLocator  # noqa: E402

from analysis.frequencies import CRANK_ROD_NOTE, case_frequencies  # noqa: E402
from analysis.studyfile import (  # noqa: E402
    amplitude_spectrum,
    analysis_window,
    number_units,
    reference_for,
    select_cases,
    series_rate,
    spectrum_window,
    unstack,
)

PANEL_CHANNELS = ("slider_acceleration", "crank_moment", "bearing_force")
"""Channels with an ideal-mechanism counterpart (the paper's plotted outputs)."""

MAX_PANELS = 4
"""Ball counts per panel or spectra figure."""

MAX_FACETS = 48
"""Facets per metrics figure; more needs `select=`."""

CHANNEL_TEXT = {
    "slider_acceleration": "slider acceleration",
    "crank_moment": "crank moment",
    "bearing_force": "bearing force |F|",
}
UNIT_TEXT = {"m s-2": "m/s²", "m2 s-4": "(m/s²)²", "m4 s-8": "(m/s²)⁴", "N2": "N²", "N4": "N⁴",
             "N s m-1": "N s/m", "kg m2": "kg m²", "1": ""}
PARAMETER_TEXT = {"ball_count": "N_b", "location": "bearing", "waviness_amplitude": "waviness", "rpm": "speed"}


def channel_text(channel):
    """How a figure names a series: CHANNEL_TEXT's words, else the series' own name."""
    return CHANNEL_TEXT.get(channel, channel)


def check_series(ds, channel):
    """Raise ValueError unless `channel` is a `[case, time]` series of `ds`, naming the
    ones it has."""
    if channel not in ds or ds[channel].dims != ("case", "time"):
        have = [str(n) for n in ds.data_vars if ds[n].dims == ("case", "time")]
        raise ValueError(f"channel {channel!r} is not a series of the file; it has {', '.join(have) or 'none'}")


def unit_text(ds, name):
    """The display unit of variable `name` (e.g. 'm/s²'; '' for dimensionless)."""
    units = number_units(ds, name)
    return UNIT_TEXT.get(units, units)


def _length_scale(values):
    """(factor in m, unit) to show lengths of this size: µm below 1 mm, mm below 1 m."""
    finite = np.abs(np.asarray(values, dtype=float))
    finite = finite[np.isfinite(finite)]
    largest = finite.max() if finite.size else 0.0
    if largest < 1e-3:
        return 1e-6, "µm"
    if largest < 1.0:
        return 1e-3, "mm"
    return 1.0, "m"


def value_text(ds, name, value):
    """A parameter value with its unit, e.g. '4 µm', '300 rpm', '9'; lengths are
    scaled to the size of the parameter's values in the study."""
    if isinstance(value, (str, np.str_)):
        return str(value)
    if np.isnan(value):
        return "n/a (differs per race)" if name.startswith("waviness_") else "n/a"
    if ds[name].attrs.get("units") == "m":
        factor, unit = _length_scale(ds[name].values)
        return f"{float(value) / factor:g} {unit}"
    return f"{float(value):g} {unit_text(ds, name)}".strip()


def describe(ds, params):
    """'bearing crank_ground, speed 300 rpm, waviness 4 µm' for a dict of parameters."""
    return ", ".join(f"{PARAMETER_TEXT.get(k, k)} {value_text(ds, k, v)}" for k, v in params.items())


def _save(fig, out, dpi):
    """Write `fig` to the PNG `out` at `dpi` (cropped to its content), close it, return the path."""
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return out


def _cases_by_ball_count(ds, params, ball_counts):
    """{ball count: case position} of the successful cases matching `params`; at most
    MAX_PANELS ball counts (all of them if `ball_counts` is None), one case each."""
    cases = select_cases(ds, **params)
    cases = cases[ds["status"].values[cases] == 1]
    if cases.size == 0:
        raise ValueError(f"no successful case with {params}")
    counts = ds["ball_count"].values[cases]
    wanted = sorted(set(counts.tolist())) if ball_counts is None else list(ball_counts)
    if len(wanted) > MAX_PANELS:
        raise ValueError(f"{len(wanted)} ball counts {wanted}: pass at most {MAX_PANELS} as ball_counts=")
    chosen = {}
    for n in wanted:
        match = cases[np.isclose(counts, n)]
        if match.size != 1:
            raise ValueError(
                f"{match.size} cases with ball_count={n} and {params}: "
                "fix the study's other varying parameters with select="
            )
        chosen[int(n)] = int(match[0])
    return chosen


def default_window(ds, rpm):
    """(t0, t1) in s: the first crank revolution (60/rpm s) after the transient,
    cut at the end of the run."""
    t0 = float(ds.attrs["transient"])
    return t0, min(t0 + 60.0 / rpm, float(ds["time"].values[-1]))


def _panel_grid(n, figsize):
    """Figure and a flat list of n axes (1×1, 1×2 or 2×2), shared x and y."""
    nrows, ncols = (1, n) if n <= 2 else (2, 2)
    fig, axes = plt.subplots(nrows, ncols, sharex=True, sharey=True, squeeze=False, figsize=figsize)
    axes = axes.ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, list(axes[:n])


def _deviation_note(ds, channel, case):
    """'RMS deviation (t ≥ 0.2 s): 22.5 m/s²' from the stored metric, '' if absent."""
    metric = f"{channel}_rms_deviation"
    if metric not in ds:
        return ""
    value = float(ds[metric].values[case])
    return (f"RMS deviation ({float(ds.attrs['transient']):g} s ≤ t < {float(ds.attrs['duration']):g} s): "
            f"{value:.3g} {unit_text(ds, channel)}")


def paper_panels(
    ds, location, rpm, waviness_amplitude, channel, out, window=None, select=None, ball_counts=None, dpi=90
):
    """Panels per ball count (up to 4, 2×2) of `channel` against time with the ideal
    mechanism overlaid: the layout of the paper's Figs. 11–34.

    `channel`: a stored series; slider_acceleration (m/s²), crank_moment (N m) and
    bearing_force (N; the ideal curve is the |F| of the ideal joint at the bearing's
    location) with the ideal mechanism's, any other (e.g. a sensor's) alone.
    `window` = (t0, t1) in s, default one revolution after the transient;
    `waviness_amplitude` in m, `rpm` in rev/min; `select` fixes other parameters that
    vary in the study, e.g. {"clearance": 4e-5}. Returns the PNG's path.
    """
    check_series(ds, channel)
    params = {"location": location, "rpm": rpm, "waviness_amplitude": waviness_amplitude, **(select or {})}
    by_count = _cases_by_ball_count(ds, params, ball_counts)
    t0, t1 = window or default_window(ds, rpm)
    time = ds["time"].values
    keep = (time >= t0) & (time <= t1)
    if not keep.any():
        raise ValueError(f"no samples in the window ({t0}, {t1}) s")
    rows = list(by_count.values())
    series = ds[channel].isel(case=rows).values[:, keep]
    ideal = (reference_for(ds.isel(case=rows), [channel])[channel].values[:, keep] if channel in PANEL_CHANNELS
             else [None] * len(rows))

    fig, axes = _panel_grid(len(rows), figsize=(10, 6.6) if len(rows) > 2 else (10, 3.8))
    for ax, (n, row), y, y_ideal in zip(axes, by_count.items(), series, ideal):
        ax.plot(time[keep], y, lw=0.6, color="C0", label="with bearing")
        if y_ideal is not None:
            ax.plot(time[keep], y_ideal, lw=1.1, ls="--", color="k", label="ideal mechanism")
        ax.set_title(f"N_b = {n}", fontsize=10)
        ax.text(0.01, 0.98, _deviation_note(ds, channel, row), transform=ax.transAxes, va="top", fontsize=7.5,
                bbox={"facecolor": "white", "alpha": 0.8, "lw": 0})
        ax.grid(alpha=0.3)
    for i, ax in enumerate(axes):
        if i % 2 == 0:
            ax.set_ylabel(f"{channel_text(channel)} ({unit_text(ds, channel)})")
        if i >= len(axes) - 2:
            ax.set_xlabel("time (s)")
            ax.xaxis.set_tick_params(labelbottom=True)
    axes[0].legend(loc="lower right", fontsize=8)
    fig.suptitle(f"{channel_text(channel)}: {describe(ds, params)}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def _marks(ds, case):
    """[(label, frequency in Hz, line style)] of the characteristic frequencies of a
    case; the waviness lines only for a race whose waviness amplitude is not zero."""
    f = case_frequencies(ds, case)
    marks = [
        ("cage f_c", f.cage, ":"),
        ("ball pass outer N_b f_out", f.ball_pass_outer, "-."),
        ("ball pass inner N_b f_in", f.ball_pass_inner, "-."),
    ]
    for race, whirl, passing, label in (
        ("outer", f.whirl_outer, f.waviness_outer, "N_o f_out"),
        ("inner", f.whirl_inner, f.waviness_inner, "N_i f_in"),
    ):
        if float(ds[f"{race}_waviness_amplitude"].values[case]) != 0:
            if math.isfinite(whirl):
                marks.append((f"{race} waviness whirl", whirl, "--"))
            else:
                marks.append((f"{race} waviness {label}", passing, "--"))
    return marks


def _default_fmax(marks, nyquist):
    """20 times the highest marked frequency, rounded up to 50 Hz, at most Nyquist
    (Hz): wide enough for the contact resonances (~1 kHz in the paper's cases)."""
    highest = max(f for _, f, _ in marks)
    return min(nyquist, 50.0 * math.ceil(20 * highest / 50.0))


def ideal_spectra(ds, rows, channel):
    """(frequencies in Hz, amplitudes [len(rows), frequency]) of the ideal mechanism's
    `channel` for the cases at positions `rows`: its stored series over the analysed
    window transformed with the file's spectrum window (`spectrum_window`), as studyrun
    computes the stored `<channel>_spectrum` of a case. The series are at their stored
    rate (`series_rate`): a decimated file's reach its Nyquist frequency only."""
    sample_rate = series_rate(ds)
    window = spectrum_window(ds)
    series = reference_for(ds.isel(case=list(rows)), [channel])[channel].values[:, analysis_window(ds)]
    freq = np.fft.rfftfreq(series.shape[1], 1.0 / sample_rate)
    return freq, np.array([amplitude_spectrum(y, sample_rate, window)[1] for y in series]).reshape(-1, freq.size)


def spectra(
    ds, location, rpm, waviness_amplitude, channel, out, fmax=None, select=None, ball_counts=None, dpi=90
):
    """Amplitude spectra of `channel` (stored `<channel>_spectrum`, transient ≤ t < duration,
    the file's window `spectrum_window`) per ball count, the ideal mechanism's spectrum
    (the same window) in grey for the PANEL_CHANNELS, and the
    characteristic frequencies of docs/model.md §7.3 marked (see analysis.frequencies):
    cage f_c, ball pass N_b f_out and N_b f_in, and each wavy race's whirl (or N_o f_out,
    N_i f_in where the balls cancel it).
    Both axes are logarithmic (frequency from the first bin above 0 Hz).

    For crank_rod the inner race (on the rod) is taken at its mean speed over a
    revolution, 0 rad/s; the figure says so. `fmax` in Hz (default: twice the
    highest marked frequency); amplitudes in the channel's units on a log scale.
    Other arguments as for `paper_panels`. Returns the PNG's path.
    """
    if f"{channel}_spectrum" not in ds:
        raise ValueError(f"no stored spectrum of {channel!r} (the grid's `spectra.channels`)")
    params = {"location": location, "rpm": rpm, "waviness_amplitude": waviness_amplitude, **(select or {})}
    by_count = _cases_by_ball_count(ds, params, ball_counts)
    rows = list(by_count.values())
    sample_rate = float(ds.attrs["sample_rate"])
    marks = {row: _marks(ds, row) for row in rows}
    fmax = fmax or _default_fmax([m for row in rows for m in marks[row]], sample_rate / 2)
    freq = ds["frequency"].values
    shown = (freq > 0) & (freq <= fmax)
    amplitudes = ds[f"{channel}_spectrum"].isel(case=rows).values[:, shown]
    if channel in PANEL_CHANNELS:
        f_ideal, ideal = ideal_spectra(ds, rows, channel)
    else:
        f_ideal, ideal = np.zeros(0), [np.zeros(0)] * len(rows)
    ideal_shown = (f_ideal > 0) & (f_ideal <= fmax)

    fig, axes = plt.subplots(len(rows), 1, sharex=True, sharey=True, squeeze=False,
                             figsize=(10, 1.9 * len(rows) + 1.4))
    for ax, (n, row), amplitude, a_ideal in zip(axes[:, 0], by_count.items(), amplitudes, ideal):
        ax.loglog(freq[shown], amplitude, lw=0.9, color="C0", label=f"with bearing, N_b = {n}")
        if a_ideal.size:
            ax.loglog(f_ideal[ideal_shown], a_ideal[ideal_shown], lw=0.8, color="0.55", label="ideal mechanism")
        for i, (label, f, style) in enumerate(marks[row]):
            if f <= fmax:
                ax.axvline(f, color=f"C{i + 1}", ls=style, lw=1.1, label=f"{label} = {f:.1f} Hz")
        ax.set_ylabel(f"amplitude ({unit_text(ds, channel)})")
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7)
        ax.yaxis.set_minor_locator(NullLocator())
        ax.grid(alpha=0.3)
    top = float(np.nanmax(amplitudes))
    axes[0, 0].set_ylim(top * 1e-5, top * 2)
    lowest = min(f for row in rows for _, f, _ in marks[row])
    axes[0, 0].set_xlim(0.8 * min(lowest, freq[1]), fmax)
    axes[-1, 0].set_xlabel("frequency (Hz)")
    resolution = freq[1] - freq[0]
    fig.suptitle(f"amplitude spectrum of {channel_text(channel)} ({float(ds.attrs['transient']):g} s ≤ t < {float(ds.attrs['duration']):g} s, "
                 f"resolution {resolution:.3g} Hz): {describe(ds, params)}", fontsize=10)
    if location == "crank_rod":
        fig.text(0.01, 0.005, CRANK_ROD_NOTE, fontsize=7.5, style="italic")
    fig.tight_layout(rect=(0, 0.025 if location == "crank_rod" else 0, 1, 1))
    return _save(fig, out, dpi)


def _norm(values):
    """Colour scale shared by the facets: logarithmic when all values are positive and
    span more than a factor 10, else linear from min(0, smallest)."""
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        raise ValueError("no finite values to show")
    lo, hi = finite.min(), finite.max()
    if lo > 0 and hi / lo > 10:
        return LogNorm(lo, hi)
    return Normalize(min(0.0, lo), hi if hi > min(0.0, lo) else min(0.0, lo) + 1.0)


def _positions(ds, grid, axis):
    """(positions, tick labels) of a grid axis: numeric axes at their values, string
    axes at 0, 1, ..."""
    values = grid[axis].values
    labels = [value_text(ds, axis, v) for v in values]
    if values.dtype.kind in "USO":
        return np.arange(len(values)), labels
    return values.astype(float), labels


def _heatmap(ax, ds, data, x_axis, y_axis, norm):
    """One facet: cells of `data` [y_axis, x_axis] with their values written in."""
    z = np.ma.masked_invalid(data.transpose(y_axis, x_axis).values)
    ny, nx = z.shape
    mesh = ax.pcolormesh(np.arange(nx + 1) - 0.5, np.arange(ny + 1) - 0.5, z, cmap="viridis", norm=norm)
    ax.set_facecolor("0.85")
    ax.set_xticks(range(nx), [value_text(ds, x_axis, v) for v in data[x_axis].values])
    ax.set_yticks(range(ny), [value_text(ds, y_axis, v) for v in data[y_axis].values])
    if nx * ny <= 150:
        for (j, i), v in np.ndenumerate(z.filled(np.nan)):
            text = "–" if not np.isfinite(v) else f"{v:.3g}"
            dark = np.isfinite(v) and norm(v) < 0.6
            ax.text(i, j, text, ha="center", va="center", fontsize=8, color="white" if dark else "black")
    return mesh


def _lines(ax, ds, data, x_axis, line_axis):
    """One facet: `data` against x_axis, one line per value of line_axis (if any)."""
    x, labels = _positions(ds, data, x_axis)
    groups = data[line_axis].values if line_axis else [None]
    for value in groups:
        y = data.sel({line_axis: value}) if line_axis else data
        label = f"{PARAMETER_TEXT.get(line_axis, line_axis)} {value_text(ds, line_axis, value)}" if line_axis else None
        ax.plot(x, y.transpose(x_axis).values, marker="o", ms=4, label=label)
    ax.set_xticks(x, labels)
    ax.grid(alpha=0.3)
    if line_axis:
        ax.legend(fontsize=7)


def metrics_view(ds, metric, x_axis, y_axis, out, select=None, dpi=90):
    """A per-case metric (e.g. slider_acceleration_rms_deviation, docs/model.md §6, in the
    metric's units) over grid axes, written to the PNG `out`: a heatmap over
    x_axis × y_axis, or with y_axis=None lines against x_axis, one per ball count (or per the first other
    axis). Remaining grid axes with several values become facets sharing one colour
    scale (or y axis), one per combination of their values that the study ran (zipped
    axes give no facet to the combinations they skip); `select` fixes some axes first,
    e.g. {"waviness_amplitude": 4e-6}. Failed cases and combinations the study did not
    run are blank. Returns the PNG's path.
    """
    sub = ds.isel(case=select_cases(ds, **select)) if select else ds
    grid = unstack(sub)
    values = grid[metric].where(grid["status"] == 1)
    for axis in (x_axis, y_axis):
        if axis is not None and axis not in values.dims:
            raise ValueError(f"{axis!r} is not a grid axis of the study ({list(values.dims)})")
    fixed = [d for d in values.dims if values.sizes[d] == 1 and d not in (x_axis, y_axis)]
    title_params = {d: values[d].values[0] for d in fixed}
    values = values.squeeze(fixed, drop=True)
    others = [d for d in values.dims if d not in (x_axis, y_axis)]
    line_axis = None
    if y_axis is None and others:
        line_axis = "ball_count" if "ball_count" in others else others[0]
    facets = [d for d in others if d != line_axis]
    ran = grid["case_id"].notnull().squeeze(fixed, drop=True)
    combos = [combo for combo in itertools.product(*(values[d].values for d in facets))
              if not facets or bool(ran.sel(dict(zip(facets, combo))).any())]
    if len(combos) > MAX_FACETS:
        raise ValueError(f"{len(combos)} facets over {facets}: fix some axes with select=")
    ncols = min(values.sizes[facets[-1]], 6) if facets else 1
    nrows = math.ceil(len(combos) / ncols)
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, sharey=y_axis is None,
                             figsize=(3.2 + 3.4 * ncols, 0.9 + 2.9 * nrows))
    label = f"{metric} ({unit_text(ds, metric)})"
    norm = _norm(values.values) if y_axis else None
    for i, (ax, combo) in enumerate(zip(axes.ravel(), combos)):
        data = values.sel(dict(zip(facets, combo))) if facets else values
        if y_axis:
            mesh = _heatmap(ax, ds, data, x_axis, y_axis, norm)
            ax.set_ylabel(PARAMETER_TEXT.get(y_axis, y_axis) if i % ncols == 0 else "")
            ax.tick_params(labelleft=i % ncols == 0)
        else:
            _lines(ax, ds, data, x_axis, line_axis)
            ax.set_ylabel(label if i % ncols == 0 else "")
        ax.set_xlabel(PARAMETER_TEXT.get(x_axis, x_axis))
        ax.set_title(describe(ds, dict(zip(facets, combo))), fontsize=9)
    for ax in axes.ravel()[len(combos):]:
        ax.set_visible(False)
    title = metric + (f" — {describe(ds, title_params)}" if title_params else "")
    fig.suptitle(title, fontsize=11)
    fig.tight_layout()
    if y_axis:
        bar = fig.colorbar(mesh, ax=axes.ravel().tolist(), label=label, shrink=0.9)
        plain = FuncFormatter(lambda v, _: f"{v:g}")
        bar.ax.yaxis.set_major_formatter(plain)
        bar.ax.yaxis.set_minor_formatter(plain if isinstance(norm, LogNorm) else NullFormatter())
    return _save(fig, out, dpi)
