"""Surface motions at the edges their docstrings state: sampling densities, times a hair
before a period's end or a breakpoint, generic acceleration roots against closed forms,
B-splines with repeated knots, and the bounds of the drive constructors."""

import math

import numpy as np
import pytest
from scipy.interpolate import BSpline, PPoly, make_interp_spline

from vibrofeed.models.surface import (
    CallableSurface,
    CoulombPumpWaveform,
    PiecewiseConstantAccel,
    PolynomialSurface,
    SampledWaveform,
    SineWaveform,
    SquareWaveAccel,
    StickSlipWaveform,
    _unique_sorted,
    sampled_pieces,
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
    assert wf.durations.tolist() == [0.01, 0.01] and wf.period == pytest.approx(0.02, rel=1e-12)


def test_stick_slip_peak_speed_is_half_the_velocity_swing():
    wf = StickSlipWaveform(20.0, 3.0, 7.0)
    v = wf.velocity(np.linspace(0, wf.period, 2001))[0]
    assert wf.peak_speed == pytest.approx(v.max(), rel=1e-9) == pytest.approx(-v.min(), rel=1e-9)
    assert StickSlipWaveform.from_peak_speed(20.0, 0.1, 0.3).peak_speed == pytest.approx(0.1, rel=1e-12)


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
    assert d.period == pytest.approx(3e-3, rel=1e-12)


def test_the_default_sampling_step_of_a_window_is_exactly_a_4096th():
    # windows whose 4095th part would also round to 4095 samples: only / 4096 gives 4096
    for t1 in (1.0, 0.3, 0.02):
        assert sine_callables().pieces(0.0, t1).n == 4096


def test_a_gap_of_exactly_eight_ulps_is_merged_and_a_lone_edge_next_to_the_end_too():
    tol = 8 * np.finfo(float).eps                     # = 2**-49 on [0, 1]
    assert _unique_sorted(np.array([0.5, 0.5 + tol]), 0.0, 1.0).tolist() == [0.0, 0.5, 1.0]
    assert _unique_sorted(np.array([0.5, 0.5 + 2 * tol]), 0.0, 1.0).tolist() == [0.0, 0.5, 0.5 + 2 * tol, 1.0]
    assert _unique_sorted(np.array([1.0 - 1e-16]), 0.0, 1.0).tolist() == [0.0, 1.0]


def test_sampled_pieces_take_one_sided_accelerations_whichever_side_the_callable_gives():
    # a = +1 before 0.5, -1 after; at 0.5 this callable gives the LEFT value (t <= 0.5)
    def acc(t):
        return np.where(np.asarray(t) <= 0.5, 1.0, -1.0)

    def vel(t):
        return 0.5 - np.abs(np.asarray(t) - 0.5)

    def pos(t):
        s = np.asarray(t) - 0.5
        return 0.5 * np.asarray(t) - 0.5 * s * np.abs(s)

    p = sampled_pieces(pos, vel, acc, 0.0, 1.0, breakpoints=[0.5], turning_points=[])
    assert p.edges.tolist() == [0.0, 0.5, 1.0]
    assert p.a_start.tolist() == [1.0, -1.0] and p.a_end.tolist() == [1.0, -1.0]
    assert p.local(1, 0.5, 2) == -1.0 and p.local(0, 0.5, 2) == 1.0
    assert p.v == pytest.approx([0.0, 0.5, 0.0], abs=1e-15)


def _rise_fall(x0=0.0):
    """a_x = +1 on [x0, x0 + 1/2], -1 on [x0 + 1/2, x0 + 1]; v = -1/4 + (t - x0) on the rise."""
    c = np.array([[0.5, -0.5], [-0.25, 0.25], [0.0, 0.0]])
    return PPoly(c, [x0, x0 + 0.5, x0 + 1.0], extrapolate=False)


def test_a_non_periodic_polynomial_has_its_interior_knots_as_open_interval_breakpoints():
    s = PolynomialSurface(_rise_fall())
    assert s.domain == (0.0, 1.0)
    assert s.breakpoints(0.0, 1.0).tolist() == [0.5]
    assert s.breakpoints(0.25, 0.75).tolist() == [0.5]
    assert s.breakpoints(0.5, 1.0).size == 0 and s.breakpoints(0.0, 0.5).size == 0   # (t0, t1) is open
    # next breakpoint: the first more than 1e-12 max(1, |t|) after t
    assert s.next_breakpoint(0.2) == 0.5
    assert s.next_breakpoint(0.5 - 1.5e-12) == 0.5
    assert s.next_breakpoint(0.5 - 0.5e-12) == 1.0
    assert s.next_breakpoint(1.0) == math.inf


def test_a_non_periodic_polynomial_is_cut_at_its_knots():
    p = PolynomialSurface(_rise_fall()).pieces(0.0, 1.0)
    assert p.edges.tolist() == [0.0, 0.5, 1.0]
    assert p.a_start.tolist() == [1.0, -1.0] and p.a_end.tolist() == [1.0, -1.0]
    assert p.v == pytest.approx([-0.25, 0.25, -0.25], abs=1e-15)


def test_a_periodic_polynomial_not_starting_at_zero_repeats_from_its_own_start():
    s = PolynomialSurface(_rise_fall(0.25), period=1.0)
    # a_x = +1 on [0.25, 0.75) + k, -1 on [0.75, 1.25) + k
    t = np.array([0.1, 0.5, 1.0, 1.5, -0.5])
    assert s.acceleration(t)[0].tolist() == [-1.0, 1.0, -1.0, 1.0, 1.0]
    assert s.velocity(np.array([0.25, 0.75, 2.25]))[0] == pytest.approx([-0.25, 0.25, -0.25], abs=1e-15)
    assert s.breakpoints(0.0, 1.0).tolist() == [0.25, 0.75]
    assert s.breakpoints(0.0, 2.0) == pytest.approx([0.25, 0.75, 1.25, 1.75], abs=1e-15)


def test_the_vectorised_path_counts_a_time_after_an_edge_only_within_1e_12_periods():
    wf = PiecewiseConstantAccel([0.01, 0.01], [1.0, -1.0])   # T = 0.02
    # 1e-11 s = 5e-10 T before the edge at 0.01: still the first piece, on both paths
    t = 0.01 - 1e-11
    assert wf.acceleration(np.array([t]))[0].tolist() == [1.0] and wf.acceleration(t)[0] == 1.0
    # 1e-15 s = 5e-14 T before it: counts as after, on both paths
    t = 0.01 - 1e-15
    assert wf.acceleration(np.array([t]))[0].tolist() == [-1.0] and wf.acceleration(t)[0] == -1.0


def test_the_wrap_into_the_next_period_starts_strictly_after_t_times_one_minus_1e_12():
    wf = PiecewiseConstantAccel([0.5, 0.5], [1.0, -1.0])     # T = 1
    c = 1.0 * (1 - 1e-12)
    assert wf.acceleration(c)[0] == -1.0 and wf.acceleration(np.array([c]))[0].tolist() == [-1.0]
    after = np.nextafter(c, 2.0)
    assert wf.acceleration(after)[0] == 1.0 and wf.acceleration(np.array([after]))[0].tolist() == [1.0]


def test_a_time_within_1e_12_periods_before_several_edges_counts_as_after_the_last():
    # a first piece of 1e-15 s (< 1e-12 T): the wrap to t = 0 lands within 1e-12 T before its end,
    # so the time is in the second piece, on both paths
    wf = PiecewiseConstantAccel([1e-15, 0.5, 0.5], [5.0, 1.0, -1.0])
    T = wf.period
    for t in (0.0, T * (1 - 1e-13), 3 * T - 1e-14):
        assert wf.acceleration(np.array([t]))[0].tolist() == [1.0] and wf.acceleration(t)[0] == 1.0


def test_piecewise_constant_accel_refuses_durations_that_are_all_zero():
    with pytest.raises(ValueError, match="positive sum"):
        PiecewiseConstantAccel([0.0, 0.0], [1.0, -1.0])


def test_coulomb_pump_at_the_bound_peak_speed_is_a_symmetric_triangle():
    accel = 40.0
    T = 1.0 / F
    wf = CoulombPumpWaveform(F, accel * T / 4, accel)            # the bound itself is allowed
    assert wf.forward_fraction == pytest.approx(0.0, abs=1e-12)
    assert wf.back_speed == pytest.approx(accel * T / 4, rel=1e-12)
    with pytest.raises(ValueError, match="peak_speed must be"):
        CoulombPumpWaveform(F, accel * T / 4 * (1 + 1e-9), accel)


def test_sine_level_crossings_over_several_periods():
    # -A w^2 sin(w t) = -A w^2 / 2: sin(w t) = 1/2 at T/12 and 5T/12 of every period
    T = 1 / F
    roots = SineWaveform(F, A, 0.0).accel_roots(1.0, 0.0, -0.5 * A * W * W, 0.0, 5 * T)
    expected = sorted(k * T + f * T for k in range(5) for f in (1 / 12, 5 / 12))
    assert roots == pytest.approx(expected, abs=1e-15)


def test_sine_level_crossings_do_not_depend_on_how_small_the_amplitude_is():
    # amplitude 1e-302 m: R w^2 ~ 1e-297 is still a representable acceleration scale
    a = 1e-302
    T = 1 / F
    roots = SineWaveform(F, a, 0.0).accel_roots(1.0, 0.0, -0.5 * a * W * W, 0.0, T)
    assert roots == pytest.approx([T / 12, 5 * T / 12], abs=1e-15)
    assert SineWaveform(F, 0.0, 0.0).accel_roots(1.0, 0.0, 0.0, 0.0, T).size == 0


def _accel_only(accel, period=None):
    """A surface at rest but for the along-track acceleration ``accel(t)``: only its roots matter."""
    def still(t):
        return np.zeros_like(np.asarray(t, dtype=float))
    return CallableSurface(still, still, accel, period=period)


def _four_sample_spline():
    # periodic cubic spline of 0, 1, 0, -1 (h = 1/4): moments M solve
    # M[i-1] + 4 M[i] + M[i+1] = 96 (y[i-1] - 2 y[i] + y[i+1]) -> M = 0, -48, 0, 48
    return SampledWaveform(1.0, [0.0, 1.0, 0.0, -1.0])


def test_sampled_waveform_needs_four_samples():
    with pytest.raises(ValueError, match="at least 4"):
        SampledWaveform(1.0, [0.0, 1.0, -1.0])
    assert _four_sample_spline().acceleration(0.25)[0] == pytest.approx(-48.0, rel=1e-12)


def test_sampled_waveform_roots_are_in_the_half_open_window():
    wf = _four_sample_spline()
    # a_x linear from -48 at 1/4 to 0 at 1/2: level -24 at 3/8
    assert wf.accel_roots(1.0, 0.0, -24.0, 0.25, 0.5) == pytest.approx([0.375], abs=1e-12)
    # a crossing exactly at t1 is found (as t1), one exactly at t0 is not
    at_t1 = float(wf.acceleration(0.25)[0])
    assert wf.accel_roots(1.0, 0.0, at_t1, 0.0, 0.25).tolist() == [0.25]
    assert wf.accel_roots(1.0, 0.0, at_t1, 0.25, 0.5).size == 0


def test_sampled_waveform_roots_do_not_depend_on_the_scale_of_the_combination():
    # cx = 1e-200: f(t0) f(t1) ~ -1e-398 underflows to -0.0, yet the root is the same 3/8
    wf = _four_sample_spline()
    roots = wf.accel_roots(1e-200, 0.0, -24e-200, 0.25, 0.5)
    assert roots == pytest.approx([0.375], abs=1e-12)


def test_generic_roots_resolve_a_close_pair_straddling_the_middle_sample():
    # a_x = (t - 0.4995)(t - 0.5005) on the window [0, 1]: 400 intervals put a sample at 0.5,
    # between the two roots, so both are bracketed
    s = _accel_only(lambda t: (np.asarray(t) - 0.4995) * (np.asarray(t) - 0.5005))
    assert s.accel_roots(1.0, 0.0, 0.0, 0.0, 1.0) == pytest.approx([0.4995, 0.5005], abs=1e-12)


def test_the_merge_tolerance_scales_with_the_largest_time_of_the_window():
    # 8 eps max(1, |t0|, |t1|): on [0, 4] it is 2**-47, so a gap of 2**-48 (8 ulps at 2) is merged
    assert _unique_sorted(np.array([2.0, 2.0 + 2.0 ** -48]), 0.0, 4.0).tolist() == [0.0, 2.0, 4.0]
    assert _unique_sorted(np.array([2.0, 2.0 + 2.0 ** -46]), 0.0, 4.0).tolist() == [
        0.0, 2.0, 2.0 + 2.0 ** -46, 4.0]


def test_an_edge_exactly_eight_ulps_before_the_end_is_merged_into_it():
    tol = 8 * np.finfo(float).eps                     # = 2**-49 on [0, 1]: 1 - tol is exact
    assert _unique_sorted(np.array([1.0 - tol]), 0.0, 1.0).tolist() == [0.0, 1.0]
    assert _unique_sorted(np.array([1.0 - 2 * tol]), 0.0, 1.0).tolist() == [0.0, 1.0 - 2 * tol, 1.0]


def test_the_default_step_of_a_window_is_a_4096th_of_its_length_not_of_its_end():
    assert sine_callables().pieces(1.0, 1.05).n == 4096
    assert sine_callables().pieces(-2.0, -1.5).n == 4096


def _sawtooth(K, T):
    """a_x = K (f - 1/2), f = frac(t / T): a jump from K/2 down to -K/2 at every k T."""
    def frac(t):
        return np.mod(np.asarray(t, dtype=float) / T, 1.0)

    return CallableSurface(lambda t: K * T * T * (frac(t) ** 3 / 6 - frac(t) ** 2 / 4 + frac(t) / 12),
                           lambda t: K * T * (frac(t) ** 2 / 2 - frac(t) / 2 + 1 / 12),
                           lambda t: K * (frac(t) - 0.5), breakpoints=[0.0], period=T)


def test_one_sided_accelerations_at_a_jump_are_taken_a_hair_inside_the_piece():
    # sampled every T/256 with no turning points; the values either side of the jump at T
    # are the limits -K/2 (after) and +K/2 (before), to far better than 1e-6 K
    K, T = 100.0, 1 / F
    p = _sawtooth(K, T).pieces(0.0, 2 * T)
    j = int(np.argmin(np.abs(p.edges - T)))
    assert p.edges[j] == pytest.approx(T, abs=1e-15)
    assert p.a_start[j] == pytest.approx(-K / 2, abs=1e-6 * K)
    assert p.a_end[j - 1] == pytest.approx(K / 2, abs=1e-6 * K)
    assert p.local(j, T, 2) == pytest.approx(-K / 2, abs=1e-6 * K)


def test_frequency_is_the_inverse_period():
    assert SineWaveform(F, A, A).freq == pytest.approx(F, rel=1e-12)
    assert StickSlipWaveform(25.0, 3.0, 9.0).freq == pytest.approx(25.0, rel=1e-12)
    with pytest.raises(ValueError, match="not periodic"):
        _ = PolynomialSurface(_rise_fall()).freq


def _linear_knots(*knots):
    """x_s = t on each interval between the given knots (non-periodic, continuous)."""
    x = np.asarray(knots, dtype=float)
    c = np.vstack([np.ones(x.size - 1), x[:-1]])
    return PolynomialSurface(PPoly(c, x, extrapolate=False))


def test_non_periodic_breakpoints_exclude_only_1e_12_of_the_window_at_each_end():
    s = _linear_knots(0.0, 50.0, 100.0)
    # 1e-11 s after t0 is 1e-11 of this 1 s window: well inside, whatever the absolute times
    assert s.breakpoints(50.0 - 1e-11, 51.0).tolist() == [50.0]
    assert s.breakpoints(49.0, 50.0 + 1e-11).tolist() == [50.0]
    # a knot exactly at t1 - 1e-12 (t1 - t0), or t0 + 1e-12 (t1 - t0), is left out
    c = 1.0 - 1e-12 * (1.0 - 0.0)
    assert _linear_knots(0.0, c, 2.0).breakpoints(0.0, 1.0).size == 0
    assert _linear_knots(-1.0, 1e-12, 1.0).breakpoints(0.0, 1.0).size == 0


def test_breakpoints_of_a_motion_with_a_period_longer_than_a_second():
    wf = PiecewiseConstantAccel([2.0, 2.0], [1.0, -1.0])          # T = 4 s, edges at 0 and 2
    assert wf.breakpoints(9.0, 15.0) == pytest.approx([10.0, 12.0, 14.0], abs=1e-12)


def test_the_next_breakpoint_is_strictly_more_than_1e_12_periods_after_t():
    # t = tb - 1e-12 T: the breakpoint tb is then only exactly 1e-12 T after t (in floats,
    # checked), so it is passed over, and the next one (T/4 or 3T/4 later) is returned
    wf = StickSlipWaveform(10.0, 2.0, 6.0)                  # T = 0.1, edges at 0 and 0.075
    T = wf.period
    for k in range(10):
        for e, gap in ((0.0, 0.075), (wf.starts[1], 0.025)):
            tb = k * T + e
            t = tb - 1e-12 * T
            assert t + 1e-12 * T == tb
            got = wf.next_breakpoint(t)
            assert got > t + 1e-12 * T
            assert got == pytest.approx(tb + gap, abs=1e-12)


def test_a_b_spline_with_a_double_interior_knot_lists_that_breakpoint_once():
    knots = np.array([0, 0, 0, 0, 0.5, 0.5, 1, 1, 1, 1], dtype=float)
    spl = BSpline(knots, np.array([0.0, 1.0, 2.0, -1.0, 0.0, 1.0]), 3)
    s = PolynomialSurface(spl)
    assert s.breakpoints(0.0, 1.0).tolist() == [0.5]
    assert s.breakpoints(-0.5, 1.5).tolist() == [0.0, 0.5, 1.0]
    t = np.linspace(0.0, 1.0, 11)
    assert s.position(t)[0] == pytest.approx(spl(t), abs=1e-12)


def test_a_periodic_polynomial_of_the_wrong_span_is_refused_saying_its_span():
    with pytest.raises(ValueError, match=r"spans 1\.0 s, period 0\.5 s"):
        PolynomialSurface(_rise_fall(), period=0.5)
    with pytest.raises(ValueError, match=r"spans 1\.0 s, period 2\.0 s"):
        PolynomialSurface(_rise_fall(), period=2.0)


def test_a_non_periodic_polynomial_accepts_times_up_to_1e_12_past_its_domain():
    s = _linear_knots(0.0, 0.5, 1.0)
    # the slack is 1e-12 max(1, |x0|, |x1|) = 1e-12 here: exactly at it the end value is used
    assert s.position(1.0 + 1e-12)[0] == 1.0 and s.position(-1e-12)[0] == 0.0
    for t in (1.0 + 2e-12, -2e-12):
        with pytest.raises(ValueError, match="outside"):
            s.position(t)


def test_generic_roots_on_a_window_much_shorter_than_a_period_use_at_least_eight_intervals():
    # 400 per period would be 4 intervals on this 1/100-period window; eight put a sample at
    # 0.5, between the two roots, so both are bracketed
    s = _accel_only(lambda t: (np.asarray(t) - 0.4995) * (np.asarray(t) - 0.5005), period=100.0)
    assert s.accel_roots(1.0, 0.0, 0.0, 0.0, 1.0) == pytest.approx([0.4995, 0.5005], abs=1e-12)


def test_from_gamma_without_a_tangential_gamma_has_no_tangential_motion():
    wf = SineWaveform.from_gamma(30.0, 2.0)
    assert wf.amp_t == 0.0 and wf.max_abs_acceleration()[0] == 0.0
    assert wf.gamma() == pytest.approx(2.0, rel=1e-14)


def test_the_net_velocity_check_is_relative_to_the_waveform_scale():
    # an imbalance of 1e-4 of a_1 d_1 is refused whether the waveform is tiny or large
    for a, d in ((1e-3, 1e-3), (1.0, 1e-2), (1e3, 1.0)):
        with pytest.raises(ValueError, match="net velocity"):
            PiecewiseConstantAccel([d, d], [a, -a * (1 + 1e-4)])
        PiecewiseConstantAccel([d, d], [a, -a])


def test_scalar_and_vectorised_paths_agree_within_1e_12_periods_before_an_edge():
    # such a time counts as the edge itself: position and velocity are those at the edge
    wf = PiecewiseConstantAccel([0.5, 0.5], [1.0, -1.0], [2.0, -2.0])       # T = 1
    t = 0.5 - 1e-13
    for f in (wf.position, wf.velocity):
        at_edge = f(0.5)
        assert f(t) == at_edge
        assert [float(c[0]) for c in f(np.array([t]))] == list(at_edge)


def test_coulomb_pump_refuses_a_non_positive_acceleration_as_such():
    for accel in (0.0, -0.5):
        with pytest.raises(ValueError, match="peak_speed and accel must be positive"):
            CoulombPumpWaveform(F, 0.01, accel)


def test_coulomb_pump_allows_a_relative_1e_12_rounding_past_the_bound():
    accel, T = 40.0, 1.0 / F
    wf = CoulombPumpWaveform(F, accel * T / 4 * (1 + 1e-12), accel)
    assert wf.forward_fraction == 0.0


def test_sine_drive_is_the_stated_harmonic_cut_at_its_acceleration_extrema():
    amp, f, phase = 2e-4, 40.0, 0.3
    w, T = 2 * math.pi * f, 1 / f
    d = sine_drive(amp, f, phase)
    t = np.linspace(0.0, T, 13)
    np.testing.assert_allclose(d.position(t)[0], amp * np.sin(w * t + phase), rtol=0, atol=1e-12 * amp)
    np.testing.assert_allclose(d.velocity(t)[0], amp * w * np.cos(w * t + phase), rtol=0,
                               atol=1e-12 * amp * w)
    np.testing.assert_allclose(d.acceleration(t)[0], -amp * w * w * np.sin(w * t + phase), rtol=0,
                               atol=1e-12 * amp * w * w)
    # a_x extrema where w t + phase = pi/2 (minimum) and 3 pi/2 (maximum)
    t_min, t_max = (math.pi / 2 - phase) / w, (3 * math.pi / 2 - phase) / w
    p = d.pieces(0.0, T)
    assert p.edges == pytest.approx([0.0, t_min, t_max, T], abs=1e-12 * T)
    assert p.a_end[0] == pytest.approx(-amp * w * w, rel=1e-12)
    assert p.a_end[1] == pytest.approx(amp * w * w, rel=1e-12)


def test_a_jump_merged_with_a_sample_just_before_it_is_still_taken_one_sided():
    # on [T/2, 3T/2] the 129th of the T/256 samples falls an ulp before the jump at T and the
    # merge of near-duplicates keeps it instead of T: that edge is still the jump, so the piece
    # after it starts at the limit -K/2, not at the callable's value an ulp before (+K/2)
    K, T = 100.0, 1 / F
    p = _sawtooth(K, T).pieces(0.5 * T, 1.5 * T)
    j = int(np.argmin(np.abs(p.edges - T)))
    assert p.edges[j] < T and p.edges[j] == pytest.approx(T, abs=1e-15)   # the merged edge
    assert p.a_start[j] == pytest.approx(-K / 2, abs=1e-6 * K)
    assert p.a_end[j - 1] == pytest.approx(K / 2, abs=1e-6 * K)
    assert p.local(j, p.edges[j], 2) == pytest.approx(-K / 2, abs=1e-6 * K)


def test_pieces_of_a_periodic_polynomial_not_starting_at_zero_use_each_piece_own_formula():
    # a_x = +1 on [0.25, 0.75) + k, -1 on [0.75, 1.25) + k; v = -1/4 at 0.25 + k, +1/4 at 0.75 + k
    s = PolynomialSurface(_rise_fall(0.25), period=1.0)
    p = s.pieces(0.0, 2.0)
    assert p.edges == pytest.approx([0.0, 0.25, 0.75, 1.25, 1.75, 2.0], abs=1e-15)
    assert p.a_start.tolist() == [-1.0, 1.0, -1.0, 1.0, -1.0]
    assert p.a_end.tolist() == [-1.0, 1.0, -1.0, 1.0, -1.0]
    assert p.v == pytest.approx([0.0, -0.25, 0.25, -0.25, 0.25, 0.0], abs=1e-15)
    for i in range(p.n):
        t = 0.5 * (p.edges[i] + p.edges[i + 1])
        for nu, f in enumerate((s.position, s.velocity, s.acceleration)):
            assert p.local(i, t, nu) == pytest.approx(float(f(t)[0]), abs=1e-15)


def test_a_non_periodic_next_breakpoint_skips_only_1e_12_of_the_time_itself_past_one_second():
    s = _linear_knots(0.0, 50.0, 100.0)
    # at t ~ 50 s the margin is 1e-12 * 50 = 5e-11 s: a knot 1e-11 s after t is passed over
    assert s.next_breakpoint(50.0 - 1e-11) == 100.0
    assert s.next_breakpoint(50.0 - 1e-10) == 50.0


def test_generic_roots_use_400_intervals_of_a_non_periodic_window_whatever_its_length():
    # window [0, 2]: samples every 0.005 s, one at 0.015 between the roots 0.0145 and 0.0155
    s = _accel_only(lambda t: (np.asarray(t) - 0.0145) * (np.asarray(t) - 0.0155))
    assert s.accel_roots(1.0, 0.0, 0.0, 0.0, 2.0) == pytest.approx([0.0145, 0.0155], abs=1e-12)


def test_generic_roots_in_the_last_sampling_interval_and_at_t1_are_found():
    s = _accel_only(lambda t: np.asarray(t) - 0.999)
    # 0.999 lies in the last of the 400 intervals of [0, 1]
    assert s.accel_roots(1.0, 0.0, 0.0, 0.0, 1.0) == pytest.approx([0.999], abs=1e-12)
    # a level met exactly at t1 (a_x(1) as computed, so f(t1) == 0) is reported as t1
    at_t1 = float(s.acceleration(1.0)[0])
    assert s.accel_roots(1.0, 0.0, at_t1, 0.0, 1.0).tolist() == [1.0]


def test_generic_roots_are_refined_relative_to_the_period_of_a_fast_drive():
    # 100 kHz: -A w^2 sin(w t) = -A w^2 / 2 at T/12 and 5T/12, to far better than 1e-12 T
    f = 1e5
    w, T = 2 * math.pi * f, 1 / f
    s = CallableSurface(lambda t: A * np.sin(w * np.asarray(t)),
                        lambda t: A * w * np.cos(w * np.asarray(t)),
                        lambda t: -A * w * w * np.sin(w * np.asarray(t)), period=T)
    roots = s.accel_roots(1.0, 0.0, -0.5 * A * w * w, 0.0, T / 2)
    assert roots == pytest.approx([T / 12, 5 * T / 12], abs=1e-12 * T)


def test_two_level_drive_refuses_a_rise_that_is_not_positive_as_such():
    for a_up in (0.0, -0.5):
        with pytest.raises(ValueError, match="two-level drive needs"):
            two_level_drive(a_up, 1e-3, 0.5)


def test_generic_pieces_cut_the_along_track_motion():
    # the sine's pieces carry x (not z): the normal motion here is larger and phase-shifted
    wf = SineWaveform(F, A, 3 * A, 40.0)
    T = wf.period
    p = wf.pieces(0.1 * T, 1.1 * T)
    t = 0.5 * (p.edges[:-1] + p.edges[1:])
    for i in range(0, p.n, 17):
        assert p.local(i, t[i], 0) == pytest.approx(A * math.sin(W * t[i]), abs=1e-12 * A)
        assert p.local(i, t[i], 1) == pytest.approx(A * W * math.cos(W * t[i]), abs=1e-12 * A * W)
        assert p.local(i, t[i], 2) == pytest.approx(-A * W * W * math.sin(W * t[i]),
                                                    abs=1e-12 * A * W * W)


def test_max_speed_samples_one_period_finely():
    # v = -1/4 + (t - x0) on the rise: |v| peaks at 1/4 at x0 and x0 + 1/2 (cusps, |a| = 1).
    # Sampled over the period, the nearest sample is within half a step T/1024 of a peak.
    x0 = 3.0 / 1024
    s = PolynomialSurface(_rise_fall(x0), period=1.0)
    assert 0.25 - 1.0 / 2048 <= s.max_speed() <= 0.25


def test_from_gamma_has_no_phase_lead_by_default():
    wf = SineWaveform.from_gamma(30.0, 2.0, 0.5)
    assert wf.phase == 0.0
    # both axes peak together at T/4
    T = wf.period
    x, z = wf.position(T / 4)
    assert x == pytest.approx(wf.amp_t, rel=1e-12) and z == pytest.approx(wf.amp_n, rel=1e-12)


def test_sine_level_crossings_from_one_crossing_to_a_later_one():
    # Windows between crossings the method returned: every later one up to t1 is found
    # again (t1 included, whatever the rounding of k), the first (t0) is not.
    wf = SineWaveform(F, A, 0.0)
    T = 1 / F
    for level in (0.0, 0.5 * A * W * W, -0.5 * A * W * W):
        r = wf.accel_roots(1.0, 0.0, level, 0.0, 30 * T)
        assert r.size == 60
        for j in range(0, 30):
            for m in (1, 2, 4, 6):
                got = wf.accel_roots(1.0, 0.0, level, r[j], r[j + 2 * m])
                assert got.tolist() == r[j + 1:j + 2 * m + 1].tolist()


def test_piecewise_constant_accel_refuses_a_negative_duration():
    # dropping the negative piece would leave a balanced waveform: it must be refused anyway
    with pytest.raises(ValueError, match="non-negative"):
        PiecewiseConstantAccel([0.01, -0.005, 0.01], [1.0, 5.0, -1.0])


def test_piecewise_constant_accel_has_no_level_crossing_inside_a_piece():
    wf = SquareWaveAccel(F, 5.0, 3.0)
    T = wf.period
    for level in (-6.0, -4.0, 0.0, 4.0, 6.0):
        assert wf.accel_roots(1.0, 0.0, level, 0.1 * T, 0.4 * T).size == 0
        assert wf.accel_roots(0.0, 1.0, level, 0.6 * T, 0.9 * T).size == 0


def test_max_abs_acceleration_of_piecewise_constant_motions_is_per_axis():
    assert SquareWaveAccel(F, 5.0, 3.0, 30.0).max_abs_acceleration() == (5.0, 3.0)
    assert StickSlipWaveform(F, 2.0, 6.0).max_abs_acceleration() == (6.0, 0.0)


def test_sampled_waveform_reports_no_crossing_of_a_level_it_never_meets():
    # all samples zero: a_x = 0 throughout; the level -1 gives cx a_x - level = 1 at both ends
    wf = SampledWaveform(1.0, [0.0, 0.0, 0.0, 0.0])
    assert wf.accel_roots(1.0, 0.0, -1.0, 0.0, 0.25).size == 0
    assert wf.accel_roots(1.0, 0.0, 1.0, 0.0, 0.25).size == 0
    # met at t1 (and all along): t1 is reported, as for a crossing exactly at t1
    assert wf.accel_roots(1.0, 0.0, 0.0, 0.0, 0.25).tolist() == [0.25]


def test_a_polynomial_is_cut_at_the_extrema_of_its_acceleration_not_its_zeros():
    # x = t^4/12 - t^3/6 + 0.12 t^2: a = t^2 - t + 0.24 = (t - 0.4)(t - 0.6), minimum -0.01 at 0.5
    c = np.array([[1 / 12], [-1 / 6], [0.12], [0.0], [0.0]])
    p = PolynomialSurface(PPoly(c, [0.0, 1.0], extrapolate=False)).pieces(0.0, 1.0)
    assert p.edges == pytest.approx([0.0, 0.5, 1.0], abs=1e-15)
    assert p.a_start == pytest.approx([0.24, -0.01], abs=1e-15)
    assert p.a_end == pytest.approx([-0.01, 0.24], abs=1e-15)
