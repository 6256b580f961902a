"""Outlet events and the mass balance (vibrofeed.engine.outlet) on known trajectories."""

import math
import warnings

import numpy as np
import pytest

from vibrofeed.engine.outlet import Outlet, ballistic_crossing, gravity_vector

G = gravity_vector(9.81, 0.0)


def test_gravity_is_tilted_by_the_incline():
    assert np.allclose(gravity_vector(9.81, 0.0), [0, 0, -9.81], rtol=0, atol=1e-12)  # m/s^2
    g = gravity_vector(9.81, 30.0)
    assert np.allclose(g, 9.81 * np.array([-0.5, 0, -math.cos(math.radians(30))]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("incline", [0.0, 5.0, -10.0])
def test_crossing_of_a_known_parabola(incline):
    """A part leaves the edge at t0 with v0; the frame sees it later; the crossing is exact."""
    g = gravity_vector(9.81, incline)
    x0, v0, t0 = np.array([0.02, 1e-4, 1.5e-4]), np.array([0.043, 0.002, 0.01]), 0.3
    catch_z = -4e-4

    def state(t):
        s = t - t0
        return x0 + v0 * s + 0.5 * g * s * s, v0 + g * s

    # true crossing time: descending root of z(t) = catch_z
    a, b, c = 0.5 * g[2], v0[2], x0[2] - catch_z
    t_true = t0 + (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    for t_frame in (t_true + 1e-6, t_true + 3e-3, t_true + 1e-2):
        x, v = state(t_frame)
        tau, pos, vel = ballistic_crossing(x[None], v[None], catch_z, g)
        assert abs(t_frame + tau[0] - t_true) < 1e-14
        want_x, want_v = state(t_true)
        assert np.allclose(pos[0], want_x, atol=1e-15, rtol=0)
        assert abs(pos[0, 2] - catch_z) < 1e-16
        assert np.allclose(vel[0], want_v, atol=1e-14, rtol=0)


def test_crossing_when_rising_after_the_plane_or_never_above_it():
    # below the plane, thrown upwards but it never reached the plane: the frame's own state
    tau, pos, _ = ballistic_crossing(np.array([[0.0, 0, -1e-3]]), np.array([[0, 0, 0.01]]), 0.0, G)
    assert tau[0] == 0 and pos[0, 2] == -1e-3
    # exactly on the plane: tau = 0
    tau, _, _ = ballistic_crossing(np.array([[0.0, 0, 0.0]]), np.array([[0, 0, -1.0]]), 0.0, G)
    assert tau[0] == 0
    # no gravity, falling at constant speed: linear
    tau, _, _ = ballistic_crossing(np.array([[0.0, 0, -1e-3]]), np.array([[0, 0, -0.1]]), 0.0,
                                   np.zeros(3))
    assert abs(tau[0] + 1e-2) < 1e-16



def test_a_part_that_never_reached_the_plane_raises_no_warning():
    # its D < 0 is clamped before the square root: no 'invalid value' RuntimeWarning per frame
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        tau, _, _ = ballistic_crossing(np.array([[0.0, 0, -1e-3]]), np.array([[0, 0, 0.01]]), 0.0, G)
    assert tau[0] == 0


def frame(ids, x, z, vz=-0.3):
    n = len(ids)
    pos = np.column_stack([x, np.zeros(n), z])
    return {"id": np.asarray(ids), "position": pos,
            "velocity": np.column_stack([np.full(n, 0.04), np.zeros(n), np.full(n, vz)])}


def test_mass_balance_with_parts_appearing_falling_and_leaving():
    out = Outlet(outlet_x=0.02, catch_z=-3e-4, gravity=G)
    # t = 0: three parts on the track
    ev, c = out.step(0.0, frame([1, 2, 3], [0.005, 0.019, 0.01], [1e-4] * 3), inserted=3)
    assert ev is None and c == dict(inserted=3, on_track=3, exited=0, lost=0)
    # t = 0.01: part 2 fell past the edge below the catch plane; part 4 inserted;
    # part 3 beyond the edge but still above the plane (not yet an event)
    ev, c = out.step(0.01, frame([1, 2, 3, 4], [0.006, 0.0205, 0.0201, 0.001],
                                 [1e-4, -5e-4, 1e-4, 1e-4]), inserted=4)
    assert ev["id"].tolist() == [2] and ev["time"][0] < 0.01
    assert ev["orientation"].tolist() == [[1, 0, 0, 0]]
    assert c == dict(inserted=4, on_track=3, exited=1, lost=0)
    # t = 0.02: part 2 still falling (no second event), part 3 crossed, part 2 ...
    ev, c = out.step(0.02, frame([1, 2, 3, 4], [0.007, 0.021, 0.0206, 0.002],
                                 [1e-4, -2e-3, -4e-4, 1e-4]), inserted=4)
    assert ev["id"].tolist() == [3]
    assert c == dict(inserted=4, on_track=2, exited=2, lost=0)
    # t = 0.03: the floor deleted 2 and 3; part 5 inserted; part 1 vanished without an event
    ev, c = out.step(0.03, frame([4, 5], [0.003, 0.001], [1e-4, 1e-4]), inserted=5)
    assert ev is None
    assert c == dict(inserted=5, on_track=2, exited=2, lost=1)


def test_events_in_one_frame_come_in_crossing_order():
    out = Outlet(outlet_x=0.0, catch_z=0.0, gravity=G)
    f = frame([7, 8, 9], [0.01, 0.01, 0.01], [-1e-3, -1e-4, -5e-4], vz=-0.5)
    f["orientation"] = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0]])
    ev, c = out.step(1.0, f, inserted=3)
    assert ev["id"].tolist() == [7, 9, 8]
    assert np.all(np.diff(ev["time"]) > 0)
    assert ev["orientation"][0].tolist() == [1, 0, 0, 0] and ev["orientation"][2].tolist() == [0, 1, 0, 0]
    assert np.allclose(ev["position"][:, 2], 0.0, atol=1e-18)
    assert c["exited"] == 3 and c["on_track"] == 0 and c["lost"] == 0
    assert out.not_ballistic == 0


def test_an_event_that_did_not_fly_freely_is_timed_at_its_frame_and_counted():
    out = Outlet(outlet_x=0.0, catch_z=0.0, gravity=G)
    ev, _ = out.step(2.0, frame([1], [0.01], [-1e-3], vz=-0.01), inserted=1)
    assert ev["time"].tolist() == [2.0] and out.not_ballistic == 1
