"""Signal processing of a diagnostician, recomputed from a study file's stored series:
crank speed and angle of a case, the bearing's fault lines as orders of the crank,
the envelope of a band (docs/model.md §7.4), the fast kurtogram (§7.6), a short-time
Fourier transform and an order spectrum (the series resampled uniformly in crank angle).

`ds` is the flat study Dataset of `studyfile.open_study` and `case` a position along
its `case` dimension. Frequencies are in Hz, speeds in rpm (rev/min), angles in rad,
orders in cycles per crank revolution.
"""

import math
from dataclasses import dataclass

import numpy as np

from analysis.frequencies import race_speeds
from analysis.studyfile import amplitude_spectrum, analysis_window, constant_rpm, parameter_value, text

FAULT_LINES = ("FTF", "BPFO", "BPFI", "BSF", "2·BSF")
"""The characteristic lines marked in envelope spectra (docs/model.md §7.3)."""

FAULT_LINE = {"outer": "BPFO", "inner": "BPFI", "ball": "2·BSF"}
"""The line a defect on each surface excites (a ball defect meets both races once per spin)."""

KURTOGRAM_MAX_LEVEL = 6
"""Deepest binary level of the fast kurtogram (docs/model.md §7.6)."""


def crank_motion(ds, case, t):
    """(crank angle θ2 in rad, speed in rpm) of `case` at the times `t` (s), in the
    closed forms of docs/model.md §1.5 for a constant speed, a ramp and a sine.
    Raises ValueError for a `table` profile (its knots are only in the grid text)."""
    t = np.asarray(t, dtype=float)
    rpm = constant_rpm(ds, case)
    if math.isfinite(rpm):
        return 2 * math.pi * rpm / 60 * t, np.full_like(t, rpm)
    profile = text(ds["speed_profile"].values[case])
    to_rad = 2 * math.pi / 60
    if profile == "ramp":
        w0, w1 = parameter_value(ds, "speed_from", case), parameter_value(ds, "speed_to", case)
        over = parameter_value(ds, "speed_over", case)
        rate = (w1 - w0) / over
        tau = np.minimum(t, over)
        theta = w0 * tau + 0.5 * rate * tau**2 + w1 * np.maximum(t - over, 0.0)
        return to_rad * theta, w0 + rate * tau
    if profile == "sine":
        wm, wa = parameter_value(ds, "speed_mean", case), parameter_value(ds, "speed_amplitude", case)
        nu = 2 * math.pi * parameter_value(ds, "speed_frequency", case)
        theta = wm * t + 2 * wa / nu * np.sin(0.5 * nu * t) ** 2
        return to_rad * theta, wm + wa * np.sin(nu * t)
    raise ValueError(f"case {int(ds['case'].values[case])}: no closed-form crank angle for "
                     f"speed profile {profile!r} (constant, ramp and sine have one)")


@dataclass(frozen=True)
class FaultOrders:
    """The characteristic lines of a case's bearing as orders of the crank speed
    (cycles per crank revolution, docs/model.md §7.3): multiply by rpm/60 for Hz."""

    ftf: float
    bpfo: float
    bpfi: float
    bsf: float

    def lines(self):
        """{name in FAULT_LINES: order}."""
        return {"FTF": self.ftf, "BPFO": self.bpfo, "BPFI": self.bpfi, "BSF": self.bsf, "2·BSF": 2 * self.bsf}


def fault_orders(ds, case):
    """FTF, BPFO, BPFI and BSF of `case` per crank revolution, from its location,
    ball count and raceway diameters (docs/model.md §7.3: the mean race speeds at
    1 rev/s). A recordings study's file has no location: its stored `*_order`
    variables are read (from its `bearing.geometry`, contact angle included). Raises
    ValueError for an `ideal` case (no bearing)."""
    if "location" not in ds and "bpfo_order" in ds:
        return FaultOrders(**{k: float(ds[f"{k}_order"].values[case]) for k in ("ftf", "bpfo", "bpfi", "bsf")})
    omega_i, omega_o = race_speeds(text(ds["location"].values[case]), 60.0)
    d_i = parameter_value(ds, "inner_race_diameter", case)
    d_o = parameter_value(ds, "outer_race_diameter", case)
    balls = parameter_value(ds, "ball_count", case)
    omega_m = (omega_i * d_i + omega_o * d_o) / (d_i + d_o)
    ball, pitch = 0.5 * (d_o - d_i), 0.5 * (d_i + d_o)
    f_r = abs(omega_i - omega_o) / (2 * math.pi)
    return FaultOrders(
        ftf=abs(omega_m) / (2 * math.pi),
        bpfo=balls * abs(omega_m - omega_o) / (2 * math.pi),
        bpfi=balls * abs(omega_i - omega_m) / (2 * math.pi),
        bsf=pitch / (2 * ball) * (1 - (ball / pitch) ** 2) * f_r,
    )


def window_series(ds, name, case):
    """(times in s, samples) of series `name` of `case` over the analysed window
    transient ≤ t < duration (docs/model.md §5.3)."""
    mask = analysis_window(ds)
    return ds["time"].values[mask], np.asarray(ds[name].values[case], dtype=float)[mask]


def band_analytic(spectrum, freqs, n, low, high):
    """The analytic signal of the band low ≤ f ≤ high (Hz) from the real FFT
    `spectrum` (at `freqs`) of `n` samples: the band's bins doubled, but DC and (even
    n) Nyquist kept once, as they have no negative-frequency twin (docs/model.md §7.4
    step 2). Returns (z, whether the band holds a bin)."""
    weight = np.full(len(freqs), 2.0)
    weight[0] = 1.0
    if n % 2 == 0:
        weight[-1] = 1.0
    keep = (freqs >= low) & (freqs <= high)
    z = np.zeros(n, dtype=complex)
    z[: len(freqs)][keep] = weight[keep] * spectrum[keep]
    return np.fft.ifft(z), keep.any()


def analytic_signal(x, sample_rate, low, high):
    """The analytic signal of the band low ≤ f ≤ high (Hz) of the samples `x`, their
    mean removed (docs/model.md §7.4 steps 1–3: a brick wall on the FFT bins)."""
    y = np.asarray(x, dtype=float) - np.mean(x)
    n = len(y)
    freqs = np.fft.rfftfreq(n, 1.0 / sample_rate)
    return band_analytic(np.fft.rfft(y), freqs, n, low, high)[0]


def envelope_spectrum(x, sample_rate, low, high):
    """(frequencies in Hz, amplitudes) of the squared envelope of the band low–high,
    mean removed, with the file's spectrum convention (docs/model.md §7.4 steps 4–5);
    the amplitudes are in the series' units squared."""
    power = np.abs(analytic_signal(x, sample_rate, low, high)) ** 2
    return amplitude_spectrum(power - power.mean(), sample_rate)


def kurtogram_depth(n):
    """The deepest binary level K ≤ 6 whose bands of a window of `n` samples hold at
    least 16 bins, n / 2^(K+1) ≥ 16 (0 when even the whole band holds fewer)."""
    return next((k for k in range(KURTOGRAM_MAX_LEVEL, -1, -1) if n >> (k + 1) >= 16), 0)


def kurtogram_levels(depth):
    """[(level, bands at that level)] of the 1/3-binary tree in the order the bands
    are compared (docs/model.md §7.6): level 0 with one band, then for k = 1..depth
    the level k − 1 + log2 3 − 1 with 3·2^(k−2) bands (k ≥ 2) and the level k with 2^k."""
    levels = [(0.0, 1)]
    for k in range(1, depth + 1):
        if k >= 2:
            levels.append((k - 1 + math.log2(3) - 1, 3 << (k - 2)))
        levels.append((float(k), 1 << k))
    return levels


@dataclass(frozen=True)
class Kurtogram:
    """A fast kurtogram: per level, the kurtosis <|z|⁴>/<|z|²>² − 2 of each band's
    analytic signal (NaN where a band holds no bin or no power), and the choice."""

    sample_rate: float
    levels: list
    """[(level, [kurtosis of band i of m, i = 0..m−1])] in the order compared."""
    band: tuple
    """(low, high) in Hz of the band of largest kurtosis, the first on a tie."""
    level: float
    """Its level."""
    kurtosis: float
    """Its kurtosis."""


def kurtogram(x, sample_rate):
    """The fast kurtogram of the samples `x` at `sample_rate` (Hz) as studyrun
    computes it for `band: kurtogram` (docs/model.md §7.6): each band's analytic signal by
    the brick wall of §7.4, band i of m spanning [i f_N/m, (i+1) f_N/m], f_N = f_s/2."""
    x = np.asarray(x, dtype=float)
    n = len(x)
    nyquist = 0.5 * sample_rate
    spectrum = np.fft.rfft(x - x.mean())
    freqs = np.fft.rfftfreq(n, 1.0 / sample_rate)
    rows, best = [], (math.nan, (math.nan, math.nan), math.nan)
    for level, m in kurtogram_levels(kurtogram_depth(n)):
        values = []
        for i in range(m):
            low, high = i * nyquist / m, (i + 1) * nyquist / m
            z, any_bin = band_analytic(spectrum, freqs, n, low, high)
            power = np.abs(z) ** 2
            mean = power.mean()
            value = np.mean(power**2) / mean**2 - 2 if any_bin and mean > 0 else math.nan
            values.append(value)
            if value > best[2] or (math.isnan(best[2]) and math.isfinite(value)):
                best = (level, (low, high), value)
        rows.append((level, values))
    return Kurtogram(sample_rate, rows, best[1], best[0], best[2])


def stft(x, sample_rate, segment, hop):
    """Short-time amplitude spectra of `x`: segments of `segment` samples every `hop`,
    each with the file's convention (periodic Hann, a sinusoid of amplitude A on a bin
    reads A). Returns (segment centre times from the first sample in s, frequencies in
    Hz, amplitudes [time, frequency])."""
    x = np.asarray(x, dtype=float)
    if segment > len(x):
        raise ValueError(f"a segment of {segment} samples is longer than the series ({len(x)})")
    starts = np.arange(0, len(x) - segment + 1, hop)
    rows = [amplitude_spectrum(x[s : s + segment], sample_rate)[1] for s in starts]
    freqs = np.fft.rfftfreq(segment, 1.0 / sample_rate)
    return (starts + 0.5 * segment) / sample_rate, freqs, np.array(rows)


def order_spectrum(x, theta, samples_per_revolution):
    """The amplitude spectrum over crank orders of the samples `x` taken at crank
    angles `theta` (rad, increasing): resampled linearly at `samples_per_revolution`
    uniform angles per revolution over the whole revolutions from theta[0], then
    transformed with the file's convention. Returns (orders, amplitudes)."""
    revolutions = math.floor((theta[-1] - theta[0]) / (2 * math.pi))
    if revolutions < 1:
        raise ValueError("the window holds no whole crank revolution")
    count = revolutions * samples_per_revolution
    uniform = theta[0] + 2 * math.pi * np.arange(count) / samples_per_revolution
    return amplitude_spectrum(np.interp(uniform, theta, x), samples_per_revolution)
