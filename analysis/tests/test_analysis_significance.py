"""analysis/significance.py: Welch's test with the integrator's floor decides which
differences are significant."""

import numpy as np

from analysis.significance import Case, compare, figure


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


def test_the_figure_draws_every_location_and_waviness(tmp_path):
    rng = np.random.default_rng(2)
    cases = [
        Case(loc, rpm, w, balls, v, float(v.mean()), 0.1, float(balls == 10))
        for loc in ("crank_ground", "crank_rod")
        for rpm in (300.0, 600.0)
        for w in (0.0, 4e-6)
        for balls in (8, 9, 10, 11)
        for v in [rng.normal(balls, 0.1, 16)]
    ]
    out = figure(cases, "slider_acceleration_rms_deviation", tmp_path / "f.png")
    import matplotlib.image as mpimg

    image = mpimg.imread(out)
    assert image.shape[0] > 500 and image.shape[1] > 800
