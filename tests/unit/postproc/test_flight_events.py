"""Flight events of records built for one rule each: an impact that lasts a while between two
frames, a contact of two frames, a landing without a free-flight root, lift-off timed by a
contact force crossing zero, a record that ends in contact. Every expected time is the
closed form of the motion written into the record (still floor at z = 0, free flight under g)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from helpers import parts, write_result
from vibrofeed.postproc import Flights
from vibrofeed.postproc.flights import normal_contact_force
from vibrofeed.results.reader import Result

G = 9.81
R = 5e-4
M = 1e-6
DT = 1e-4


def record(tmp_path, rows, variables=None, name="f.h5", plate=None):
    """A one-part result from (t, bottom height, vz, contact force) rows on a still floor, or
    on a plate whose height and velocity at t are ``plate(t)`` (the bottom height is then
    absolute); the recorded force is the total one (contact force minus the weight)."""
    frames = [(k, float(t), parts([1], [[0.0, 0.0, z + R]], radius=R, mass=M, velocity=[[0, 0, v]],
                                  force=[[0, 0, fc - M * G]]))
              for k, (t, z, v, fc) in enumerate(rows)]
    if variables is None:
        variables = {"freq": ("50", "Hz", "f", "50"), "incline": ("0", "deg", "i", "0")}
    surface = None if plate is None else [([0.0, 0.0, plate(t)[0]], [0.0, 0.0, plate(t)[1]])
                                          for t, *_ in rows]
    return Result(write_result(tmp_path / name, frames, surface=surface, variables=variables))


def without_force(path):
    """Remove the recorded force, as in an older file (contact is then a gap below the tolerance)."""
    import h5py

    with h5py.File(path, "r+") as f:
        del f["particles/parts/force"]
    return path


def flight(t, t0, z0, v0):
    return z0 + v0 * (t - t0) - G / 2 * (t - t0) ** 2, v0 - G * (t - t0)


def test_an_impact_that_lasts_between_two_frames_launches_when_the_part_leaves(tmp_path):
    # falls from rest at t = 0, hits at t1 = 2.2 frames, rests 30 us, leaves at t_up with
    # half the speed: both instants between frames 2 and 3, seen only as a velocity jump
    t1, contact, e = 2.2e-4, 3e-5, 0.5
    h = G * t1 ** 2 / 2
    t_up = t1 + contact
    v_out = e * G * t1
    rows = []
    for t in np.arange(5) * DT:   # ends before the second impact (t_up + 2 v_out / g)
        z, v = flight(t, 0.0, h, 0.0) if t < t1 else flight(t, t_up, 0.0, v_out)
        rows.append((t, z, v, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1], abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]
    assert fl.impacts[0, 1] == pytest.approx(-G * t1, rel=1e-9)
    assert fl.impacts[0, 2] == pytest.approx(e, rel=1e-9)


def test_a_short_contact_ends_at_the_root_of_the_flight_that_follows(tmp_path):
    # Lands at t1 (between frames 4 and 5), touches at frames 5 and 6 (the force falling but
    # positive: too short for a lift-off from the force), leaves at t_up between frames 6
    # and 7, lands again at t_up + 2 w / g and rests to the end of the record.
    t1, t_up, w = 4.4e-4, 6.3e-4, 4e-3
    h = G * t1 ** 2 / 2
    t2 = t_up + 2 * w / G
    rows = []
    for t in np.arange(30) * DT:
        if t < t1:
            z, v = flight(t, 0.0, h, 0.0)
            fc = 0.0
        elif t < t_up:
            z, v, fc = -1e-9, 0.0, (3.0 if t < 5.5 * DT else 1.0) * M * G
        elif t < t2:
            z, v = flight(t, t_up, 0.0, w)
            fc = 0.0
        else:
            z, v, fc = 0.0, 0.0, M * G
        rows.append((t, z, v, fc))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1, t2], abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12)       # no launch from the final rest
    assert fl.takeoff_kinds == ["rebound"]
    assert fl.flights.tolist() == pytest.approx(np.array([[t_up, t2]]), abs=1e-12) and fl.n_hops == 1
    assert fl.impacts[0, 2] == pytest.approx(w / (G * t1), rel=1e-9)   # out over in
    assert fl.impacts[1, 2] == 0.0                                    # stays down


def test_a_landing_without_a_free_flight_root_is_the_first_frame_in_contact(tmp_path):
    # Held 1 um above the floor, rising slowly (as by an adhesive pull the record does not
    # show): no ballistic path reaches the floor, yet frame 3 has a contact force. The landing
    # is that frame; its approach speed is not an approach (w_in > 0): restitution 0.
    # The part leaves again after two frames of contact and flies until the end.
    v_hold, t_up, w = 2 * G * DT, 4.5e-4, 5e-3
    rows = []
    for k in range(12):
        t = k * DT
        if k < 3:
            rows.append((t, 1e-6, v_hold, 0.0))
        elif t < t_up:
            rows.append((t, 0.0, 0.0, (2.0 if k == 3 else 1.0) * M * G))
        else:
            z, v = flight(t, t_up, 0.0, w)
            rows.append((t, z, v, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings.tolist() == [3 * DT]
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]
    assert fl.impacts[0, 1] == pytest.approx(v_hold - G * DT, abs=1e-15)  # m/s, ~1e-3 (> 0)
    assert fl.impacts[0, 2] == 0.0


@pytest.mark.parametrize("f11, f12, overlap", [(0.5, -1.0, 1e-9), (1.0, 0.0, 1e-9), (0.5, -1.0, 0.0)])
def test_lift_off_where_the_contact_force_crosses_zero_inside_the_contact(tmp_path, f11, f12, overlap):
    # Lands between frames 2 and 3, rests; the contact force goes 3, f11, f12 (x m g) at
    # frames 10, 11, 12 while the part still overlaps (a damped contact pulls): lift-off is
    # the linear zero between frames 11 and 12 (at frame 12 itself when f12 = 0), not the
    # extrapolation of frames 10 and 11; it flies from frame 13 on. Touching the floor
    # exactly (overlap 0) is contact as much as overlapping it.
    t1 = 2.5e-4
    h = G * t1 ** 2 / 2
    t_l = (11 + f11 / (f11 - f12)) * DT
    force = {10: 3.0, 11: f11, 12: f12}
    rows = []
    for k in range(25):
        t = k * DT
        if t < t1:
            z, v = flight(t, 0.0, h, 0.0)
            rows.append((t, z, v, 0.0))
        elif k <= 12:
            rows.append((t, -overlap, 0.0, force.get(k, 2.0) * M * G))
        else:
            z, v = flight(t, t_l, 0.0, 2e-3)
            rows.append((t, z, v, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
        short = Flights(r).run(stop=14).results   # ends at the first frame in flight
    assert fl.landings[0] == pytest.approx(t1, abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_l], abs=1e-12) and fl.takeoff_kinds == ["lift-off"]
    assert short.takeoffs == pytest.approx([t_l], abs=1e-12)


def test_three_frames_of_contact_are_sustained_two_are_not(tmp_path):
    # Contact at frames 3..5 (force 4, 3, 1 x m g): sustained, lift-off extrapolated from the
    # last two, half a frame on; the part does leave then. Two frames (4..5) are an impact:
    # its launch is the root of the flight that follows, the same instant, a rebound.
    t_up = 5.5 * DT
    for first, kind in ((3, "lift-off"), (4, "rebound")):
        force = {3: 4.0, 4: 3.0, 5: 1.0}
        rows = []
        for k in range(10):
            t = k * DT
            if k < first:
                rows.append((t, 1e-6 * (first - k), -1e-2 * (k < first - 1), 0.0))
            elif t < t_up:
                rows.append((t, -1e-9, 0.0, force[k] * M * G))
            else:
                z, v = flight(t, t_up, 0.0, 3e-3)
                rows.append((t, z, v, 0.0))
        with record(tmp_path, rows, name=f"c{first}.h5") as r:
            fl = Flights(r).run().results
        assert fl.takeoffs == pytest.approx([t_up], abs=1e-12), kind
        assert fl.takeoff_kinds == [kind]


def test_a_launch_whose_flight_does_not_reach_back_to_the_floor_is_its_first_frame_in_flight(tmp_path):
    # At rest (two frames, no sustained contact), then seen 10 um up at its apex: traced back
    # over the frame interval the free flight stays above the floor
    rows = [(k * DT, 0.0, 0.0, M * G) for k in range(2)]
    rows += [(k * DT, 1e-5 - G / 2 * ((k - 2) * DT) ** 2, -G * (k - 2) * DT, 0.0) for k in range(2, 5)]
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.takeoffs.tolist() == [2 * DT] and fl.takeoff_kinds == ["rebound"]


def test_gravity_is_normal_to_the_surface_when_the_deck_has_no_incline(tmp_path):
    rows = [(k * DT, 0.0, 0.0, 2.5 * M * G) for k in range(3)]
    with record(tmp_path, rows, variables={"freq": ("50", "Hz", "f", "50")}) as r:
        assert normal_contact_force(r, 1) == pytest.approx(np.full(3, 2.5 * M * G), rel=1e-12)
        fl = Flights(r)
        assert repr(fl).endswith("not run>")
        fl.run()
        assert repr(fl).endswith("3 frames>")
    assert math.isclose(math.cos(math.radians(0.0)), 1.0)


def test_a_slow_impact_is_found_from_its_velocity_jump(tmp_path):
    # Falls from rest, hits at 1.5 frames at v_in = 1.5 g dt, rebounds with e = 0.2: the
    # velocity changes by (1 + e) v_in = 1.8 g dt between frames 1 and 2, less than two
    # frames' worth of gravity, and the impact must still be seen
    t1, e = 1.5 * DT, 0.2
    h, v_in = G * t1 ** 2 / 2, G * t1
    rows = []
    for t in np.arange(3) * DT:
        z, v = flight(t, 0.0, h, 0.0) if t < t1 else flight(t, t1, 0.0, e * v_in)
        rows.append((t, z, v, 0.0))
    assert rows[2][1] > 0   # frame 2 is in flight again
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1], abs=1e-12)
    assert fl.takeoffs == pytest.approx([t1], abs=1e-12)
    assert fl.impacts[0, 2] == pytest.approx(e, rel=1e-9)


def test_without_recorded_force_contact_is_a_gap_below_the_tolerance(tmp_path):
    # An older file without forces: resting 0.5 um above the floor is contact by the default
    # tolerance (0.2 % of the radius, 1 um); the part then leaves from that height at t_up
    # with speed w, so its flight traced back meets the floor at t_up + s, s < 0 the root of
    # g0 + w s - g s^2 / 2 = 0. With no tolerance the rest is flight and nothing launches.
    import h5py

    g0, w, t_up = 5e-7, 0.02, 4.5 * DT
    rows = []
    for k in range(9):
        t = k * DT
        if t < t_up:
            rows.append((t, g0, 0.0, 0.0))
        else:
            z, v = flight(t, t_up, g0, w)
            rows.append((t, z, v, 0.0))
    r = record(tmp_path, rows)
    r.close()
    with h5py.File(tmp_path / "f.h5", "r+") as f:
        del f["particles/parts/force"]
    s = (w - math.sqrt(w * w + 2 * G * g0)) / G
    with Result(tmp_path / "f.h5") as r:
        fl = Flights(r).run().results
        strict = Flights(r, contact_tolerance=0.0).run().results
    assert fl.contact_force is None
    assert fl.takeoffs == pytest.approx([t_up + s], abs=1e-12) and fl.takeoff_kinds == ["rebound"]
    assert len(strict.takeoffs) == 0 and len(strict.landings) == 0


def test_an_impact_in_a_record_of_two_frames(tmp_path):
    t1, e = 0.5 * DT, 0.8
    h, v_in = G * t1 ** 2 / 2, G * t1
    rows = [(0.0, h, 0.0, 0.0), (DT, *flight(DT, t1, 0.0, e * v_in), 0.0)]
    assert rows[1][1] > 0
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1], abs=1e-12) and fl.takeoffs == pytest.approx([t1], abs=1e-12)
    assert fl.impacts[0, 2] == pytest.approx(e, rel=1e-9)
    assert fl.n_hops == 0                                   # no complete flight in one interval
    # but in the air throughout: falling from the first frame, flying again after the impact
    assert fl.airborne_at_start and fl.in_flight_at_end == pytest.approx(t1, abs=1e-12)
    assert fl.airborne_fraction == pytest.approx(1.0, abs=1e-9)


def test_the_part_followed_by_default_is_the_lowest_id(tmp_path):
    frames = [(k, k * DT, parts([9, 4], [[0, 0, 1e-3 + R], [0, 0, R]], radius=R, mass=M)) for k in range(3)]
    with Result(write_result(tmp_path / "two.h5", frames)) as r:
        fl = Flights(r).run().results
        assert fl.part_id == 4 and fl.max_gap == pytest.approx(0.0, abs=1e-15)
        assert Flights(r, part_id=9).run().results.max_gap == pytest.approx(1e-3, abs=1e-15)  # m


def test_a_flat_contact_force_cannot_be_extrapolated_and_the_launch_is_the_flight_root(tmp_path):
    # Sustained contact (frames 3..6) whose force stays at m g to the end: no zero to find
    # or extrapolate; the launch is the root of the flight seen after it
    t_up = 6.4 * DT
    rows = []
    for k in range(12):
        t = k * DT
        if k < 3:
            rows.append((t, 1e-6 * (3 - k), -1e-2 * (k < 2), 0.0))
        elif t < t_up:
            rows.append((t, -1e-9, 0.0, M * G))
        else:
            z, v = flight(t, t_up, 0.0, 3e-3)
            rows.append((t, z, v, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]


def drop_and_hop(n, t1, t_up, w):
    """n frames of a part dropped from rest at t = 0 that lands at t1, is pressed (5 m g) until
    t_up, leaves at relative speed w and rests (m g) from its next landing t2 on: (rows, t2)."""
    h = G * t1 ** 2 / 2
    t2 = t_up + 2 * w / G
    rows = []
    for k in range(n):
        t = k * DT
        if t < t1:
            rows.append((t, *flight(t, 0.0, h, 0.0), 0.0))
        elif t < t_up:
            rows.append((t, -1e-9, 0.0, 5 * M * G))
        elif t < t2:
            rows.append((t, *flight(t, t_up, 0.0, w), 0.0))
        else:
            rows.append((t, -1e-9, 0.0, M * G))
    return rows, t2


def test_a_contact_seen_at_one_frame_lands_and_launches(tmp_path):
    # hits at 2.6 frames, seen touching at frame 3 only, leaves at 3.3 frames; the record
    # ends in contact (frames 8, 9), after the landing that ends the hop
    t1, t_up, w = 2.6 * DT, 3.3 * DT, 2e-3
    rows, t2 = drop_and_hop(10, t1, t_up, w)
    assert 7 * DT < t2 < 8 * DT
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1, t2], abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]


def test_the_realised_restitution_is_the_median_of_the_fast_impacts(tmp_path):
    # Three bounces on a still floor, restitution 0.6, 0.5, 0.1: the first two come in at
    # 0.2 and 0.12 m/s, the third at 0.06 m/s, slower than half the fastest: left out.
    v1, t1 = 0.2, 0.2 / G          # dropped from rest
    es = (0.6, 0.5, 0.1)
    hits, t, v = [], t1, v1
    for e in es:
        hits.append((t, v, e))
        t, v = t + 2 * e * v / G, e * v
    end = hits[-1][0] + 5e-4
    rows = []
    for tt in np.arange(0.0, end, 2e-4):
        last = [h for h in hits if h[0] <= tt]
        z, vz = flight(tt, 0.0, G * t1 ** 2 / 2, 0.0) if not last else \
            flight(tt, last[-1][0], 0.0, last[-1][2] * last[-1][1])
        rows.append((tt, z, vz, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([h[0] for h in hits], abs=1e-12)
    assert fl.impacts[:, 1] == pytest.approx([-h[1] for h in hits], rel=1e-9)
    assert fl.impacts[:, 2] == pytest.approx(es, rel=1e-9)
    assert fl.realised_restitution == pytest.approx(0.55, rel=1e-9)


def test_a_gap_equal_to_the_contact_tolerance_is_contact(tmp_path):
    # the record of the no-force test, its resting gap given as the tolerance itself:
    # airborne means above the tolerance
    import h5py

    g0, w, t_up = 5e-7, 0.02, 4.5 * DT
    rows = [(k * DT, g0, 0.0, 0.0) if k * DT < t_up else (k * DT, *flight(k * DT, t_up, g0, w), 0.0)
            for k in range(9)]
    record(tmp_path, rows).close()
    with h5py.File(tmp_path / "f.h5", "r+") as f:
        del f["particles/parts/force"]
    with Result(tmp_path / "f.h5") as r:
        rest = float(Flights(r).run().results.gap[0])
        fl = Flights(r, contact_tolerance=rest).run().results
    assert fl.takeoff_kinds == ["rebound"] and len(fl.takeoffs) == 1


def bounces_with(es, v1, dt):
    """Rows of a part dropped from rest onto a still floor, hitting it at v1 [m/s] and then
    rebounding with the restitutions ``es`` in turn; and the impacts (time, speed in, e)."""
    t1 = v1 / G
    hits, t, v = [], t1, v1
    for e in es:
        hits.append((t, v, e))
        t, v = t + 2 * e * v / G, e * v
    rows = []
    for tt in np.arange(0.0, hits[-1][0] + 5e-4, dt):
        last = [h for h in hits if h[0] <= tt]
        z, vz = flight(tt, 0.0, G * t1 ** 2 / 2, 0.0) if not last else \
            flight(tt, last[-1][0], 0.0, last[-1][2] * last[-1][1])
        rows.append((tt, z, vz, 0.0))
    return rows, hits


def test_the_realised_restitution_is_the_median_not_the_mean_of_the_fast_impacts(tmp_path):
    # Four bounces, restitution 0.9, 0.8, 0.5, 0.1: in at v1, 0.9 v1, 0.72 v1 (all at least
    # half the fastest) and 0.36 v1 (left out). The median of 0.9, 0.8, 0.5 is 0.8 (their
    # mean 0.733, the median of all four 0.65).
    es = (0.9, 0.8, 0.5, 0.1)
    rows, hits = bounces_with(es, 0.05, 2e-4)
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([h[0] for h in hits], abs=1e-12)   # s
    assert fl.impacts[:, 2] == pytest.approx(es, rel=1e-9)
    assert fl.realised_restitution == pytest.approx(0.8, rel=1e-9)


def test_a_touch_down_at_zero_speed_realises_no_restitution_not_nan(tmp_path):
    # The record of the landing without a free-flight root, the part's velocity now exactly
    # what gravity takes away over the last interval: carried to the first frame in contact it
    # is 0, a touch-down without approach. It is an impact (as fast as the fastest, 0), which
    # rebounds nothing: the realised restitution is 0; NaN is only for a record without impacts.
    t = np.arange(7) * DT
    v_hold = G * (t[3] - t[2])      # m/s: the same product the free flight subtracts
    rows = [(t[k], 1e-6, v_hold, 0.0) if k < 3 else (t[k], 0.0, 0.0, M * G) for k in range(7)]
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings.tolist() == [t[3]]
    assert fl.impacts.tolist() == [[t[3], 0.0, 0.0]]
    assert fl.realised_restitution == 0.0


def test_a_flight_slowed_by_air_drag_is_not_taken_for_an_impact(tmp_path):
    # Falling under gravity and Stokes drag (tau = m / (6 pi mu r), 5.9 s in air): each frame
    # it gains ~dt / tau = 2e-5 of its speed over free flight, far below an impact's jump. It
    # lands 0.2 ns after frame 3, 21 pm above the floor then, where free flight from frame 2,
    # without the drag, would already be 88 pm lower: below the floor. That is no impact: the
    # only landing is the one after frame 3, the part resting from frame 4 on.
    tau = M / (6 * math.pi * 1.81e-5 * R)
    v0 = -0.1
    t_land = 3 * DT + 2e-10

    def fall(t):   # height above the floor (0 at t_land) and velocity
        c = v0 + G * tau
        return (-G * tau * (t - t_land) + tau * c * (math.exp(-t_land / tau) - math.exp(-t / tau)),
                -G * tau + c * math.exp(-t / tau))

    rows = [(k * DT, *fall(k * DT), 0.0) if k <= 3 else (k * DT, -1e-9, 0.0, M * G) for k in range(8)]
    assert 0 < rows[3][1] < 3e-11                                      # m: just above at frame 3
    z2, v2 = rows[2][1], rows[2][2]
    assert z2 + v2 * DT - G / 2 * DT ** 2 < -5e-11                     # free flight: below
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t_land], abs=1e-12)          # s
    assert len(fl.takeoffs) == 0 and fl.n_hops == 0
    assert fl.impacts[0, 1] == pytest.approx(fall(t_land)[1], rel=1e-9)


def test_a_hop_shorter_than_two_frames_after_a_contact_lands(tmp_path):
    # Hits at 2.6 frames, touching at frame 3 only, leaves at 3.3 frames with w = 1.2 g dt / 2:
    # lands again 1.2 frames later, at 4.5 frames, frame 4 its only airborne frame; at rest after
    t1, t_up = 2.6 * DT, 3.3 * DT
    w = G * 1.2 * DT / 2
    rows, t2 = drop_and_hop(9, t1, t_up, w)
    assert 4 * DT < t2 < 5 * DT and rows[4][1] > 0
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1, t2], abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]
    assert fl.flights == pytest.approx(np.array([[t_up, t2]]), abs=1e-12) and fl.n_hops == 1


def falling_plate(t):
    """A plate falling away at 2 g (the top of a swing of Gamma = 2): height, velocity."""
    return -G * t ** 2, -2 * G * t


def test_a_gentle_landing_on_a_plate_falling_away_is_the_first_root(tmp_path):
    # Relative to a plate accelerating down at 2 g the part's free flight curves up at g: in
    # flight, its gap g / 2 (t - t1)(t - t2) would meet the plate at t1 = 2.2 and leave it at
    # t2 = 2.7 frames. It lands at t1 (relative speed w1 = -g (t2 - t1) / 2) and rebounds with
    # e = 0.5: the landing is the first root, the launch the same instant.
    t1, t2, e = 2.2 * DT, 2.7 * DT, 0.5
    w1 = -G * (t2 - t1) / 2
    rows = []
    for k in range(7):
        t = k * DT
        zs, vs = falling_plate(t)
        if t < t1:
            gap, rel = G / 2 * (t - t1) * (t - t2), G / 2 * (2 * t - t1 - t2)
        else:
            gap, rel = -e * w1 * (t - t1) + G / 2 * (t - t1) ** 2, -e * w1 + G * (t - t1)
        rows.append((t, zs + gap, vs + rel, 0.0))
    with record(tmp_path, rows, plate=falling_plate) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1], abs=1e-12)             # s
    assert fl.takeoffs == pytest.approx([t1], abs=1e-12) and fl.takeoff_kinds == ["rebound"]
    assert fl.impacts[0, 1] == pytest.approx(w1, rel=1e-6)           # m/s, -2.5e-4
    assert fl.impacts[0, 2] == pytest.approx(e, rel=1e-6)


def test_a_launch_from_a_plate_falling_away_is_the_last_root(tmp_path):
    # Pressed on the plate falling at 2 g at frames 0 and 1 (a soft impact under way), the part
    # leaves it at t_up = 1.6 frames with relative speed w: its flight traced back curves down
    # relative to the plate and met it also at t_up - 2 w / g (1.29 frames), in the same
    # interval; it left at the later one.
    t_up, w = 1.6 * DT, 1.5e-4
    assert DT < t_up - 2 * w / G
    rows = []
    for k in range(6):
        t = k * DT
        zs, vs = falling_plate(t)
        if t < t_up:
            rows.append((t, zs - 1e-9, vs, M * G))
        else:
            rows.append((t, zs + w * (t - t_up) + G / 2 * (t - t_up) ** 2, vs + w + G * (t - t_up), 0.0))
    with record(tmp_path, rows, plate=falling_plate) as r:
        fl = Flights(r).run().results
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]


@pytest.mark.parametrize("stop", [None, 3])
def test_without_force_a_slow_launch_is_traced_back_over_the_contact_to_its_first_frame(tmp_path, stop):
    # Resting 0.5 um above the floor (contact by the 1 um tolerance) at frames 0 and 1, it leaves
    # at 1.1 frames with w = 0.01 m/s: from that height its flight traced back meets the floor at
    # t_up + s = 0.61 frames (s < 0 the root of g0 + w s - g s^2 / 2), in the contact's first
    # interval; frame 2 is its first frame above the tolerance. The same when the record ends
    # there (stop=3: the run stopped at its first frame in flight).
    g0, w, t_up = 5e-7, 0.01, 1.1 * DT
    rows = [(k * DT, g0, 0.0, 0.0) if k * DT < t_up else (k * DT, *flight(k * DT, t_up, g0, w), 0.0)
            for k in range(6)]
    record(tmp_path, rows).close()
    s = (w - math.sqrt(w * w + 2 * G * g0)) / G
    assert 0 < t_up + s < DT and rows[2][1] > 1e-6
    with Result(without_force(tmp_path / "f.h5")) as r:
        fl = Flights(r).run(stop=stop).results
    assert fl.takeoffs == pytest.approx([t_up + s], abs=1e-12) and fl.takeoff_kinds == ["rebound"]


def test_without_force_the_launch_is_the_last_time_the_flight_traced_back_meets_the_plate(tmp_path):
    # A plate moving as a cubic over the record: the flight seen after the launch differs from
    # it by k (t - t_e)(t - t_m)(t - t_up), t_e, t_m, t_up = 0.5, 1.5, 3.5 frames: traced back it
    # meets the plate three times, and the part rests on the plate until t_up, the last.
    # Frame 4 is in flight but within the 1 um tolerance (0.44 um up), frame 5 above it.
    t_e, t_m, t_up, w = 0.5 * DT, 1.5 * DT, 3.5 * DT, 0.01
    k = 1e-7 / DT ** 3

    def path(t):   # the flight: height and velocity
        return w * (t - t_up) - G / 2 * (t - t_up) ** 2, w - G * (t - t_up)

    def plate(t):  # the flight minus the cubic
        f = k * (t - t_e) * (t - t_m) * (t - t_up)
        df = k * ((t - t_m) * (t - t_up) + (t - t_e) * (t - t_up) + (t - t_e) * (t - t_m))
        return path(t)[0] - f, path(t)[1] - df

    rows = [(k_ * DT, *(plate(k_ * DT) if k_ * DT <= t_up else path(k_ * DT)), 0.0) for k_ in range(7)]
    record(tmp_path, rows, plate=plate).close()
    with Result(without_force(tmp_path / "f.h5")) as r:
        fl = Flights(r).run().results
    assert fl.gap[4] == pytest.approx(4.375e-7, abs=1e-15) and fl.gap[5] > 1e-6   # m
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == ["rebound"]


@pytest.mark.parametrize("force, t_up, kind", [
    # the force peaks at the middle frame (the landing's impact) and falls at the last: lift-off
    # extrapolated from the last two, half a frame on, whatever came before
    ({3: 0.5, 4: 3.0, 5: 1.0}, 5.5 * DT, "lift-off"),
    # overlapping, yet no frame of the contact pushes (the force 0, then pulling): no force to
    # extrapolate to zero; the launch is the root of the flight seen after it
    ({3: 0.0, 4: 0.0, 5: -0.5}, 5.4 * DT, "rebound"),
])
def test_only_a_pushing_force_falling_at_the_end_of_a_sustained_contact_times_a_lift_off(
        tmp_path, force, t_up, kind):
    t1 = 2.5 * DT
    h = G * t1 ** 2 / 2
    rows = []
    for k in range(10):
        t = k * DT
        if t < t1:
            rows.append((t, *flight(t, 0.0, h, 0.0), 0.0))
        elif k <= 5:
            rows.append((t, -1e-9, 0.0, force[k] * M * G))
        else:
            rows.append((t, *flight(t, t_up, 0.0, 3e-3), 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings[0] == pytest.approx(t1, abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12) and fl.takeoff_kinds == [kind]


@pytest.mark.parametrize("tol", [-1e-9, float("nan"), float("inf")])
def test_a_contact_tolerance_that_is_not_a_gap_is_refused(tmp_path, tol):
    """A gap tolerance below 0 would call a part resting in contact airborne (and one
    NaN or infinite, nothing): refused before the result is read."""
    from vibrofeed.errors import InputError

    with pytest.raises(InputError, match=r"contact_tolerance must be a gap of 0 m or more, got "):
        Flights(None, contact_tolerance=tol)


def test_a_result_without_a_vibration_frequency_is_analysed_at_any_frame_spacing(tmp_path):
    # a plate rising at a steady 1 cm/s (followed exactly by its Hermite cubic), the part resting
    # on it, frames 0.2 s apart and no `freq` in the deck: no period to hold the frames to, so
    # nothing is refused; the part stays in contact throughout
    v = 0.01

    def plate(t):
        return v * t, v

    rows = [(t, v * t - 1e-9, v, M * G) for t in (0.0, 0.2, 0.4)]
    with record(tmp_path, rows, variables={"incline": ("0", "deg", "i", "0")}, plate=plate) as r:
        fl = Flights(r).run().results
    assert len(fl.landings) == 0 and len(fl.takeoffs) == 0 and fl.n_hops == 0
    assert fl.max_gap == pytest.approx(-1e-9, abs=1e-15)   # m


def test_with_a_recorded_force_the_launch_is_not_traced_back_past_the_last_frame_in_contact(tmp_path):
    # Falls onto the floor at 1.5 frames, pushed at frames 2 and 3 (two frames: no lift-off
    # from the force), seen in flight from frame 4 on. That flight traced back meets the floor
    # at 2.5 frames, before frame 3, where the recorded force still pushes: the contact lasts
    # to frame 3, so the launch is not there but at the first frame in flight.
    t1, t_back, w = 1.5 * DT, 2.5 * DT, 0.05
    h = G * t1 ** 2 / 2
    rows = [(k * DT, *flight(k * DT, 0.0, h, 0.0), 0.0) for k in range(2)]
    rows += [(k * DT, -1e-9, 0.0, 3 * M * G) for k in (2, 3)]
    rows += [(k * DT, *flight(k * DT, t_back, 0.0, w), 0.0) for k in range(4, 8)]
    assert flight(3 * DT, t_back, 0.0, w)[0] > 0    # the traced flight is above the floor at frame 3
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings[0] == pytest.approx(t1, abs=1e-12)
    assert fl.takeoffs.tolist() == [4 * DT] and fl.takeoff_kinds == ["rebound"]


def test_a_lift_off_extrapolated_past_the_contact_is_the_first_frame_in_flight(tmp_path):
    # Sustained contact at frames 3..5 whose force falls slowly (3, 2.5, 2 x m g): extrapolated,
    # it would reach zero 4 frames after frame 5; the part is seen in flight at frame 6, so it
    # lifted off by then: the lift-off is frame 6, not later.
    force = {3: 3.0, 4: 2.5, 5: 2.0}
    rows = [(k * DT, 1e-6 * (3 - k), -1e-2 * (k < 2), 0.0) for k in range(3)]
    rows += [(k * DT, -1e-9, 0.0, force[k] * M * G) for k in (3, 4, 5)]
    rows += [(k * DT, *flight(k * DT, 5.9 * DT, 0.0, 3e-3), 0.0) for k in range(6, 10)]
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.takeoffs.tolist() == [6 * DT] and fl.takeoff_kinds == ["lift-off"]


def test_a_touch_down_at_zero_speed_that_leaves_again_realises_no_restitution(tmp_path):
    # The touch-down without approach (w_in = 0 exactly at frame 3), after which the part leaves
    # at 3.4 frames upward at 0.02 m/s: whatever the speed out, out over an approach of 0 is no
    # restitution; it is 0, not infinite.
    t = np.arange(8) * DT
    v_hold = G * (t[3] - t[2])      # m/s: the same product the free flight subtracts
    t_up, w = 3.4 * DT, 0.02
    rows = [(t[k], 1e-6, v_hold, 0.0) for k in range(3)] + [(t[3], 0.0, 0.0, M * G)]
    rows += [(t[k], *flight(t[k], t_up, 0.0, w), 0.0) for k in range(4, 8)]
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings.tolist() == [t[3]]
    assert fl.takeoffs == pytest.approx([t_up], abs=1e-12)              # s
    assert fl.impacts.tolist() == [[t[3], 0.0, 0.0]]
    assert fl.realised_restitution == 0.0


def test_a_launch_seen_coming_down_realises_no_restitution(tmp_path):
    # Falls onto the floor at 1.5 frames, touches at frame 2, and is next seen 5 um up at frame
    # 3 coming down at 1 cm/s (its flight traced back does not reach the floor: launched at
    # frame 3), landing again at frame 4. Just after that launch it approaches the floor: it
    # did not rebound, and a restitution is never negative: 0 (not -1e-2 / -1.5e-3).
    t1 = 1.5 * DT
    h = G * t1 ** 2 / 2
    rows = [(k * DT, *flight(k * DT, 0.0, h, 0.0), 0.0) for k in range(2)]
    rows += [(2 * DT, -1e-9, 0.0, 5 * M * G), (3 * DT, 5e-6, -0.01, 0.0)]
    rows += [(k * DT, -1e-9, 0.0, M * G) for k in (4, 5)]
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
    assert fl.landings == pytest.approx([t1, 4 * DT], abs=1e-12)      # s
    assert fl.takeoffs.tolist() == [3 * DT] and fl.takeoff_kinds == ["rebound"]
    assert fl.impacts[0, 1] == pytest.approx(-G * t1, rel=1e-9)        # m/s: it did approach
    assert fl.impacts[:, 2].tolist() == [0.0, 0.0]
