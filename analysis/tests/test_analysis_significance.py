"""analysis/significance.py: Welch's test with the integrator's floor decides which
differences are significant."""

import numpy as np

from analysis.significance import compare


def test_separated_samples_are_significant_and_equal_ones_are_not():
    rng = np.random.default_rng(0)
    a, b = rng.normal(10.0, 0.1, 16), rng.normal(11.0, 0.1, 16)
    diff, p, sig = compare(a, b)
    assert sig and p < 1e-10 and abs(diff - 1.0) < 0.1
    # Another draw of the same distribution.
    _, p, sig = compare(a, np.random.default_rng(1).normal(10.0, 0.1, 16))
    assert not sig and p > 0.05, p


def test_differences_below_the_floor_are_not_significant_however_small_the_spread():
    a = 10.0 + 1e-9 * np.arange(16)
    # Welch's p is tiny, but 1e-4 of the mean is below the integrator's floor.
    diff, p, sig = compare(a, a + 1e-3)
    assert p < 1e-10 and not sig
    # Replicates that do not vary at all: the floor alone decides.
    const = np.full(16, 10.0)
    assert compare(const, const + 0.5)[2]
    assert not compare(const, const + 1e-3)[2]
