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


def record(tmp_path, rows, variables=None, name="f.h5"):
    """A one-part result from (t, bottom height, vz, contact force) rows on a still floor;
    the recorded force is the total one (contact force minus the weight)."""
    frames = [(k, float(t), parts([1], [[0.0, 0.0, z + R]], radius=R, mass=M, velocity=[[0, 0, v]],
                                  force=[[0, 0, fc - M * G]]))
              for k, (t, z, v, fc) in enumerate(rows)]
    if variables is None:
        variables = {"freq": ("50", "Hz", "f", "50"), "incline": ("0", "deg", "i", "0")}
    return Result(write_result(tmp_path / name, frames, variables=variables))


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
    assert fl.n_hops == 0 and fl.airborne_fraction == 0.0   # no complete flight in one interval


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


def test_a_contact_seen_at_one_frame_lands_and_launches(tmp_path):
    # hits at 2.6 frames, seen touching at frame 3 only, leaves at 3.3 frames; the record
    # ends in contact (frames 8, 9), after the landing that ends the hop
    t1, t_up, w = 2.6 * DT, 3.3 * DT, 2e-3
    h = G * t1 ** 2 / 2
    t2 = t_up + 2 * w / G
    rows = []
    for k in range(10):
        t = k * DT
        if t < t1:
            rows.append((t, *flight(t, 0.0, h, 0.0), 0.0))
        elif t < t_up:
            rows.append((t, -1e-9, 0.0, 5 * M * G))
        elif t < t2:
            rows.append((t, *flight(t, t_up, 0.0, w), 0.0))
        else:
            rows.append((t, -1e-9, 0.0, M * G))
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
