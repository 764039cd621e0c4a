"""Writes the recordings fixtures with NumPy and SciPy, the independent writers the
readers of src/recordings/read are checked against (tests.rs there reads them).

Run from this folder: python make.py. Every value is exact in float32 and int16.
"""
import numpy as np
import scipy.io
import scipy.io.wavfile

x = np.arange(-8, 8) / 8.0  # -1.0, -0.875, ..., 0.875
n = (np.arange(16) * 1000 - 8000).astype(np.int16)

np.save("numpy_be_f4.npy", x.astype(">f4"))
np.save("numpy_i2_column.npy", n.reshape(-1, 1))
np.savez("numpy_stored.npz", a=x, b=n)
np.savez_compressed("numpy_deflated.npz", a=x, b=n)
scipy.io.wavfile.write("scipy_i16_stereo.wav", 12000, np.stack([n, -n - 1], axis=1))
scipy.io.wavfile.write("scipy_f32.wav", 48000, x.astype(np.float32))
scipy.io.savemat(
    "scipy_compressed.mat",
    {"bearing": {"gs": x, "sr": 12000.0, "n": n}, "label": "inner race"},
    do_compression=True,
    oned_as="column",
)
scipy.io.savemat("scipy_plain.mat", {"acc": x, "n": n}, oned_as="row")
np.savetxt("numpy.csv", np.stack([x, n], axis=1), delimiter=",", header="x,n", comments="")
