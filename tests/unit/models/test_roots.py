"""Event-root searches of vibrofeed/models/roots.py on functions and drives with known roots."""

import numpy as np
import pytest

from vibrofeed.models.roots import XTOL, all_roots, slip_end, stick_exit
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


@pytest.mark.parametrize("s", [1, -1])
@pytest.mark.parametrize("w0", [0.1, 0.5])
def test_a_slip_whose_relative_velocity_dips_ends_only_if_the_dip_reaches_zero(s, w0):
    """a_s = a0 + slope t crosses a_p = 0 at t = 1/2 on one piece [0, 1] (a0 = -s, slope = 2 s):
    from s w(0) = w0 > 0 (an initial condition, not an event) s w = w0 - t + t^2 falls to its
    minimum w0 - 1/4 at t = 1/2 and rises again. For w0 = 0.1 the minimum is below zero and the
    slip ends at the first root (1 - sqrt(1 - 4 w0)) / 2; for w0 = 0.5 it stays above: no end."""
    P = _linear_accel(-s, 2.0 * s).pieces(0.0, 1.0)   # v_s = 1 - s t + s t^2
    assert P.n == 1
    v_p0 = 1.0 - s * w0
    got = slip_end(P, 0, 0.0, v_p0, s, 0.0, 1e-12, from_zero=False)
    if w0 < 0.25:
        assert got[1] == 0
        assert got[0] == pytest.approx((1 - np.sqrt(1 - 4 * w0)) / 2, abs=1e-13)   # s
    else:
        assert got is None


def test_an_acceleration_touching_the_band_edge_and_turning_inward_does_not_leave_it():
    """a_s = 4 - 4 |t - 1| rises to the band's top hi = 4 exactly at its turning point t = 1 and
    falls back: the band [lo, hi] is closed, so it never leaves it, whether the search starts
    before the touch (the second piece starts on the edge) or at it (held=False)."""
    def s(t):
        return np.asarray(t, dtype=float) - 1.0

    touch = CallableSurface(lambda t: 2 / 3 + 2 * s(t) + 2 * s(t) ** 2 - 2 / 3 * s(t) ** 2 * np.abs(s(t)),
                            lambda t: 2 + 4 * s(t) - 2 * s(t) * np.abs(s(t)),
                            lambda t: 4 - 4 * np.abs(s(t)), turning_points=[1.0])
    P = touch.pieces(0.0, 2.0)
    assert P.n == 2 and P.a_start[1] == 4.0
    assert stick_exit(P, 0, 0.0, -20.0, 4.0) is None
    assert stick_exit(P, 1, 1.0, -20.0, 4.0) is None
    # the same band lowered by 1 m/s^2 is left where a_s = 3, at t = 3/4, upward
    t_x, j, side = stick_exit(P, 0, 0.0, -20.0, 3.0)
    assert (j, side) == (0, 1) and t_x == pytest.approx(0.75, abs=1e-13)
