"""Vertical stick/slip transport model (vibrofeed/models/vertical.py) against closed forms."""

import dataclasses
import math

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.models.roots import first_descent, stick_exit
from vibrofeed.models.surface import (
    CallableSurface,
    SineWaveform,
    SquareWaveAccel,
    StickSlipWaveform,
    sine_drive,
    two_level_drive,
)
from vibrofeed.models.vertical import (
    Contact,
    check_feasible,
    periodic_transport,
    simulate,
    two_level_transport,
)

M = 0.009  # kg, the experiment's part


def contact(fn_mg, mu_s=0.72, mu_k=0.6, g=G):
    return Contact(mass=M, normal_force=fn_mg * M * G, mu_s=mu_s, mu_k=mu_k, g=g)


def callables_of_x(motion, **kw):
    """The same along-track motion given as plain callables (the generic, sampled cut)."""
    return CallableSurface(lambda t: motion.position(t)[0], lambda t: motion.velocity(t)[0],
                           lambda t: motion.acceleration(t)[0], **kw)


def constant_velocity(v):
    """z_s = v t: acceleration identically zero, a single monotone piece."""
    return CallableSurface(lambda t: v * np.asarray(t), lambda t: v + 0 * np.asarray(t),
                           lambda t: 0 * np.asarray(t), turning_points=[])


def test_stick_band_and_slip_accelerations():
    c = contact(10.0, mu_s=0.7, mu_k=0.5)
    assert c.stick_upper == pytest.approx(0.7 * 10 * G - G, rel=1e-14)
    assert c.stick_lower == pytest.approx(-0.7 * 10 * G - G, rel=1e-14)
    assert c.slip_acceleration(+1) == pytest.approx(0.5 * 10 * G - G, rel=1e-14)
    assert c.slip_acceleration(-1) == pytest.approx(-0.5 * 10 * G - G, rel=1e-14)


@pytest.mark.parametrize("kwargs", [dict(mu_k=0.8), dict(mass=0.0), dict(normal_force=-1.0),
                                    dict(mu_s=math.nan)])
def test_contact_rejects_unphysical_values(kwargs):
    base = dict(mass=M, normal_force=1.0, mu_s=0.72, mu_k=0.6)
    base.update(kwargs)
    with pytest.raises(ValueError):
        Contact(**base)


def test_feasible_case_returns_positive_margins():
    fn = 5 * M * G
    margins = check_feasible(M, fn, 0.72, a_max=10 * G)
    assert margins["normal_force_margin"] == pytest.approx(fn - M * G / 0.72, rel=1e-12)
    assert margins["acceleration_margin"] == pytest.approx(10 * G - (0.72 * 5 * G + G),
                                                           rel=1e-12)


def test_feasibility_flags_small_normal_force_and_by_how_much():
    fn = 1.0 * M * G  # below m g / mu_s = 1.389 m g
    with pytest.raises(ValueError) as err:
        check_feasible(M, fn, 0.72, a_max=100 * G)
    msg = str(err.value)
    assert "normal force too small" in msg and "acceleration" not in msg
    short = M * G / 0.72 - fn
    assert f"{short:.3g} N" in msg


def test_feasibility_flags_small_peak_acceleration():
    fn = 5 * M * G  # needs a_max > 0.72*5 g + g = 4.6 g
    with pytest.raises(ValueError) as err:
        check_feasible(M, fn, 0.72, a_max=4.0 * G)
    msg = str(err.value)
    assert "peak surface acceleration too small" in msg and "normal force" not in msg
    assert f"{0.6 * G:.3g} m/s^2" in msg  # short by 0.6 g


def test_feasibility_reports_both_bounds_when_both_fail():
    with pytest.raises(ValueError) as err:
        check_feasible(M, 0.5 * M * G, 0.72, a_max=1.0 * G)
    assert "normal force too small" in str(err.value)
    assert "peak surface acceleration too small" in str(err.value)


def test_pure_sticking_inside_the_band_gives_no_net_motion():
    c = contact(5.0)  # band [-4.6 g, +2.6 g]
    drive = sine_drive(amplitude=0.2e-3, frequency=40.0)  # peak 1.29 g, inside
    traj = simulate(drive, c, t_end=0.2)
    assert len(traj.phases) == 1 and traj.phases[0].stuck
    assert traj.stuck_fraction == 1.0
    gap = traj.z - drive.position(traj.t)[0]
    assert np.max(np.abs(gap - gap[0])) < 1e-15
    assert abs(traj.net_speed(period=1 / 40.0)) < 1e-12


def test_part_slides_down_when_normal_force_is_below_mg_over_mu_s():
    c = contact(1.2, mu_s=0.72, mu_k=0.6)  # 1.2 < 1/0.72
    with pytest.raises(ValueError, match="normal force too small"):
        check_feasible(M, c.normal_force, c.mu_s, a_max=50 * G)
    # Surface at rest: the part falls at mu_k F_n/m - g from the start.
    traj = simulate(constant_velocity(0.0), c, t_end=0.05, t_eval=[0.0, 0.05])
    a = 0.6 * 1.2 * G - G
    assert traj.z[-1] == pytest.approx(0.5 * a * 0.05 ** 2, rel=1e-12)
    assert traj.stuck_fraction == 0.0
    # Under a transporting two-level drive it still loses height.
    drive = two_level_drive(a_up=0.1 * G, t_up=0.02, a_down=20 * G)
    assert periodic_transport(drive, c, n_periods=4).net_speed < 0


def test_initially_slipping_part_follows_exact_parabola_until_caught():
    c = contact(5.0, mu_k=0.5)  # slip up at 1.5 g
    v = 0.1
    traj = simulate(constant_velocity(v), c, t_end=0.02, z0=0.0, v0=0.0)
    a = 0.5 * 5 * G - G
    t_catch = v / a
    assert traj.phases[0].t1 == pytest.approx(t_catch, abs=1e-13)
    assert not traj.phases[0].stuck and traj.phases[1].stuck
    z, vv, stuck = traj.sample([t_catch / 2, 0.02])
    assert z[0] == pytest.approx(0.5 * a * (t_catch / 2) ** 2, rel=1e-12)
    # Once caught it rides along: z = z(t_catch) + v (t - t_catch).
    assert z[1] == pytest.approx(0.5 * a * t_catch ** 2 + v * (0.02 - t_catch), rel=1e-12)
    assert vv[1] == pytest.approx(v, rel=1e-14) and stuck[1]


# (a_up, t_up, a_down, F_n [m g], mu_k): from gentle to violent drops,
# a catch late in the rise, and mu_k = mu_s.
TWO_LEVEL_CASES = [
    (0.5 * G, 0.02, 15 * G, 5.0, 0.6),
    (2.0 * G, 0.01, 40 * G, 5.0, 0.6),
    (0.2 * G, 0.03, 6.0 * G, 5.0, 0.1),
    (5.0 * G, 0.004, 30 * G, 10.0, 0.72),
]


@pytest.mark.parametrize("a_up,t_up,a_down,fn_mg,mu_k", TWO_LEVEL_CASES)
def test_two_level_model_matches_closed_form(a_up, t_up, a_down, fn_mg, mu_k):
    c = contact(fn_mg, mu_k=mu_k)
    exact = two_level_transport(a_up, t_up, a_down, c)
    assert exact.net_speed > 0 and 0 < exact.catch_delay <= t_up
    got = periodic_transport(two_level_drive(a_up, t_up, a_down), c, n_periods=5)
    assert got.net_speed == pytest.approx(exact.net_speed, rel=1e-6)
    assert got.stuck_fraction == pytest.approx(exact.stuck_fraction, rel=1e-6)
    assert got.displacement_per_period == pytest.approx(exact.displacement_per_period, rel=1e-6)


def test_two_level_catch_time_is_exact():
    a_up, t_up, a_down = 0.5 * G, 0.02, 15 * G
    c = contact(5.0)
    exact = two_level_transport(a_up, t_up, a_down, c)
    traj = simulate(two_level_drive(a_up, t_up, a_down), c, t_end=2 * exact.period)
    # stuck (rise) | slip (drop + catch) | stuck | ...
    assert [p.stuck for p in traj.phases[:3]] == [True, False, True]
    assert traj.phases[0].t1 == pytest.approx(t_up, abs=1e-13)
    assert traj.phases[1].t1 == pytest.approx(exact.period + exact.catch_delay, abs=1e-12)


def test_two_level_generic_callable_surface_matches_closed_form():
    """Same drive given as plain callables with breakpoints, sampled cut (no turning points)."""
    a_up, t_up, a_down = 1.0 * G, 0.015, 25 * G
    c = contact(6.0)
    exact = two_level_transport(a_up, t_up, a_down, c)
    poly = two_level_drive(a_up, t_up, a_down)
    generic = callables_of_x(poly, breakpoints=[0.0, t_up], period=exact.period)
    got = periodic_transport(generic, c, n_periods=5)
    assert got.net_speed == pytest.approx(exact.net_speed, rel=1e-6)


def test_two_level_without_slip_has_zero_transport():
    c = contact(5.0)  # lower band edge -4.6 g
    a_up, t_up, a_down = 0.5 * G, 0.02, 4.0 * G
    assert two_level_transport(a_up, t_up, a_down, c).net_speed == 0.0
    got = periodic_transport(two_level_drive(a_up, t_up, a_down), c, n_periods=3)
    assert got.net_speed == pytest.approx(0.0, abs=1e-15)
    assert got.stuck_fraction == pytest.approx(1.0, abs=1e-12)


def test_two_level_closed_form_refuses_slip_during_rise():
    with pytest.raises(ValueError, match="sticking during the rise"):
        two_level_transport(3.0 * G, 0.01, 30 * G, contact(5.0))  # band top 2.6 g


def test_without_gravity_a_mirrored_drive_mirrors_the_part():
    """g = 0: z -> -z is a symmetry of the model, exactly."""
    c = Contact(mass=M, normal_force=4 * M * G, mu_s=0.72, mu_k=0.55, g=0.0)
    up = sine_drive(amplitude=0.5e-3, frequency=60.0, phase=0.3)
    down = sine_drive(amplitude=0.5e-3, frequency=60.0, phase=0.3 + math.pi)  # = -up
    t = np.linspace(0, 0.5, 301)
    a = simulate(up, c, t_end=0.5, t_eval=t)
    b = simulate(down, c, t_end=0.5, t_eval=t)
    assert len(a.phases) > 5  # really stick-slip
    assert np.allclose(a.z, -b.z, rtol=0, atol=1e-15)
    # and once the start-up transient has died out (~20 periods), a
    # symmetric drive cannot transport without gravity
    assert abs(a.net_speed(1 / 60.0, skip_periods=20)) < 1e-9


def test_periodic_drive_is_shift_invariant():
    c = contact(5.0)
    drive = sine_drive(amplitude=1.0e-3, frequency=50.0)
    p = 1 / 50.0
    a = simulate(drive, c, t_end=4 * p, t_eval=np.linspace(0, 4 * p, 50))
    b = simulate(drive, c, t_start=p, t_end=5 * p, t_eval=np.linspace(p, 5 * p, 50))
    assert np.allclose(a.z, b.z, rtol=0, atol=1e-13)


def test_net_speed_needs_a_whole_period_after_the_transient():
    traj = simulate(sine_drive(1e-4, 50.0), contact(5.0), t_end=0.03)
    with pytest.raises(ValueError):
        traj.net_speed(period=0.02, skip_periods=1)


def test_any_object_with_position_velocity_acceleration_is_a_surface():
    """A plain object (no ``pieces``) with breakpoints is wrapped and gives the closed form."""
    a_up, t_up, a_down = 0.5 * G, 0.02, 15 * G
    poly = two_level_drive(a_up, t_up, a_down)
    exact = two_level_transport(a_up, t_up, a_down, contact(5.0))

    class Motion:
        breakpoints = (0.0, t_up)
        period = exact.period

        @staticmethod
        def position(t):
            return poly.position(t)[0]

        @staticmethod
        def velocity(t):
            return poly.velocity(t)[0]

        @staticmethod
        def acceleration(t):
            return poly.acceleration(t)[0]

    got = periodic_transport(Motion(), contact(5.0), n_periods=4)
    assert got.net_speed == pytest.approx(exact.net_speed, rel=1e-6)
    with pytest.raises(TypeError, match="acceleration"):
        simulate(object(), contact(5.0), t_end=0.1)


def test_deck_waveforms_drive_the_vertical_model_along_the_track():
    """A two-axis motion of the part-on-surface model drives the vertical model by its x axis."""
    c = contact(5.0)
    square = SquareWaveAccel(40.0, 60.0 * G, 3.0 * G, 30.0)
    only_x = callables_of_x(square, breakpoints=square.starts, period=square.period)
    a = periodic_transport(square, c, n_periods=6)
    b = periodic_transport(only_x, c, n_periods=6)
    assert a.net_speed == b.net_speed and a.stuck_fraction == b.stuck_fraction
    assert a.net_speed != 0.0
    # The pieces of a piecewise-constant motion start at its breakpoints.
    ss = StickSlipWaveform(25.0, 3.0, 9.0)
    edges = ss.pieces(0.0, 3 * ss.period).edges
    for tb in ss.breakpoints(0.0, 3 * ss.period):
        assert np.min(np.abs(edges - tb)) < 1e-15


def test_stick_exit_names_the_side_the_acceleration_leaves_the_band_by():
    # x = a sin(w t): x'' = -a w^2 sin(w t) falls through -A/2 at w t = pi/6 (the surface drops away:
    # side -1) and rises through +A/2 at w t = pi + pi/6 (it outruns the part: side +1), inside pieces
    f, a = 50.0, 1e-4
    w = 2 * math.pi * f
    A = a * w * w
    wf = SineWaveform(f, a, 0.0)
    P = wf.pieces(0.0, 2 / f)
    for t, want_t, side in ((0.0, math.asin(0.5) / w, -1), (0.55 / f, (math.pi + math.asin(0.5)) / w, 1)):
        i = int(np.searchsorted(P.edges, t, side="right")) - 1
        t_x, j, s = stick_exit(P, i, t, -0.5 * A, 0.5 * A)
        assert s == side
        assert t_x == pytest.approx(want_t, rel=1e-12, abs=0)
        assert P.edges[j] <= t_x <= P.edges[j + 1]


def test_first_descent_of_a_function_already_at_or_below_zero_is_its_start():
    # a piece that starts at <= 0 and falls is an event at its start (no bracket to search)
    assert first_descent(lambda t: -0.5 - t, 0.2, 1.0, [], 1e-12) == 0.2
    assert first_descent(lambda t: -t, 0.0, 1.0, [0.5], 1e-12) == 0.0
    assert first_descent(lambda t: 0.5 - t, 0.0, 1.0, [], 1e-12) == pytest.approx(0.5, abs=1e-12)
    assert first_descent(lambda t: t, 0.0, 1.0, [], 1e-12) is None


def test_periodic_transport_is_an_immutable_value():
    got = periodic_transport(two_level_drive(0.5 * G, 0.02, 15 * G), contact(5.0), n_periods=2)
    with pytest.raises(dataclasses.FrozenInstanceError):
        got.net_speed = 0.0


# Exact binary numbers for the edge cases below: m = 1 kg, F_n = 16 N, mu_s = 0.75, mu_k = 0.5,
# g = 8 m/s^2, so the stick band is [-20, 4] m/s^2 and the part slips at 0 (up) or -16 (down).
EXACT = dict(mass=1.0, normal_force=16.0, mu_s=0.75, mu_k=0.5, g=8.0)


def jump_surface():
    """a_s = 8 (above the band) until 0.25 s, then 2 (inside it); v_s(0) = 0, x_s(0) = 0."""
    def x(t):
        t = np.asarray(t, dtype=float)
        return np.where(t < 0.25, 4 * t * t, 0.25 + 2 * (t - 0.25) + (t - 0.25) ** 2)

    def v(t):
        t = np.asarray(t, dtype=float)
        return np.where(t < 0.25, 8 * t, 2 + 2 * (t - 0.25))

    def a(t):
        return np.where(np.asarray(t, dtype=float) < 0.25, 8.0, 2.0)

    return CallableSurface(x, v, a, breakpoints=[0.25], turning_points=[])


def test_a_slip_ending_exactly_at_a_jump_decides_with_the_acceleration_after_it():
    # The part starts 6 m/s faster than the surface: it slips down (a_p = -16) while
    # w = v_s - v_p = -6 + 24 t returns to 0 exactly at the jump, t = 0.25 s, z_p = 1 m. The
    # surface then accelerates at 2 m/s^2, inside the band: the part sticks and rides along
    # (before the jump, at 8 m/s^2, it could not have).
    c = Contact(**EXACT)
    traj = simulate(jump_surface(), c, t_end=0.5, z0=0.0, v0=6.0, t_eval=[0.25, 0.5])
    assert [(p.stuck, p.t0, p.t1) for p in traj.phases] == [(False, 0.0, 0.25), (True, 0.25, 0.5)]
    assert traj.z[0] == 6 * 0.25 - 8 * 0.25 ** 2 == 1.0
    # stuck: z_p - z_s stays 1 - 0.25; z_s(0.5) = 0.25 + 2 * 0.25 + 0.25^2
    assert traj.z[1] == pytest.approx(0.75 + 0.8125, abs=1e-15)
    assert traj.v[1] == pytest.approx(2.5, abs=1e-15) and traj.stuck[1]


def test_a_slip_ending_exactly_at_the_end_of_the_run_is_one_phase():
    # same start, run stopped at the instant the slip ends (also the last piece's end)
    traj = simulate(jump_surface(), Contact(**EXACT), t_end=0.25, z0=0.0, v0=6.0, t_eval=[0.25])
    assert [(p.stuck, p.t0, p.t1) for p in traj.phases] == [(False, 0.0, 0.25)]
    assert traj.z[0] == 1.0 and traj.v[0] == 2.0


def test_a_part_starting_inside_the_band_rides_until_the_acceleration_reaches_its_edge():
    # a_s = 3.5 + 2 t: 0.5 m/s^2 inside the upper edge 4 at the start, reaching it at 0.25 s;
    # then the part slips up at a_p = 0, keeping v_s(0.25) = 3.5 * 0.25 + 0.25^2 = 0.9375
    c = Contact(**EXACT)
    rising = CallableSurface(lambda t: 1.75 * np.asarray(t) ** 2 + np.asarray(t) ** 3 / 3,
                             lambda t: 3.5 * np.asarray(t) + np.asarray(t) ** 2,
                             lambda t: 3.5 + 2 * np.asarray(t), turning_points=[])
    traj = simulate(rising, c, t_end=0.5, t_eval=[0.5])
    assert [p.stuck for p in traj.phases] == [True, False]
    assert traj.phases[0].t1 == pytest.approx(0.25, abs=1e-13)
    z_catch = 1.75 * 0.25 ** 2 + 0.25 ** 3 / 3
    assert traj.z[0] == pytest.approx(z_catch + 0.9375 * 0.25, abs=1e-13)
    assert traj.v[0] == pytest.approx(0.9375, abs=1e-13)


@pytest.mark.parametrize("ratio", [1.3, 1.68])
def test_equal_friction_coefficients_without_gravity_leave_the_band_cleanly(ratio):
    """mu_k = mu_s: at a stick exit the part's slip acceleration equals a_s, so the relative
    velocity starts flat and the event time's rounding decides its first sign; the trend of
    a_s must decide instead (no chattering), for every exit of a long run."""
    f, amp = 100.0, 1e-3
    A = amp * (2 * math.pi * f) ** 2 / ratio      # mu_s F_n / m, the band half-width (g = 0)
    c = Contact(mass=M, normal_force=A * M / 0.6, mu_s=0.6, mu_k=0.6, g=0.0)
    up = sine_drive(amp, f, 0.3)
    t = np.linspace(0, 20 / f, 201)
    a = simulate(up, c, t_end=20 / f, t_eval=t)
    b = simulate(sine_drive(amp, f, 0.3 + math.pi), c, t_end=20 / f, t_eval=t)
    # each exit is one event: the slip it starts lasts (no zero-length phase decided again at
    # once), and stick and slip phases alternate. A slip from a_s = A (phase angle p0 after
    # a_s's zero, sin p0 = 1 / ratio) gains 2 sqrt(ratio^2 - 1) - pi + 2 p0 (in A / w units) of
    # relative velocity while a_s > A and loses 2 p0 before a_s reaches -A: for ratio below
    # sqrt(1 + pi^2 / 4) = 1.86 it ends with a_s inside the band, i.e. stuck (mirrored: down).
    assert all(p.t1 > p.t0 for p in a.phases)
    assert all(p.stuck != q.stuck for p, q in zip(a.phases, a.phases[1:]))
    exits = [p.t1 for p in a.phases[:-1] if p.stuck]
    assert len(exits) >= 38                          # two stick phases a period
    # every stick phase ends where |a_s| reaches the band edge A
    assert np.allclose(np.abs(up.acceleration(np.array(exits))[0]), A, rtol=0, atol=1e-9 * A)
    # every slip phase ends where the part's velocity meets the surface's
    slips = [p for p in a.phases[:-1] if not p.stuck]
    v_end = np.array([p.v0 + p.accel * (p.t1 - p.t0) for p in slips])
    assert np.allclose(v_end, up.velocity(np.array([p.t1 for p in slips]))[0], rtol=0,
                       atol=1e-9 * amp * 2 * math.pi * f)
    assert np.allclose(a.z, -b.z, rtol=0, atol=1e-15)       # mirror symmetry (g = 0)
    assert abs(a.net_speed(1 / f, skip_periods=10)) < 1e-12


@pytest.mark.parametrize("mu_k", [0.6, 0.5])
@pytest.mark.parametrize("twelfths", [5, 11])
def test_a_start_on_a_band_edge_with_the_acceleration_turning_inward_sticks(twelfths, mu_k):
    """a_s = -A_pk sin(w t + phase) starts on a band edge (+-A_pk / 2 with A = A_pk / 2, g = 0)
    and moves into the band: the part sticks from t = 0 until a_s reaches the other edge, at
    w t = pi / 3. The computed a_s(0) may lie a rounding error outside the band; that must
    neither make the part slip nor chatter (mu_k = mu_s)."""
    f, amp = 60.0, 1e-3
    A = 0.5 * amp * (2 * math.pi * f) ** 2
    c = Contact(mass=M, normal_force=A * M / 0.6, mu_s=0.6, mu_k=mu_k, g=0.0)
    drive = sine_drive(amp, f, twelfths * (2 * math.pi / 12))   # 5 pi / 6 or 11 pi / 6
    traj = simulate(drive, c, t_end=0.5 / f, t_eval=[0.0])
    first = traj.phases[0]
    assert first.stuck and first.t0 == 0.0
    assert first.t1 == pytest.approx(1 / (6 * f), abs=1e-13)   # s
    assert not traj.phases[1].stuck


def test_a_part_at_rest_on_a_surface_accelerating_beyond_the_band_slips_from_the_start():
    # jump_surface accelerates at 8 m/s^2 > 4 (the band's top) from v_s = 0: the part cannot
    # follow and slips up at a_p = 0, i.e. stays at rest, while the surface runs away
    # (a_s = 2 > a_p after the jump too: w = v_s - v_p never returns to 0).
    traj = simulate(jump_surface(), Contact(**EXACT), t_end=0.5, t_eval=[0.25, 0.5])
    assert [(p.stuck, p.t0, p.t1) for p in traj.phases] == [(False, 0.0, 0.5)]
    assert list(traj.z) == [0.0, 0.0] and list(traj.v) == [0.0, 0.0]


def test_a_slip_caught_by_a_surface_decelerating_gently_ends_at_the_closed_form_time():
    # a_s = -0.5 m/s^2, within 1 m/s^2 of the part's a_p = 0 (slipping up, EXACT): from
    # v_s = 1 and v_p = 0.5, w = 0.5 - 0.5 t reaches 0 at t = 1 s, z_p = 0.5 m; a_s is inside
    # the band, so the part then rides along: z_p(2) = z_p(1) + z_s(2) - z_s(1) = 0.75 m.
    gentle = CallableSurface(lambda t: np.asarray(t) - 0.25 * np.asarray(t) ** 2,
                             lambda t: 1.0 - 0.5 * np.asarray(t),
                             lambda t: -0.5 + 0 * np.asarray(t), turning_points=[])
    traj = simulate(gentle, Contact(**EXACT), t_end=2.0, z0=0.0, v0=0.5, t_eval=[1.0, 2.0])
    assert [p.stuck for p in traj.phases] == [False, True]
    assert traj.phases[0].t1 == pytest.approx(1.0, abs=1e-13)
    assert traj.z == pytest.approx([0.5, 0.75], abs=1e-13)
    assert traj.v == pytest.approx([0.5, 0.0], abs=1e-13)


@pytest.mark.filterwarnings("error")
def test_a_slip_caught_on_a_piece_whose_acceleration_ends_at_the_part_s():
    # a_s = -2 |t - 1| (v_s = -(t-1)|t-1|, x_s = 1/3 - (t-1)^2 |t-1| / 3) turns at t = 1, where
    # it equals the part's a_p = 0 (slipping up, EXACT) exactly. From v_p = 1/4 the relative
    # velocity w = (1 - t)^2 - 1/4 returns to 0 at t = 1/2, z_p = 1/8; a_s = -1 is inside the
    # band: the part sticks to the end, where x_s(3/2) = x_s(1/2), so z_p(3/2) = 1/8 again.
    # The boundary case (w' = 0 at the piece end) is computed cleanly, without numeric warnings.
    def s(t):
        return np.asarray(t, dtype=float) - 1.0

    drive = CallableSurface(lambda t: 1 / 3 - s(t) ** 2 * np.abs(s(t)) / 3,
                            lambda t: -s(t) * np.abs(s(t)), lambda t: -2.0 * np.abs(s(t)),
                            turning_points=[1.0])
    traj = simulate(drive, Contact(**EXACT), t_end=1.5, z0=0.0, v0=0.25, t_eval=[0.5, 1.5])
    assert [p.stuck for p in traj.phases] == [False, True]
    assert traj.phases[0].t1 == pytest.approx(0.5, abs=1e-13)
    assert traj.z == pytest.approx([0.125, 0.125], abs=1e-13)
    assert traj.v == pytest.approx([0.25, -0.25], abs=1e-13)


def test_a_surface_acceleration_touching_the_band_top_keeps_the_part_stuck():
    # a_s = 4 - 4 |t - 1| (v_s = 2 + 4 s - 2 s |s|, x_s = 2/3 + 2 s + 2 s^2 - 2/3 s^2 |s|,
    # s = t - 1) reaches the band's top 4 (EXACT) only at its turning point t = 1: the part
    # can follow it all along and rides from rest at x_s(0) = 0 to x_s(2) = 4 m, v_s(2) = 4 m/s
    # (v_s(1) = 2 m/s, x_s(1) = 2/3 m).
    def s(t):
        return np.asarray(t, dtype=float) - 1.0

    touch = CallableSurface(lambda t: 2 / 3 + 2 * s(t) + 2 * s(t) ** 2 - 2 / 3 * s(t) ** 2 * np.abs(s(t)),
                            lambda t: 2 + 4 * s(t) - 2 * s(t) * np.abs(s(t)),
                            lambda t: 4 - 4 * np.abs(s(t)), turning_points=[1.0])
    traj = simulate(touch, Contact(**EXACT), t_end=2.0, t_eval=[1.0, 2.0])
    assert [(p.stuck, p.t0, p.t1) for p in traj.phases] == [(True, 0.0, 2.0)]
    assert traj.z == pytest.approx([2 / 3, 4.0], abs=1e-14)    # m
    assert traj.v == pytest.approx([2.0, 4.0], abs=1e-14)      # m/s
