"""Writes the synthetic rig recordings of studies/recordings.yaml and
tests/recordings_study.rs: a 9-ball bearing (D = 7.94 mm, d_m = 39.04 mm, contact
angle 0) at 1800 rpm (30 Hz), sampled at 12 kHz. A localized fault strikes once per
ball pass, BPFO = 107.55 Hz (outer race) or BPFI = 162.45 Hz (inner race, the impacts
modulated at the shaft speed), each impact ringing a 3 kHz resonance that decays in
1 ms, in Gaussian noise; the healthy recording is the noise and a 30 Hz shaft line.
The files differ in length (the outer-race one is the shortest) and format.

Run from this folder: python make.py (NumPy and SciPy; seeded, so the files repeat).
"""
import numpy as np
import scipy.io
import scipy.io.wavfile

RATE = 12_000
SHAFT = 30.0
N_B, D, DM = 9, 7.94, 39.04
BPFO = N_B / 2 * SHAFT * (1 - D / DM)
BPFI = N_B / 2 * SHAFT * (1 + D / DM)
rng = np.random.default_rng(35)


def impacts(n, rate_hz, modulated):
    t = np.arange(n) / RATE
    x = np.zeros(n)
    k = 0
    while (tk := k / rate_hz + rng.normal(0, 2e-4)) < t[-1]:
        if tk > 0:
            a = 1 + 0.5 * np.cos(2 * np.pi * SHAFT * tk) if modulated else 1.0
            dt = t - tk
            on = dt >= 0
            x[on] += a * np.exp(-dt[on] / 1e-3) * np.sin(2 * np.pi * 3000 * dt[on])
        k += 1
    return x + 0.3 * rng.normal(size=n)


outer = impacts(6000, BPFO, False)
inner = impacts(7200, BPFI, True)
t = np.arange(6600) / RATE
healthy = 0.3 * rng.normal(size=6600) + 0.2 * np.sin(2 * np.pi * SHAFT * t)

np.save("outer.npy", outer.astype(np.float32))
scipy.io.wavfile.write("inner.wav", RATE, (inner / 8 * 32767).astype(np.int16))
scipy.io.savemat("healthy.mat", {"rig": {"de": healthy.astype(np.float32)}}, oned_as="column")
