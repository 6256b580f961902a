"""Outlet events and the mass balance (vibrofeed.engine.outlet) on known trajectories."""

import math
import warnings

import numpy as np
import pytest

from vibrofeed.engine.outlet import LineOutlet, Outlet, ballistic_crossing, gravity_vector

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


def test_a_part_on_the_plane_rising_or_without_gravity_rising_is_timed_at_its_frame():
    # on the plane and rising (d = 0, v_z > 0): sqrt(D) - v_z = 0, no descending crossing
    # behind it; rising with no gravity never came down through the plane: both tau = 0
    # and the frame's own state (not 0/0 or 2d/0)
    at = np.array([[0.01, 0.0, 0.0]])
    tau, pos, vel = ballistic_crossing(at, np.array([[0.0, 0, 0.5]]), 0.0, G)
    assert tau.tolist() == [0.0] and pos.tolist() == at.tolist() and vel[0, 2] == 0.5
    below = np.array([[0.01, 0.0, -1e-3]])
    tau, pos, _ = ballistic_crossing(below, np.array([[0.0, 0, 0.5]]), 0.0, np.zeros(3))
    assert tau.tolist() == [0.0] and pos.tolist() == below.tolist()


def test_a_flight_whose_apex_just_touched_the_plane_crossed_it_there():
    # D = 0: g_z = -8, d = -1/16, v_z = -1 (v_z^2 = 2 g_z d, all exact in binary): the apex,
    # tau = v_z / g_z = -1/8 s ago, sat on the plane; that is its crossing, not tau = 0
    tau, pos, vel = ballistic_crossing(np.array([[0.0, 0, -0.0625]]), np.array([[0.0, 0, -1.0]]),
                                       0.0, np.array([0.0, 0.0, -8.0]))
    assert tau.tolist() == [-0.125]
    assert pos[0, 2] == 0.0 and vel[0, 2] == 0.0


def test_a_part_exactly_on_the_catch_plane_has_not_left_yet():
    # below means z < catch_z: beyond the edge at z = catch_z is no event yet, nor before
    # the edge a reject; a hair lower it is
    out = Outlet(outlet_x=0.02, catch_z=-3e-4, gravity=G)
    ev, c = out.step(0.0, frame([1], [0.021], [-3e-4]), inserted=1)
    assert ev is None and c == dict(inserted=1, on_track=1, exited=0, lost=0)
    ev, c = out.step(0.01, frame([1], [0.021], [-3.01e-4]), inserted=1)
    assert ev["id"].tolist() == [1] and c["exited"] == 1 and c["on_track"] == 0
    # beyond means x > outlet_x: below the plane right at the edge it has not left
    ev, c = out.step(0.02, frame([1, 2], [0.021, 0.02], [-2e-3, -5e-4]), inserted=2)
    assert ev is None and c == dict(inserted=2, on_track=1, exited=1, lost=0)
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    ev, rej, c = line.step(0.0, frame([1, 2], [0.021, 0.01], [-3e-4, -3e-4]), inserted=2)
    assert ev is None and rej is None
    assert c == dict(inserted=2, on_track=2, exited=0, rejected=0, lost=0)


def test_a_part_below_the_plane_right_at_the_outlet_edge_is_a_reject():
    # it left when x > outlet_x; at x = outlet_x it had not got over the edge: it fell off
    # a side of section 2
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    ev, rej, c = line.step(0.5, frame([4], [0.02], [-5e-4]), inserted=1)
    assert ev is None and rej["id"].tolist() == [4] and rej["section"].tolist() == [2]
    assert c == dict(inserted=1, on_track=0, exited=0, rejected=1, lost=0)
    assert line.reject_times.tolist() == rej["time"].tolist()


def test_a_reject_is_of_the_section_where_it_crossed_the_plane_behind_the_inlet_section_1():
    # sections start at 0 and 6 mm; crossings (flown back at 0.04 m/s along x) behind the
    # inlet wall (x < 0), on section 1 and on section 2
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    _, rej, c = line.step(1.0, frame([1, 2, 3], [-1e-4, 0.003, 0.01], [-5e-4] * 3), inserted=3)
    assert rej["position"][:, 0].max() < 0.01 and rej["position"][:, 0].min() < 0.0
    by_id = dict(zip(rej["id"].tolist(), rej["section"].tolist()))
    assert by_id == {1: 1, 2: 1, 3: 2}
    assert c["rejected"] == 3 and c["lost"] == 0


# -- parts that tumble over an edge (issue 36) -------------------------------------------------
CHIP_REACH = 1.46e-4  # m: a 200 x 200 x 50 um chip's enclosing sphere about its centre


def with_radius(f, radius):
    f["radius"] = np.full(len(f["id"]), radius)
    return f


def test_a_part_tumbling_over_the_outlet_edge_is_an_exit_not_a_loss():
    # The chip went over the outlet edge tumbling; the track is a sheet without
    # thickness, so its centre was still 60-90 um behind the edge when it dropped below the
    # catch plane. Its reach is 146 um: it went over the edge, an exit.
    out = Outlet(outlet_x=0.02, catch_z=-3e-4, gravity=G)
    out.step(0.0, with_radius(frame([1], [0.02 - 3e-5], [1e-4]), CHIP_REACH), inserted=1)
    ev, c = out.step(0.01, with_radius(frame([1], [0.02 - 8e-5], [-4e-4]), CHIP_REACH), inserted=1)
    assert ev["id"].tolist() == [1] and c == dict(inserted=1, on_track=0, exited=1, lost=0)
    ev, c = out.step(0.02, with_radius(frame([], [], []), CHIP_REACH), inserted=1)  # the floor took it
    assert ev is None and c == dict(inserted=1, on_track=0, exited=1, lost=0)


def test_a_part_below_the_plane_farther_behind_the_edge_than_its_reach_did_not_go_over_it():
    out = Outlet(outlet_x=0.02, catch_z=-3e-4, gravity=G)
    ev, c = out.step(0.0, with_radius(frame([1], [0.02 - 1.47e-4], [-4e-4]), CHIP_REACH), inserted=1)
    assert ev is None and c == dict(inserted=1, on_track=1, exited=0, lost=0)
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    ev, rej, c = line.step(0.0, with_radius(frame([1], [0.02 - 1.47e-4], [-4e-4]), CHIP_REACH),
                           inserted=1)
    assert ev is None and rej["section"].tolist() == [2] and c["rejected"] == 1


def test_a_line_counts_a_part_tumbling_over_its_outlet_edge_as_an_exit_not_a_reject():
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    ev, rej, c = line.step(0.5, with_radius(frame([4], [0.02 - 9e-5], [-5e-4]), CHIP_REACH), inserted=1)
    assert ev["id"].tolist() == [4] and rej is None
    assert c == dict(inserted=1, on_track=0, exited=1, rejected=0, lost=0)


def test_a_part_tumbling_off_at_a_joint_is_a_reject_of_the_section_it_fell_from():
    # Section 2 starts at 6 mm. Part 1 was last seen above the plane on section 1's end, 20 um
    # before the joint; tumbling into the joint its centre swung 60 um under section 2's edge
    # before it crossed the plane there: it fell from section 1. Part 2 was over section 2,
    # its centre 200 um past the joint (more than its reach): section 2's, as its crossing.
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    line.step(0.0, with_radius(frame([1, 2], [0.006 - 2e-5, 0.0062], [1e-4, 1e-4]), CHIP_REACH),
              inserted=2)
    _, rej, c = line.step(0.01, with_radius(frame([1, 2], [0.006 + 6e-5, 0.0062], [-4e-4, -4e-4]),
                                            CHIP_REACH), inserted=2)
    assert rej["position"][:, 0].min() > 0.006   # both crossed the plane beyond the joint
    assert dict(zip(rej["id"].tolist(), rej["section"].tolist())) == {1: 1, 2: 2}
    assert c == dict(inserted=2, on_track=0, exited=0, rejected=2, lost=0)


def test_a_part_remembered_above_the_plane_keeps_where_it_was_until_it_falls():
    # seen above the plane over section 2 at one frame, then below it at a frame later (two
    # frames in between it was still above): the last frame above it decides, not the first
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006))
    line.step(0.0, frame([5], [0.004], [1e-4]), inserted=1)
    line.step(0.01, frame([5], [0.0065], [1e-4]), inserted=1)
    _, rej, _ = line.step(0.02, frame([5], [0.0059], [-1e-3]), inserted=1)
    assert rej["section"].tolist() == [2]


def test_a_part_blown_off_the_side_that_flies_on_past_the_edge_is_a_reject_not_an_exit():
    # the exit's walls at y = -0.5 and 0.5 mm, a 0.5 mm part: the band reaches 1 mm either way.
    # Part 1 leaves over the edge (y = 0.2 mm); part 2 crosses the plane past the edge 3 mm
    # across (a jet blew it over the wall 2 mm before the edge and it flew on); part 3 at the
    # band's edge is still an exit, part 4 just beyond it is not
    line = LineOutlet(outlet_x=0.02, catch_z=-3e-4, gravity=G, section_x=(0.0, 0.006),
                      band=(-1e-3, 1e-3))
    f = frame([1, 2, 3, 4], [0.0205, 0.021, 0.0203, 0.0203], [-4e-4] * 4)
    f["position"][:, 1] = [2e-4, 3e-3, -1e-3, -1.001e-3]
    ev, rej, c = line.step(0.5, f, inserted=4)
    assert sorted(ev["id"].tolist()) == [1, 3]
    assert sorted(rej["id"].tolist()) == [2, 4] and rej["section"].tolist() == [2, 2]
    assert c == dict(inserted=4, on_track=0, exited=2, rejected=2, lost=0)


def test_the_band_is_the_last_elements_walls_a_part_either_way_in_the_decks_frame():
    from vibrofeed.feeders.feeder import Feeder

    line = Feeder.from_values({"part_size": "5e-4", "shape": "1", "part_thickness": "2e-4",
                               "track_length": "5e-3", "track_width": "1.2e-3", "sections": "2",
                               "s2_length": "4e-3", "s2_width": "8e-4", "s2_step": "5e-5",
                               "s2_freq": "100", "s2_amp_t": "6e-5", "s2_amp_n": "2e-5"})
    assert line.exit_band == pytest.approx((-4e-4 - 5e-4, 4e-4 + 5e-4), rel=0, abs=1e-15)
