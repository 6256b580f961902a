"""The flights' own Hermite interpolant and cubic roots against scipy's (postproc.flights writes
them out to keep scipy.interpolate's import out of a short run's summary)."""

import numpy as np
import pytest
from scipy.interpolate import CubicHermiteSpline, PPoly

from vibrofeed.postproc.flights import Hermite, cubic_roots


def test_values_and_slopes_equal_scipys():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(1e-4, 2e-3, 40))
    y, dy = 1e-4 * rng.standard_normal(40), 0.1 * rng.standard_normal(40)
    ours, theirs = Hermite(t, y, dy), CubicHermiteSpline(t, y, dy)
    np.testing.assert_allclose(ours.c, theirs.c, rtol=1e-12, atol=0)
    x = np.linspace(t[0] - 1e-3, t[-1] + 1e-3, 997)  # beyond the knots too
    np.testing.assert_allclose(ours(x), theirs(x), rtol=0, atol=1e-12 * np.abs(y).max())
    np.testing.assert_allclose(ours(x, 1), theirs(x, 1), rtol=0, atol=1e-10 * np.abs(dy).max())


@pytest.mark.parametrize("roots, outside", [([0.2, 0.5, 0.9], []), ([0.3], [3.0, -2.0]),
                                             ([0.0, 1.0], [4.0]), ([0.1, 0.6], None)])
def test_roots_in_the_interval(roots, outside):
    # a gap in metres over 1 ms through the given roots (and others outside the interval); None:
    # a quadratic, whose leading term is absent
    t0, h = 0.25, 1e-3
    if outside is None:
        c = np.concatenate([[0.0], 1e-6 / h**2 * np.poly([r * h for r in roots])])
    else:
        c = 1e-6 / h**3 * np.poly([r * h for r in roots + outside])
    got = cubic_roots(c, t0, t0 + h)
    np.testing.assert_allclose(got, t0 + np.array(roots) * h, rtol=0, atol=1e-12 * h)
    want = PPoly(c[:, None], [t0, t0 + h]).roots(extrapolate=False)
    np.testing.assert_allclose(got, want[np.isfinite(want)], rtol=0, atol=1e-12 * h)


def test_no_roots_and_a_zero_cubic():
    assert cubic_roots([0.0, 1.0, 0.0, 1.0], 0.0, 1e-3).size == 0  # s^2 + 1 > 0
    assert cubic_roots([0.0, 0.0, 0.0, 0.0], 0.0, 1e-3).size == 0
