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
    assert fl.impacts[0, 1] == pytest.approx(v_hold - G * DT)      # > 0
    assert fl.impacts[0, 2] == 0.0


def test_lift_off_where_the_contact_force_crosses_zero_inside_the_contact(tmp_path):
    # Lands between frames 2 and 3, rests; the contact force goes 3, 1, -1 (x m g) at frames
    # 10, 11, 12 while the part still overlaps (a damped contact pulls): lift-off is the
    # linear zero between frames 11 and 12; it flies from frame 13 on.
    t1 = 2.5e-4
    h = G * t1 ** 2 / 2
    t_l = 11.5 * DT
    force = {10: 3.0, 11: 1.0, 12: -1.0}
    rows = []
    for k in range(25):
        t = k * DT
        if t < t1:
            z, v = flight(t, 0.0, h, 0.0)
            rows.append((t, z, v, 0.0))
        elif k <= 12:
            rows.append((t, -1e-9, 0.0, force.get(k, 2.0) * M * G))
        else:
            z, v = flight(t, t_l, 0.0, 2e-3)
            rows.append((t, z, v, 0.0))
    with record(tmp_path, rows) as r:
        fl = Flights(r).run().results
        short = Flights(r).run(stop=14).results   # ends at the first frame in flight
    assert fl.landings[0] == pytest.approx(t1, abs=1e-12)
    assert fl.takeoffs == pytest.approx([t_l], abs=1e-12) and fl.takeoff_kinds == ["lift-off"]
    assert short.takeoffs == pytest.approx([t_l], abs=1e-12)


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
