"""Event-root searches of vibrofeed/models/roots.py on functions and drives with known roots."""

import numpy as np
import pytest

from vibrofeed.models.roots import XTOL, all_roots, slip_end
from vibrofeed.models.surface import CallableSurface


def test_a_root_on_a_split_shared_by_two_pieces_is_listed_once():
    # f = (t - 1)(t - 3) is monotone on [0, 2] and [2, 4]; g = t - 1 is zero exactly on its split
    def f(t):
        return (t - 1.0) * (t - 3.0)

    assert all_roots(f, 0.0, 4.0, [2.0], XTOL) == pytest.approx([1.0, 3.0], abs=1e-14)
    assert all_roots(lambda t: t - 1.0, 0.0, 2.0, [1.0], XTOL) == [1.0]
    assert all_roots(lambda t: t - 1.0, 0.0, 2.0, [0.5, 1.0, 1.5], XTOL) == [1.0]


def _linear_accel(a0, slope):
    """x_s = t + a0 t^2 / 2 + slope t^3 / 6: v_s(0) = 1, a_s = a0 + slope t (one monotone piece)."""
    def x(t):
        t = np.asarray(t, dtype=float)
        return t + a0 * t ** 2 / 2 + slope * t ** 3 / 6

    def v(t):
        t = np.asarray(t, dtype=float)
        return 1.0 + a0 * t + slope * t ** 2 / 2

    return CallableSurface(x, v, lambda t: a0 + slope * np.asarray(t, dtype=float), turning_points=[])


@pytest.mark.parametrize("s, slope", [(1, 0.0), (-1, 0.0), (1, -0.5), (-1, 0.5)])
def test_a_slip_from_zero_that_cannot_move_away_ends_at_once(s, slope):
    """From w = v_s - v_p = 0 with a_s = a_p at the start, w' = a_s - a_p stays 0 (slope 0) or
    turns against s (s * slope < 0, by less than 1 m/s^2 over the piece): s * w never becomes
    positive, so the slip ends where it starts and the caller decides again."""
    a_p = -0.5
    P = _linear_accel(a_p, slope).pieces(0.0, 1.0)
    assert P.n == 1
    assert slip_end(P, 0, 0.0, 1.0, s, a_p, 1e-12, from_zero=True) == (0.0, 0)
