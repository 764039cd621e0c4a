"""Defect pass frequencies of analysis/faults.py (docs/model.md section 2.9)."""

import numpy as np
import pytest

from analysis.faults import amplitude_near, pass_frequency

D_I, D_O = 29.2e-3, 46.6e-3


@pytest.mark.parametrize("location", ["crank_ground", "crank_rod"])
def test_pass_frequencies_are_the_textbook_ones(location):
    """BPFO = N/2 (1 - D/d_m) Δf, BPFI = N/2 (1 + D/d_m) Δf, BSF = d_m/(2D) (1 - (D/d_m)^2) Δf
    with D = 8.7 mm, d_m = 37.9 mm; Δf = 10 Hz at 600 rpm at either location."""
    d, dm, df = 8.7e-3, 37.9e-3, 10.0
    assert pass_frequency("outer", location, 600, 9, D_I, D_O) == pytest.approx(4.5 * (1 - d / dm) * df, rel=1e-12)
    assert pass_frequency("inner", location, 600, 9, D_I, D_O) == pytest.approx(4.5 * (1 + d / dm) * df, rel=1e-12)
    bsf = dm / (2 * d) * (1 - (d / dm) ** 2) * df
    assert pass_frequency("ball", location, 600, 9, D_I, D_O) == pytest.approx(2 * bsf, rel=1e-12)
    assert pass_frequency("outer", location, 600, 9, D_I, D_O) == pytest.approx(34.67, abs=0.005)


def test_amplitude_near_takes_the_largest_neighbouring_bin():
    freq = [0.0, 1.0, 2.0, 3.0, 4.0]
    spectrum = np.array([0.0, 5.0, 1.0, 0.5, 9.0])
    assert amplitude_near(np.array(freq), spectrum, 2.2) == 5.0
