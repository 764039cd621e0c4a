"""Diagnosis figures of a study file (matplotlib, Agg backend): the journal centre's
orbit, envelope spectra with the bearing's fault lines and shaft sidebands, a
spectrogram, a waterfall of envelope spectra over the crank speed, order spectra, an
rpm–order map of a run-up, the stored spectral kurtosis, the fast kurtogram and
heatmaps of condition indicators. Each function writes one
PNG and returns its path; it raises ValueError when the study lacks what it needs.

`ds` is the flat study Dataset of `studyfile.open_study`; `cases` are positions
along its `case` dimension, given as {panel label: case} (one panel each, at most
MAX_PANELS) or for the orbit as {panel title: {curve label: case}}. The computations
are those of analysis/diagnosis.py (docs/model.md §7.3–§7.7); what is recomputed from
a stored series uses the series' own rate, `studyfile.series_rate` (sample_rate /
decimate in a file of `output.decimate`), while the stored spectra and bands are of
the full-rate series.
"""

import math

import numpy as np
import xarray as xr
from matplotlib.patches import Rectangle

from analysis import diagnosis
from analysis.figures import _heatmap, _norm, _save, plt, unit_text
from analysis.studyfile import series_rate

MAX_PANELS = 6
"""Panels per figure."""

LINE_COLOURS = {"FTF": "tab:purple", "BPFO": "tab:red", "BPFI": "tab:blue", "BSF": "tab:olive", "2·BSF": "tab:green"}
"""Marker colour of each characteristic line."""

HEALTHY = "none"
"""The `fault` label of a bearing without defects."""


def _panels(count, width=5.0, height=3.0, ncols=2):
    """A figure of `count` panels in rows of `ncols` (unused panels hidden)."""
    if not 1 <= count <= MAX_PANELS:
        raise ValueError(f"{count} panels: give 1 to {MAX_PANELS} cases")
    ncols = min(ncols, count)
    nrows = math.ceil(count / ncols)
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, figsize=(width * ncols, height * nrows + 0.6))
    for ax in axes.ravel()[count:]:
        ax.set_visible(False)
    return fig, axes.ravel()[:count]


def _need(ds, *names):
    """Raise ValueError naming the first variable of `names` the study lacks."""
    for name in names:
        if name not in ds:
            raise ValueError(f"the study has no {name}")


def fault_label(ds, case):
    """The case's fault label (`none` without the `fault` variable)."""
    return diagnosis.text(ds["fault"].values[case]) if "fault" in ds else HEALTHY


def orbit(ds, groups, out, dpi=90):
    """The journal centre relative to the housing, eccentricity_y against
    eccentricity_x (µm) over the analysed window, one panel per group
    {title: {label: case}}, with the clearance circle of radius P_d/2 (the radial
    gap of each ball with the journal centred, docs/model.md §2.4) for each diametral
    clearance P_d > 0 among the cases; a preload (P_d < 0) has no circle and says so."""
    _need(ds, "eccentricity_x", "eccentricity_y", "clearance")
    fig, axes = _panels(len(groups), width=4.2, height=4.0, ncols=3)
    phi = np.linspace(0, 2 * math.pi, 361)
    for ax, (title, cases) in zip(axes, groups.items()):
        for label, case in cases.items():
            _, x = diagnosis.window_series(ds, "eccentricity_x", case)
            _, y = diagnosis.window_series(ds, "eccentricity_y", case)
            ax.plot(1e6 * x, 1e6 * y, lw=0.6, label=label)
        for p_d in sorted({float(ds["clearance"].values[c]) for c in cases.values()}):
            if p_d > 0:
                r = 0.5e6 * p_d
                ax.plot(r * np.cos(phi), r * np.sin(phi), "k--", lw=0.9, label=f"clearance circle P_d/2 = {r:g} µm")
            else:
                ax.plot([], [], " ", label=f"preload {-1e6 * p_d:g} µm: no clearance circle")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("eccentricity x (µm)")
        ax.set_ylabel("eccentricity y (µm)")
        ax.set_title(title, fontsize=9)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    fig.suptitle("Journal centre orbit (journal minus housing centre), analysed window", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def _line_frequencies(ds, case):
    """({name: frequency in Hz} of FAULT_LINES, shaft frequency rpm/60 in Hz) of a
    constant-speed case; ValueError for a varying speed."""
    rpm = diagnosis.constant_rpm(ds, case)
    if not math.isfinite(rpm):
        raise ValueError(f"case {int(ds['case'].values[case])} has no constant speed")
    f_shaft = rpm / 60
    return {k: order * f_shaft for k, order in diagnosis.fault_orders(ds, case).lines().items()}, f_shaft


def squared_unit_text(ds, channel):
    """The display unit of the square of `channel`, e.g. 'N²' or '(m/s²)²'."""
    units = unit_text(ds, channel)
    return f"({units})²" if any(c in units for c in " /²") else f"{units}²"


def case_envelope(ds, channel, case):
    """(frequencies in Hz, envelope amplitudes, (low, high) band in Hz, stored?) of one
    case: the file's `<channel>_envelope_spectrum` and band where it has them (a
    simulated channel or a sensor's series the study's `envelope:` lists), else the
    envelope spectrum (docs/model.md §7.4) of the stored series `channel` in the band
    of its fast kurtogram (§7.6), both recomputed here, e.g. for a sensor's series
    `envelope:` does not list."""
    name = f"{channel}_envelope_spectrum"
    if name in ds:
        band = tuple(float(ds[f"{channel}_envelope_band_{e}"].values[case]) for e in ("low", "high"))
        return ds["frequency"].values, ds[name].values[case], band, True
    _need(ds, channel)
    fs = series_rate(ds)
    _, x = diagnosis.window_series(ds, channel, case)
    band = diagnosis.kurtogram(x, fs).band
    freq, amplitude = diagnosis.envelope_spectrum(x, fs, *band)
    return freq, amplitude, band, False


def envelope_spectra(ds, channel, cases, out, f_max=None, sidebands=2, dpi=90):
    """Envelope spectra of `channel` at constant speeds (`case_envelope`: the file's, or
    recomputed from the series in its kurtogram's band), one panel per {label: case}
    (labels are fault labels: none, outer, inner, ball), on a linear scale up to
    `f_max` (Hz; default 2.2 × the largest line), the healthy case (label `none`) grey
    behind the others (its peak in the legend). Marked: the first harmonics of FTF,
    BPFO, BPFI, BSF and 2·BSF (docs/model.md §7.3), and around the panel's fault line
    (BPFO, BPFI, 2·BSF) its shaft sidebands ±k·f_shaft, k = 1..sidebands, f_shaft = rpm/60."""
    healthy = cases.get(HEALTHY)
    calm = case_envelope(ds, channel, healthy) if healthy is not None else None
    fig, axes = _panels(len(cases))
    for ax, (label, case) in zip(axes, cases.items()):
        lines, f_shaft = _line_frequencies(ds, case)
        freq, spectrum, (low, high), stored = calm if case == healthy else case_envelope(ds, channel, case)
        top = f_max or 2.2 * max(lines.values())
        band = (freq > 0) & (freq <= top)
        if calm is not None and healthy != case:
            keep = (calm[0] > 0) & (calm[0] <= top)
            ax.plot(calm[0][keep], calm[1][keep], color="0.6", lw=0.8,
                    label=f"none (healthy), peak {calm[1][keep].max():.2g}")
        ax.plot(freq[band], spectrum[band], color="k", lw=0.9, label=label)
        for line, f in lines.items():
            ax.axvline(f, color=LINE_COLOURS[line], ls="--", lw=0.9, label=f"{line} {f:.1f} Hz")
        own = diagnosis.FAULT_LINE.get(label)
        if own:
            for k in range(1, sidebands + 1):
                for sign in (-1, 1):
                    ax.axvline(lines[own] + sign * k * f_shaft, color=LINE_COLOURS[own], ls=":", lw=0.8,
                               label=f"{own} ± k·f_shaft, k ≤ {sidebands}" if (k, sign) == (1, 1) else None)
        source = "band" if stored else "recomputed kurtogram's band"
        ax.set_title(f"{label}: {source} {low:g}–{high:g} Hz, f_shaft = {f_shaft:g} Hz", fontsize=9)
        ax.set_xlim(0, top)
        ax.set_ylim(0, 1.6 * np.nanmax(spectrum[band]))  # room for the legend above the lines
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel(f"envelope amplitude ({squared_unit_text(ds, channel)})")
        ax.grid(alpha=0.3, lw=0.4)
        ax.legend(fontsize=6, loc="upper right", ncol=2)
    fig.suptitle(f"Envelope spectra of {channel}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def measured_beside_simulated(measured, simulated, out, dpi=90):
    """A measured case and a simulated case of the same fault side by side: each
    `(ds, channel, case)`'s envelope spectrum (`case_envelope`: the file's, in the band
    it records) up to 2.2 × its largest line, with its own FTF, BPFO, BPFI, BSF and
    2·BSF (docs/model.md §7.3) marked; each panel scaled to its own largest value, the
    two studies' units and speeds differing."""
    fig, axes = _panels(2, width=6.0, height=3.6)
    for ax, (what, (ds, channel, case)) in zip(axes, (("measured", measured), ("simulated", simulated))):
        lines, f_shaft = _line_frequencies(ds, case)
        freq, spectrum, (low, high), _ = case_envelope(ds, channel, case)
        top = 2.2 * max(lines.values())
        band = (freq > 0) & (freq <= top)
        ax.plot(freq[band], spectrum[band], color="k", lw=0.9, label=f"{channel}, {fault_label(ds, case)}")
        for line, f in lines.items():
            ax.axvline(f, color=LINE_COLOURS[line], ls="--", lw=0.9, label=f"{line} {f:.1f} Hz")
        study = ds.attrs.get("study_name", "")
        ax.set_title(f"{what} ({study}, case {int(ds['case'].values[case])}): band {low:g}–{high:g} Hz, "
                     f"f_shaft = {f_shaft:g} Hz", fontsize=9)
        ax.set_xlim(0, top)
        ax.set_ylim(0, 1.6 * np.nanmax(spectrum[band]))
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel(f"envelope amplitude ({squared_unit_text(ds, channel)})")
        ax.grid(alpha=0.3, lw=0.4)
        ax.legend(fontsize=6, loc="upper right", ncol=2)
    fig.suptitle(f"Measured and simulated envelope spectra, fault {fault_label(*measured[::2])}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


CONTENT_SHARE = 0.995
"""The share of a series' power a raw spectrogram's frequency axis holds (`content_top`)."""


def content_top(series, sample_rate, share=CONTENT_SHARE):
    """The frequency axis's top (Hz) for the raw spectra of `series` (a list of 1-D
    sample arrays at `sample_rate`): the lowest frequency below which `share` of their
    summed power (mean removed) lies, rounded up to 1, 2 or 5 × 10^k Hz, at most the
    Nyquist frequency sample_rate/2."""
    nyquist = 0.5 * sample_rate
    n = min(len(x) for x in series)
    power = sum(np.abs(np.fft.rfft(np.asarray(x[:n], dtype=float) - np.mean(x[:n]))) ** 2 for x in series)
    cumulative = np.cumsum(power)
    if cumulative[-1] <= 0:
        return nyquist
    freqs = np.fft.rfftfreq(n, 1.0 / sample_rate)
    edge = float(freqs[min(np.searchsorted(cumulative, share * cumulative[-1]) + 1, freqs.size - 1)])
    scale = 10.0 ** math.floor(math.log10(max(edge, 1e-300)))
    nice = next(m * scale for m in (1, 2, 5, 10) if m * scale >= edge)
    return min(nyquist, nice)


def spectrogram(ds, series, cases, out, demodulate=True, f_max=None, segment=None, dpi=90):
    """STFT of a stored `series` over the analysed window, one panel per
    {label: case}: amplitude (file convention, dB re its largest) against time and
    frequency, segments of `segment` samples (default about 0.1 s, at most a quarter of
    the window) every segment/4, at the stored series' rate (`series_rate`: a decimated
    file's series run over the whole duration at sample_rate / decimate).
    With `demodulate` (and a band stored for the case, `<series>_envelope_band_low/
    _high`) the STFT is that of the squared envelope of the band (docs/model.md §7.4,
    mean removed) up to `f_max` (default 2.2 × the fastest BPFI): the fault lines, which
    follow the crank speed, are dashed (1× and 2× of the panel's line: BPFO, BPFI or
    2·BSF; for any other label BPFO). Else the raw series up to `f_max` (default
    `content_top`: where 99.5 % of the panels' power lies, at most f_s/2)."""
    _need(ds, series)
    fs = series_rate(ds)
    if segment is None:
        n = int(diagnosis.analysis_window(ds).sum())
        segment = 1 << min(round(math.log2(0.1 * fs)), int(math.log2(max(n // 4, 2))))
    demodulate = demodulate and f"{series}_envelope_band_low" in ds
    panels = {}
    for label, case in cases.items():
        t, x = diagnosis.window_series(ds, series, case)
        band = None
        if demodulate:
            band = tuple(float(ds[f"{series}_envelope_band_{e}"].values[case]) for e in ("low", "high"))
            power = np.abs(diagnosis.analytic_signal(x, fs, *band)) ** 2
            x = power - power.mean()
        panels[label] = (case, t, x, band)
    raw_top = f_max or (None if demodulate else content_top([x for _, _, x, _ in panels.values()], fs))
    fig, axes = _panels(len(cases), width=5.2, height=3.2)
    for ax, (label, (case, t, x, band)) in zip(axes, panels.items()):
        centres, freqs, amp = diagnosis.stft(x, fs, segment, segment // 4)
        centres = centres + t[0]
        _, rpm = diagnosis.crank_motion(ds, case, centres)
        lines = diagnosis.fault_orders(ds, case).lines()
        top = raw_top or 2.2 * lines["BPFI"] * rpm.max() / 60
        keep = (freqs > 0) & (freqs <= top)
        db = 20 * np.log10(np.maximum(amp[:, keep].T, 1e-300) / amp[:, keep].max())
        mesh = ax.pcolormesh(centres, freqs[keep], db, shading="nearest", cmap="magma", vmin=-40, vmax=0)
        if demodulate:
            own = diagnosis.FAULT_LINE.get(label, "BPFO")
            for k, style in ((1, "--"), (2, ":")):
                ax.plot(centres, k * lines[own] * rpm / 60, ls=style, color="cyan", lw=1.0,
                        label=f"{k}× {own} (order {k * lines[own]:.3g})")
            ax.legend(fontsize=7, loc="upper left")
            what = f"squared envelope of {band[0]:g}–{band[1]:g} Hz"
        else:
            what = "raw series"
        ax.set_ylim(0, top)
        ax.set_xlim(t[0], t[-1])
        ax.set_xlabel("time (s)")
        ax.set_ylabel("frequency (Hz)")
        ax.set_title(f"{label}: {what}, {segment / fs:.3g} s segments", fontsize=9)
        fig.colorbar(mesh, ax=ax, label="amplitude (dB re the panel's largest)")
    fig.suptitle(f"Spectrogram of {series}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def _envelope_rows(ds, channel, case, segment_time):
    """[(rpm, frequencies, envelope amplitudes)] of one case: its stored envelope
    spectrum at a constant speed; for a varying speed the envelope spectra (§7.4, the
    case's band) of segments of `segment_time` s every half of that, each at its
    mean speed."""
    rpm = diagnosis.constant_rpm(ds, case)
    if math.isfinite(rpm):
        return [(rpm, ds["frequency"].values, ds[f"{channel}_envelope_spectrum"].values[case])]
    fs = series_rate(ds)
    low, high = (float(ds[f"{channel}_envelope_band_{e}"].values[case]) for e in ("low", "high"))
    t, x = diagnosis.window_series(ds, channel, case)
    length = int(round(segment_time * fs))
    rows = []
    for start in range(0, len(x) - length + 1, length // 2):
        _, speed = diagnosis.crank_motion(ds, case, t[start : start + length])
        f, a = diagnosis.envelope_spectrum(x[start : start + length], fs, low, high)
        rows.append((float(speed.mean()), f, a))
    return rows


def waterfall(ds, channel, cases, out, f_max=None, segment_time=0.2, dpi=90):
    """Envelope spectra of `channel` stacked over the crank speed, one panel per
    {label: [cases]}: each spectrum drawn at its speed (rpm, y axis) with its height
    scaled to its own largest amplitude; a constant-speed case gives its stored
    spectrum, a run-up its segments' (see `_envelope_rows`). The characteristic
    lines move along f = order · rpm/60 (dashed)."""
    _need(ds, f"{channel}_envelope_spectrum", f"{channel}_envelope_band_low")
    fig, axes = _panels(len(cases), width=5.0, height=3.6)
    for ax, (label, group) in zip(axes, cases.items()):
        rows = sorted((row for case in group for row in _envelope_rows(ds, channel, case, segment_time)),
                      key=lambda r: r[0])
        lines = diagnosis.fault_orders(ds, group[0]).lines()
        speeds = np.array([r[0] for r in rows])
        top = f_max or 2.2 * lines["BPFI"] * speeds.max() / 60
        gap = np.ptp(speeds) / (len(rows) - 1) if np.ptp(speeds) > 0 else 100.0
        for rpm, f, a in rows:
            keep = (f > 0) & (f <= top)
            largest = a[keep].max() or 1.0  # a band above a decimated series' Nyquist holds nothing
            height = rpm + 2.5 * gap * a[keep] / largest
            ax.fill_between(f[keep], rpm, height, color="white", zorder=-rpm)
            ax.plot(f[keep], height, color="k", lw=0.6, zorder=-rpm)
        span = np.array([speeds.min() - gap, speeds.max() + 3 * gap])
        for line in ("FTF", "BPFO", "BPFI", "2·BSF"):
            ax.plot(lines[line] * span / 60, span, ls="--", lw=0.9, color=LINE_COLOURS[line], label=line)
        ax.set_xlim(0, top)
        ax.set_ylim(*span)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("crank speed (rpm); spectrum above its speed")
        ax.set_title(f"{label}: {len(rows)} spectra, each scaled to its largest", fontsize=9)
        ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"Waterfall of envelope spectra of {channel} over the crank speed", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def _order_rows(ds, channel, case):
    """(orders, amplitudes, stored?) of one case: the stored `<channel>_order_spectrum`
    over the `order` coordinate where the file has it and it is finite, else computed
    from the series resampled uniformly in crank angle (diagnosis.order_spectrum) at
    the samples per revolution of the fastest speed in the window."""
    name = f"{channel}_order_spectrum"
    if name in ds and np.isfinite(ds[name].values[case]).any():
        return ds["order"].values, ds[name].values[case], True
    t, x = diagnosis.window_series(ds, channel, case)
    theta, rpm = diagnosis.crank_motion(ds, case, t)
    per_revolution = 2 * int(series_rate(ds) * 60 / rpm.max() / 2)
    orders, amplitude = diagnosis.order_spectrum(x, theta, per_revolution)
    return orders, amplitude, False


def order_spectra(ds, channel, cases, out, max_order=None, dpi=90):
    """Order spectra of `channel` (amplitude against cycles per crank revolution), one
    panel per {label: case}, on a log scale up to `max_order` (default 2.2 × the BPFI
    order), with the orders of FTF, BPFO, BPFI, BSF and 2·BSF marked. Each panel says
    whether the spectrum is the file's `<channel>_order_spectrum` or recomputed."""
    _need(ds, channel)
    fig, axes = _panels(len(cases))
    for ax, (label, case) in zip(axes, cases.items()):
        orders, amplitude, stored = _order_rows(ds, channel, case)
        lines = diagnosis.fault_orders(ds, case).lines()
        top = max_order or 2.2 * lines["BPFI"]
        keep = (orders > 0) & (orders <= top)
        ax.semilogy(orders[keep], amplitude[keep], color="k", lw=0.9, label=label)
        for line, order in lines.items():
            ax.axvline(order, color=LINE_COLOURS[line], ls="--", lw=0.9, label=f"{line} order {order:.3f}")
        ax.set_xlim(0, top)
        ax.set_xlabel("order (cycles per crank revolution)")
        ax.set_ylabel(f"amplitude ({unit_text(ds, channel)})")
        source = "stored" if stored else "resampled in crank angle"
        ax.set_title(f"{label}: {source}", fontsize=9)
        ax.grid(alpha=0.3, which="both", lw=0.4)
        ax.legend(fontsize=6, loc="upper right", ncol=2)
    fig.suptitle(f"Order spectra of {channel}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def spectral_kurtosis(ds, channel, cases, out, f_max=None, dpi=90):
    """The stored spectral kurtosis `<channel>_spectral_kurtosis` (docs/model.md §7.5,
    dimensionless, 0 for Gaussian noise) against its own frequency axis (the STFT bins,
    `sk_frequency`), one panel per {label: case}, up to `f_max` (Hz; default the end of
    that axis),
    with the band the file records for the case (`<channel>_envelope_band_low/_high`)
    shaded: where the impacts ring, the kurtosis stands out."""
    name = f"{channel}_spectral_kurtosis"
    _need(ds, name, f"{channel}_envelope_band_low")
    freq = ds[ds[name].dims[1]].values
    top = f_max or float(freq[-1])
    keep = (freq >= 0) & (freq <= top)
    fig, axes = _panels(len(cases))
    for ax, (label, case) in zip(axes, cases.items()):
        sk = np.asarray(ds[name].values[case], dtype=float)
        low, high = (float(ds[f"{channel}_envelope_band_{e}"].values[case]) for e in ("low", "high"))
        ax.axvspan(low, high, color="tab:cyan", alpha=0.3, lw=0, label=f"band in the file: {low:g}–{high:g} Hz")
        ax.plot(freq[keep], sk[keep], color="k", lw=0.7, label=label)
        ax.axhline(0.0, color="0.5", lw=0.6, ls="--", label="Gaussian noise: 0")
        peak = int(np.nanargmax(np.where(keep, sk, np.nan)))
        ax.set_title(f"{label}: largest {sk[peak]:.3g} at {freq[peak]:.0f} Hz", fontsize=9)
        ax.set_xlim(0, top)
        ax.set_xlabel("frequency (Hz)")
        ax.set_ylabel("spectral kurtosis")
        ax.grid(alpha=0.3, lw=0.4)
        ax.legend(fontsize=6, loc="upper right")
    fig.suptitle(f"Spectral kurtosis of {channel} (stored)", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def order_map(ds, series, case, segment_time=0.2, max_order=None):
    """(rpm of each segment, orders, amplitudes [segment, order]) of a stored `series` of
    `case` over the analysed window: short-time spectra (`diagnosis.stft`, segments of
    about `segment_time` s every quarter segment, at the series' stored rate) of the
    squared envelope of the band the file records (docs/model.md §7.4, mean removed),
    or of the series itself where it records none; each segment's spectrum read at
    orders 0 … `max_order` (default 2.2 × the BPFI order; 400 points) as frequencies
    order × rpm/60 at the segment's mean crank speed (linear interpolation)."""
    fs = series_rate(ds)
    t, x = diagnosis.window_series(ds, series, case)
    if f"{series}_envelope_band_low" in ds:
        band = tuple(float(ds[f"{series}_envelope_band_{e}"].values[case]) for e in ("low", "high"))
        power = np.abs(diagnosis.analytic_signal(x, fs, *band)) ** 2
        x = power - power.mean()
    segment = 1 << min(round(math.log2(segment_time * fs)), int(math.log2(max(len(x) // 4, 2))))
    centres, freqs, amp = diagnosis.stft(x, fs, segment, segment // 4)
    _, rpm = diagnosis.crank_motion(ds, case, centres + t[0])
    top = max_order or 2.2 * diagnosis.fault_orders(ds, case).bpfi
    orders = np.linspace(0.0, top, 400)
    return rpm, orders, np.array([np.interp(orders * r / 60, freqs, row) for r, row in zip(rpm, amp)])


def rpm_order_map(ds, series, cases, out, segment_time=0.2, max_order=None, dpi=90):
    """The rpm–order map of run-ups (or any varying speed): `order_map` of each
    {label: case} as an image, crank speed (rpm) against order (cycles per crank
    revolution), dB re the panel's largest. A fault line stays at its order while the
    speed sweeps: the orders of FTF, BPFO, BPFI and 2·BSF are dashed."""
    _need(ds, series)
    fig, axes = _panels(len(cases), width=5.2, height=3.4)
    for ax, (label, case) in zip(axes, cases.items()):
        rpm, orders, amp = order_map(ds, series, case, segment_time, max_order)
        db = 20 * np.log10(np.maximum(amp, 1e-300) / amp[:, 1:].max())
        mesh = ax.pcolormesh(orders, rpm, db, shading="nearest", cmap="magma", vmin=-40, vmax=0)
        for line, order in diagnosis.fault_orders(ds, case).lines().items():
            if line != "BSF" and order <= orders[-1]:
                ax.axvline(order, color=LINE_COLOURS[line], ls="--", lw=1.0, label=f"{line} order {order:.3f}")
        ax.set_xlim(0, orders[-1])
        ax.set_xlabel("order (cycles per crank revolution)")
        ax.set_ylabel("crank speed (rpm)")
        what = "squared envelope" if f"{series}_envelope_band_low" in ds else "series"
        ax.set_title(f"{label}: {what}, {rpm.min():.0f}–{rpm.max():.0f} rpm", fontsize=9)
        ax.legend(fontsize=6, loc="upper right")
        fig.colorbar(mesh, ax=ax, label="amplitude (dB re the panel's largest)")
    fig.suptitle(f"rpm–order map of {series}", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)


def kurtogram(ds, series, case, out, dpi=90):
    """The fast kurtogram (docs/model.md §7.6) of a stored `series` of `case`,
    recomputed over the analysed window at the series' stored rate (`series_rate`): the
    kurtosis of each band's complex envelope as an image, level against frequency up to
    that rate's Nyquist frequency. The band of largest kurtosis is outlined
    (white), and the band the file records for the case, if it does
    (`<series>_envelope_band_low/_high`), dashed (cyan)."""
    _need(ds, series)
    fs = series_rate(ds)
    _, x = diagnosis.window_series(ds, series, case)
    result = diagnosis.kurtogram(x, fs)
    nyquist = 0.5 * fs
    values = np.array([v for _, row in result.levels for v in row], dtype=float)
    norm = plt.Normalize(0.0, np.nanmax(values) if np.isfinite(values).any() else 1.0)
    fig, ax = plt.subplots(figsize=(8.0, 4.2))
    levels = [level for level, _ in result.levels]
    row_of = {level: i for i, level in enumerate(levels)}
    for i, (level, row) in enumerate(result.levels):
        edges = np.linspace(0.0, nyquist, len(row) + 1)
        mesh = ax.pcolormesh(edges, [i - 0.5, i + 0.5], np.ma.masked_invalid([row]), cmap="viridis", norm=norm)
    low, high = result.band
    ax.add_patch(Rectangle((low, row_of[result.level] - 0.5), high - low, 1.0, fill=False, ec="white", lw=2,
                           label=f"largest kurtosis {result.kurtosis:.3g}: {low:g}–{high:g} Hz"))
    name_low = f"{series}_envelope_band_low"
    if name_low in ds:
        s_low, s_high = float(ds[name_low].values[case]), float(ds[f"{series}_envelope_band_high"].values[case])
        width = [abs(nyquist / m - (s_high - s_low)) for m in (len(r) for _, r in result.levels)]
        ax.add_patch(Rectangle((s_low, int(np.argmin(width)) - 0.5), s_high - s_low, 1.0, fill=False, ec="cyan",
                               ls="--", lw=1.5, label=f"band in the file: {s_low:g}–{s_high:g} Hz"))
    ax.set_yticks(range(len(levels)), [f"{level:.1f}" for level in levels])
    ax.set_ylim(len(levels) - 0.5, -0.5)
    ax.set_xlim(0.0, nyquist)
    ax.set_xlabel(f"frequency (Hz), series stored at {fs:g} Hz")
    ax.set_ylabel("level (bands of f_s / 2^(level+1))")
    case_id = int(ds["case"].values[case])
    fault = f" ({fault_label(ds, case)})" if "fault" in ds else ""
    ax.set_title(f"Fast kurtogram of {series}, case {case_id}{fault}", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    fig.colorbar(mesh, ax=ax, label="kurtosis of the complex envelope <|z|⁴>/<|z|²>² − 2")
    fig.tight_layout()
    return _save(fig, out, dpi)


def indicator_heatmaps(ds, names, x, y, out, dpi=90):
    """Per-case indicators (e.g. bearing_force_kurtosis, docs/model.md §7.7) as
    heatmaps over two case labels, one panel and colour scale each. `x` and `y` are
    (title, [label of each case], [sort key of each case]) of the columns and rows,
    ordered by their keys (e.g. speeds by value, not as the cases come); a cell holds
    the one case with that pair of labels (ValueError if several have it), blank where
    none does."""
    (x_title, x_labels, x_keys), (y_title, y_labels, y_keys) = x, y

    def ordered(labels, keys):
        first = dict(zip(reversed(labels), reversed(keys)))  # each label's key at its first case
        return sorted(dict.fromkeys(labels), key=lambda label: first[label])

    columns, rows = ordered(x_labels, x_keys), ordered(y_labels, y_keys)
    cells = {}
    for case, key in enumerate(zip(x_labels, y_labels)):
        if key in cells:
            raise ValueError(f"cases {cells[key]} and {case} share {x_title} {key[0]}, {y_title} {key[1]}")
        cells[key] = case
    ncols = min(4, len(names))
    nrows = math.ceil(len(names) / ncols)
    size = (3.0 + 1.1 * len(columns) * ncols, 0.9 + (0.6 + 0.45 * len(rows)) * nrows)
    fig, axes = plt.subplots(nrows, ncols, squeeze=False, figsize=size)
    for ax, name in zip(axes.ravel(), names):
        _need(ds, name)
        grid = np.full((len(rows), len(columns)), np.nan)
        ok = ds["status"].values == 1
        for (cx, cy), case in cells.items():
            if ok[case]:
                grid[rows.index(cy), columns.index(cx)] = float(ds[name].values[case])
        data = xr.DataArray(grid, dims=(y_title, x_title), coords={y_title: rows, x_title: columns})
        mesh = _heatmap(ax, ds, data, x_title, y_title, _norm(grid))
        units = unit_text(ds, name)
        fig.colorbar(mesh, ax=ax, label=units or None)
        ax.set_title(name + (f" ({units})" if units else ""), fontsize=8)
        ax.set_xlabel(x_title, fontsize=8)
        ax.set_ylabel(y_title, fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes.ravel()[len(names):]:
        ax.set_visible(False)
    fig.suptitle("Condition indicators (docs/model.md §7.7)", fontsize=11)
    fig.tight_layout()
    return _save(fig, out, dpi)
