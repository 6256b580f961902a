"""Surface motions at the edges their docstrings state: sampling densities, times a hair
before a period's end or a breakpoint, generic acceleration roots against closed forms,
B-splines with repeated knots, and the bounds of the drive constructors."""

import math

import numpy as np
import pytest
from scipy.interpolate import make_interp_spline

from vibrofeed.validation.models.surface import (
    CallableSurface,
    CoulombPumpWaveform,
    PiecewiseConstantAccel,
    PolynomialSurface,
    StickSlipWaveform,
    _unique_sorted,
    sine_drive,
    two_level_drive,
)

A, F = 1e-3, 50.0
W = 2 * math.pi * F


def sine_callables(**kw):
    return CallableSurface(lambda t: A * np.sin(W * np.asarray(t)),
                           lambda t: A * W * np.cos(W * np.asarray(t)),
                           lambda t: -A * W * W * np.sin(W * np.asarray(t)), **kw)


def test_without_turning_points_the_acceleration_is_sampled_as_documented():
    assert sine_callables(period=1 / F).pieces(0.0, 1 / F).n == 256          # period / 256
    assert sine_callables().pieces(0.0, 0.05).n == 4096                       # window / 4096
    assert sine_callables(max_step=1e-3).pieces(0.0, 0.05).n == 50


def test_generic_acceleration_roots_of_a_sine():
    # -A w^2 sin(w t) = level: at level -A w^2 / 2, sin = 1/2 at T/12 and 5 T/12
    s = sine_callables(period=1 / F)
    T = 1 / F
    roots = s.accel_roots(1.0, 0.0, -0.5 * A * W * W, 0.0, T / 2)
    assert roots == pytest.approx([T / 12, 5 * T / 12], abs=1e-15)
    assert s.accel_roots(1.0, 0.0, 0.5 * A * W * W, 0.0, T / 2).size == 0


def test_near_duplicate_edges_are_merged_keeping_both_ends():
    assert _unique_sorted(np.array([0.5, 1.0 - 1e-16]), 0.0, 1.0).tolist() == [0.0, 0.5, 1.0]
    assert _unique_sorted(np.array([1e-17, 0.5]), 0.0, 1.0).tolist() == [0.0, 0.5, 1.0]


def test_a_time_a_hair_before_the_period_end_is_in_the_next_period():
    wf = PiecewiseConstantAccel([0.01, 0.01], [1.0, -1.0])
    assert float(wf.acceleration(0.02 - 1e-16)[0]) == 1.0          # the first piece's
    assert float(wf.acceleration(0.015)[0]) == -1.0
    # the next breakpoint is the first more than 1e-12 periods after t
    assert wf.next_breakpoint(0.01 - 1e-12) == pytest.approx(0.01, abs=1e-15)
    assert wf.next_breakpoint(0.01) == pytest.approx(0.02, abs=1e-15)


def test_zero_length_pieces_are_dropped():
    wf = PiecewiseConstantAccel([0.01, 0.0, 0.01], [1.0, 5.0, -1.0])
    assert wf.durations.tolist() == [0.01, 0.01] and wf.period == pytest.approx(0.02)


def test_stick_slip_peak_speed_is_half_the_velocity_swing():
    wf = StickSlipWaveform(20.0, 3.0, 7.0)
    v = wf.velocity(np.linspace(0, wf.period, 2001))[0]
    assert wf.peak_speed == pytest.approx(v.max(), rel=1e-9) == pytest.approx(-v.min(), rel=1e-9)
    assert StickSlipWaveform.from_peak_speed(20.0, 0.1, 0.3).peak_speed == pytest.approx(0.1)


def test_a_b_spline_with_repeated_knots_is_the_same_motion():
    x = np.linspace(0.0, 1.0, 9)
    spl = make_interp_spline(x, np.sin(2 * np.pi * x), k=3)   # end knots repeated 4 times
    s = PolynomialSurface(spl)
    t = np.linspace(0.05, 0.95, 7)
    assert s.position(t)[0] == pytest.approx(spl(t), abs=1e-12)


def test_constructors_refuse_what_their_docstrings_exclude():
    with pytest.raises(ValueError):
        sine_drive(A, 0.0)
    with pytest.raises(ValueError, match="positive"):
        CoulombPumpWaveform(F, 0.0, 10.0)
    spl = make_interp_spline(np.linspace(0.0, 0.5, 9), np.sin(np.linspace(0, 2 * np.pi, 9)), k=3)
    with pytest.raises(ValueError, match="span one period"):
        PolynomialSurface(spl, period=1.0)
    d = two_level_drive(1.0, 1e-3, 0.5)                        # a gentle drop is allowed
    assert d.period == pytest.approx(3e-3)
