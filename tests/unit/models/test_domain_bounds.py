"""The in-plane and vertical transport models at the edges of their domains: the bounds
their docstrings state (at and just past them), closed forms with friction coefficients that
do not sum to 1, a part launched faster than its wall, slow drives (periods above 1 s)."""

import math

import numpy as np
import pytest

from vibrofeed.models.constants import G
from vibrofeed.models.inplane import (
    optimal_stick_slip_speed,
    optimal_stick_slip_waveform,
    sliding_limit_speed,
)
from vibrofeed.models.surface import CallableSurface, PiecewiseConstantAccel, sine_drive
from vibrofeed.models.vertical import Contact, periodic_transport, simulate

M = 0.009


def test_optimal_stick_slip_needs_more_than_static_friction():
    mu_s, mu_k, f = 0.5, 0.3, 50.0
    with pytest.raises(ValueError, match="a_max > mu_s g"):
        optimal_stick_slip_waveform(mu_s * G, mu_s, mu_k, f)       # at the bound: no slip
    assert optimal_stick_slip_speed(mu_s * G, mu_s, mu_k, f) == 0.0
    optimal_stick_slip_waveform(mu_s * G * 1.001, mu_s, mu_k, f)    # just past it


def test_optimal_stick_slip_speed_by_hand_with_unequal_friction():
    # g/f mu_s^2 (alpha^2 - mu_k^2) / (4 alpha (mu_s + mu_k)^2) at alpha = 1, mu_s = 0.5,
    # mu_k = 0.3: g/f * 0.25 * 0.91 / (4 * 0.64) = g/f * 0.088867...
    assert optimal_stick_slip_speed(G, 0.5, 0.3, 50.0) == pytest.approx(G / 50.0 * 0.25 * 0.91 / 2.56,
                                                                         rel=1e-12)


def test_sliding_limit_needs_kinetic_friction_on_an_incline():
    wf = optimal_stick_slip_waveform(2 * G, 0.5, 0.3, 50.0)
    for mu_k in (None, 0.0, -0.1):
        with pytest.raises(ValueError, match="mu_k > 0 needed"):
            sliding_limit_speed(wf, mu_k=mu_k, incline=5.0, n=1000)
    assert math.isfinite(sliding_limit_speed(wf, mu_k=0.3, incline=5.0, n=1000))


def test_contact_refuses_negative_gravity():
    for g in (-0.5, -1e-9):
        with pytest.raises(ValueError, match="must be >= 0"):
            Contact(mass=M, normal_force=1.0, mu_s=0.7, mu_k=0.6, g=g)
    assert Contact(mass=M, normal_force=1.0, mu_s=0.7, mu_k=0.6, g=0.0).g == 0.0


def still_wall():
    return CallableSurface(lambda t: 0 * np.asarray(t), lambda t: 0 * np.asarray(t),
                           lambda t: 0 * np.asarray(t), turning_points=[])


def test_a_part_launched_up_a_still_wall_brakes_by_kinetic_friction_and_gravity():
    # v0 = 0.1 m/s up; friction mu_k N/m and gravity both pull down until it stops at
    # t* = v0 / a, z* = v0^2 / (2 a); then mu_s N > m g holds it
    c = Contact(mass=M, normal_force=2 * M * G, mu_s=0.72, mu_k=0.6)
    a = 0.6 * 2 * G + G
    v0 = 0.1
    traj = simulate(still_wall(), c, t_end=0.05, z0=0.0, v0=v0, t_eval=[0.0, v0 / a / 2, 0.05])
    assert traj.z[1] == pytest.approx(v0 * v0 / a / 2 - a / 2 * (v0 / a / 2) ** 2, rel=1e-9)
    assert traj.z[2] == pytest.approx(v0 * v0 / (2 * a), rel=1e-9)
    assert traj.stuck[2] and traj.phases[0].t1 == pytest.approx(v0 / a, rel=1e-9)
    with pytest.raises(ValueError, match="outside the simulated interval"):
        traj.sample([0.06])                      # after the run only
    with pytest.raises(ValueError, match="outside the simulated interval"):
        traj.sample([-0.01])                     # before it only


def test_a_slow_drive_that_never_breaks_static_friction_is_stuck_throughout():
    # a 0.5 Hz sine whose acceleration (1 mm * w^2 ~ 0.01 m/s^2) cannot break mu_s N = 1.44 m g:
    # the part is stuck for all the averaged periods, at speed 0; two periods with one
    # skipped leave one to average
    c = Contact(mass=M, normal_force=2 * M * G, mu_s=0.72, mu_k=0.6)
    for n in (2, 4):
        got = periodic_transport(sine_drive(1e-3, 0.5), c, n_periods=n, skip_periods=1)
        assert got.stuck_fraction == pytest.approx(1.0, abs=1e-12)
        assert got.net_speed == pytest.approx(0.0, abs=1e-12)


def test_the_optimal_waveform_reaches_the_bound_with_friction_not_summing_to_one():
    from vibrofeed.models.part_on_surface import PartParams, mean_velocity

    a_max, mu_s, mu_k, f = 2 * G, 0.5, 0.3, 20.0
    wf = optimal_stick_slip_waveform(a_max, mu_s, mu_k, f)
    v = mean_velocity(wf, PartParams(mu_s, mu_k), n_transient=8, n_block=4, max_blocks=4,
                      rtol=1e-9).velocity
    assert v == pytest.approx(optimal_stick_slip_speed(a_max, mu_s, mu_k, f), rel=1e-9)


def test_a_two_level_drive_that_never_breaks_the_part_loose_moves_nothing():
    from vibrofeed.models.vertical import two_level_transport

    c = Contact(mass=M, normal_force=2 * M * G, mu_s=0.72, mu_k=0.6)
    # stick_upper = (1.44 - 1) g, stick_lower = -(1.44 + 1) g: a rise of 0.4 g and a drop
    # of 2 g the part follows, stuck throughout
    got = two_level_transport(0.4 * G, 5e-3, 2.0 * G, c)
    assert (got.displacement_per_period, got.net_speed, got.stuck_fraction, got.catch_delay) == \
        (0.0, 0.0, 1.0, 0.0)
    assert got.t_down == pytest.approx(1e-3, rel=1e-12) and got.period == pytest.approx(6e-3, rel=1e-12)  # s


def test_feasibility_needs_a_normal_force_strictly_above_mg_over_mu_s():
    from vibrofeed.models.vertical import check_feasible

    f_min = M * G / 0.72                         # the grip that just balances gravity
    with pytest.raises(ValueError, match="normal force too small"):
        check_feasible(M, f_min, 0.72, a_max=100 * G)          # at the bound: "must exceed"
    margins = check_feasible(M, f_min * (1 + 1e-9), 0.72, a_max=100 * G)   # just past it
    assert margins["normal_force_margin"] == pytest.approx(f_min * 1e-9, rel=1e-6)


def sliding_waveform(a_n):
    # x: +2 for 0.5 s then -2 for 0.5 s (velocity a triangle from -0.5 to 0.5 m/s, zero mean);
    # z: +a_n, -a_n, 0 on [0, 0.25], [0.25, 0.5], [0.5, 1] s
    return PiecewiseConstantAccel([0.25, 0.25, 0.5], [2.0, 2.0, -2.0], [a_n, -a_n, 0.0])


def test_sliding_limit_refuses_a_normal_load_that_reaches_zero():
    # g = 10: the normal load g + a_z is 0 on the second piece when a_n = g (at the bound), -0.5
    # just past it; either way the part would leave the track
    for a_n in (10.0, 10.5):
        with pytest.raises(ValueError, match="lose contact"):
            sliding_limit_speed(sliding_waveform(a_n), g=10.0, n=4000)


def test_sliding_limit_weights_the_friction_by_the_normal_load():
    # a_n = 9, g = 10: load 19, 1, 10 on the three pieces. For -0.5 < V < 0 the surface is
    # faster than V for -V/2 s of piece 1 (v_s = -0.5 + 2 t) and slower for (V + 0.5)/2 s; always
    # faster on piece 2; on piece 3 faster (0.5 - V)/2 s, slower (0.5 + V)/2 s. Balance:
    # 19 (-V - 0.25) + 0.25 - 10 V = 0, so V = -4.5 / 29
    V = sliding_limit_speed(sliding_waveform(9.0), g=10.0, n=40_000)
    assert V == pytest.approx(-4.5 / 29, abs=1e-4)             # ~ max|a_x| T / n
