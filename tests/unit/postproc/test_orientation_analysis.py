"""The orientation analysis on synthetic results whose answers are known by construction
(tests/bulk_synthetic.py): box-like clumps turned by hand, exiting at known times, turned by a
station between where they arrive at it and where they have passed it."""

import math

import numpy as np
import pytest

from bulk_synthetic import OUTLET_X, RADIUS, feeder
from vibrofeed.errors import InputError, ParameterError
from vibrofeed.feeders.feeder import Feeder
from vibrofeed.orientation import body_axes
from vibrofeed.postproc.feedrate import batch_rate
from vibrofeed.postproc.orientation import Orientation, path_directions
from vibrofeed.results.reader import Result

FRAMES = np.arange(0, 1.0 + 1e-9, 0.01)
# A box-like part: 5 x 2 spheres spanning a 0.5 x 0.2 mm rectangle in the body's xy plane
# (long along x, thin along z).
R_S = 5e-5
BOX = np.array([[x, y, 0.0, R_S] for x in (-2e-4, -1e-4, 0.0, 1e-4, 2e-4) for y in (-5e-5, 5e-5)])


def quat(axis, deg):
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    h = math.radians(deg) / 2
    return np.array([math.cos(h), *(math.sin(h) * a)])


def then(first, second):
    """The quaternion of turning by ``first``, then by ``second``."""
    w1, x1, y1, z1 = second
    w2, x2, y2, z2 = first
    return np.array([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                     w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2])


def yaw(deg):
    return quat([0, 0, 1], deg)


DOWN = quat([1, 0, 0], 180)   # marked face (+z) down, long axis still along x
SIDE = quat([1, 0, 0], 90)    # on a long side (+y down... -y up), long axis along x
END = quat([0, 1, 0], 90)     # standing on an end


# -- at the outlet ----------------------------------------------------------------------
def outlet_run(tmp_path):
    """10 parts: 0-6 up and lengthwise (either end leading), 7 on a side, 8 up and lengthwise,
    9 face down and crosswise, 0.1 ms after 8 (a double: no clear track between them). They
    tip onto an end past the edge (the events' orientation)."""
    q = [yaw(a) for a in (0, 5, -10, 180, 15, 190, 3)] + [SIDE, yaw(-4), then(DOWN, yaw(70))]
    exits = np.r_[0.1 + 0.08 * np.arange(8), 0.74, 0.7401]
    lanes = np.r_[np.arange(9) * 1e-3, 8e-3 + 1.5e-3]
    path = feeder(tmp_path / "out.h5", FRAMES, exits, speed=0.05, orientations=np.array(q),
                  tipped=np.tile(END, (10, 1)), body_template=BOX, lanes=lanes)
    return path, exits


def test_the_outlet_census_and_the_rate_of_correct_single_parts(tmp_path):
    path, exits = outlet_run(tmp_path)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=1.0).run().results
    assert o.n_delivered == 10 and o.delivered_times == pytest.approx(exits, abs=1e-15)
    # read on the track, not tipped onto an end past the edge
    assert o.state_fractions == {"up": 0.8, "down": 0.1, "side": 0.1, "end": 0.0}
    assert o.lengthwise_fraction == pytest.approx(0.9, abs=1e-12)      # all but the one at 70 deg
    assert o.correct_fraction == pytest.approx(0.8, abs=1e-12)         # 0-6 and 8
    assert o.singulated_fraction == pytest.approx(0.8, abs=1e-12)      # all but the double 8, 9
    assert list(o.delivered_correct & o.delivered_singulated) == [True] * 7 + [False] * 3
    # over the window of 1 s: 8 correct parts, 7 of them single
    assert o.correct_rate == pytest.approx(8.0, rel=1e-12)
    assert o.oriented_rate == pytest.approx(7.0, rel=1e-12)
    assert o.parts_per_s == pytest.approx(10.0, rel=1e-12)
    # its error is the feed rate's batch means of those parts' exits
    single = exits[:7]
    assert o.oriented_rate_err == pytest.approx(batch_rate(single, np.ones(7), 0.0, 1.0, 100.0, 10)[1],
                                                rel=1e-12)
    assert o.correct == "up, lengthwise" and o.reason is None     # 10 exits: enough


def test_what_counts_as_correct_is_the_designers_choice(tmp_path):
    path, _ = outlet_run(tmp_path)
    with Result(path) as r:
        either = Orientation(r, correct="up|down, any-direction", start=0.0, end=1.0).run().results
        lead = Orientation(r, correct="up, lengthwise, lead +x", start=0.0, end=1.0).run().results
        loose = Orientation(r, within=80, start=0.0, end=1.0).run().results
    assert either.correct_fraction == pytest.approx(0.9, abs=1e-12)    # all but the one on a side
    # +x leading: yaw 0, 5, -10, 15, 3 and -4 (not 180 and 190)
    assert lead.correct_fraction == pytest.approx(0.6, abs=1e-12)
    assert lead.oriented_rate == pytest.approx(5.0, rel=1e-12)
    assert loose.lengthwise_fraction == pytest.approx(1.0, abs=1e-12)


def test_the_runs_own_correct_is_the_default_of_the_analysis_and_of_the_sweeps_metrics(tmp_path):
    from vibrofeed.sweep.metrics import metrics

    path, _ = outlet_run(tmp_path)   # recorded before correct existed: up and lengthwise
    said = {"correct": ("up|down,any-direction", "-", "", "up,lengthwise")}
    q = [yaw(a) for a in (0, 5, -10, 180, 15, 190, 3)] + [SIDE, yaw(-4), then(DOWN, yaw(70))]
    told = feeder(tmp_path / "told.h5", FRAMES, np.r_[0.1 + 0.08 * np.arange(8), 0.74, 0.7401],
                  speed=0.05, orientations=np.array(q), tipped=np.tile(END, (10, 1)), body_template=BOX,
                  lanes=np.r_[np.arange(9) * 1e-3, 8e-3 + 1.5e-3], variables=said)
    with Result(path) as old, Result(told) as r:
        before = Orientation(old, start=0.0, end=1.0).run().results
        own = Orientation(r, start=0.0, end=1.0).run().results
        over = Orientation(r, correct="up, lengthwise", start=0.0, end=1.0).run().results
    assert (before.correct, before.correct_source) == ("up, lengthwise", "run")
    assert before.correct_fraction == pytest.approx(0.8, abs=1e-12)
    assert (own.correct, own.correct_source, own.run_correct) == ("up|down, any-direction", "run",
                                                                  "up|down, any-direction")
    assert own.correct_fraction == pytest.approx(0.9, abs=1e-12)      # all but the one on a side
    assert (over.correct, over.correct_source, over.run_correct) == ("up, lengthwise", "given",
                                                                     "up|down, any-direction")
    assert over.correct_fraction == pytest.approx(0.8, abs=1e-12)
    # a sweep's row, and so the optimiser's objective (its metrics), measures the run's own: 60
    # parts, one in four face down, the run counting face down correct
    n = 60
    q = np.array([DOWN if k % 4 == 0 else yaw(0) for k in range(n)])
    many = feeder(tmp_path / "many.h5", np.arange(0, 1.2 + 1e-9, 0.01), 0.403 + 0.01 * np.arange(n),
                  speed=0.05, orientations=q, body_template=BOX, lanes=np.arange(n) % 6 * 1e-3,
                  variables={"correct": ("down", "-", "", "up,lengthwise")})
    row = metrics(many)
    assert row["singulation_reason"] is None
    assert row["correct_fraction"] == pytest.approx(0.25, abs=1e-12)


def test_recirculation_load_of_a_track_without_returns_is_its_rejects(tmp_path):
    path, _ = outlet_run(tmp_path)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=1.0).run().results
    assert o.recirculation_source == "rejected" and o.recirculation_per_s == 0.0


def test_recirculation_load_of_a_run_that_returns_is_its_returned_count():
    # a line returning one part at every other frame (10 ms, 30 ms, ...): 50 parts/s over the window,
    # whatever its rejects table holds
    from types import SimpleNamespace

    from vibrofeed.postproc.base import Results

    time = np.arange(0, 1.0 + 1e-9, 0.01)
    result = SimpleNamespace(time=time, mass_balance={"returned": (np.arange(len(time)) + 1) // 2},
                             rejects={"time": np.array([0.3, 0.5])})
    o = SimpleNamespace(result=result, results=Results(), batches=10)
    Orientation._recirculation(o, Results(), (0.0, 1.0, 100.0))
    assert o.results.recirculation_source == "returned"
    assert o.results.recirculation_per_s == pytest.approx(50.0, rel=1e-12)
    assert o.results.recirculation_per_s_err == pytest.approx(0.0, abs=1e-9)    # every batch alike


# -- a station --------------------------------------------------------------------------
GATE = {"gate_width": ("6e-4", "m", "", "0"), "gate_at": ("0.5", "-", "", "0.7"),
        "track_width": ("1.2e-3", "m", "", "1e-3")}


def test_a_gate_that_turns_parts_between_its_in_and_out(tmp_path):
    # the gate at 10 mm narrows 1.2 -> 0.6 mm: 0.3 mm long; a part passes it from a part size
    # (0.3 mm) before to one past: 9.7 .. 10.6 mm. The parts turn at 10.1 mm: in, 4 up and
    # lengthwise, 3 up and crosswise, 3 on a side; out, the crosswise ones lengthwise and one
    # of those on a side up: 8 correct of 10, from 4.
    before = [yaw(0)] * 4 + [yaw(90)] * 3 + [SIDE] * 3
    after = [yaw(0)] * 4 + [yaw(2)] * 3 + [yaw(0), SIDE, SIDE]
    exits = 0.503 + 0.04 * np.arange(10)
    lanes = np.arange(10) * 1e-3
    path = feeder(tmp_path / "gate.h5", FRAMES, exits, speed=0.05, orientations=np.array(before),
                  turn=(0.0101, np.array(after)), body_template=BOX, lanes=lanes, variables=GATE)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=1.0).run().results
    (gate,) = o.stations
    assert (gate["name"], gate["kind"], gate["element"], gate["out_at"]) == ("s1.gate", "gate", 1, "x_out")
    assert gate["x_in"] == pytest.approx(9.7e-3, abs=1e-12)
    assert gate["x_out"] == pytest.approx(1.06e-2, abs=1e-12)
    assert (gate["n_in"], gate["n_out"]) == (10, 10)
    assert gate["in_states"] == {"up": 7, "down": 0, "side": 3, "end": 0}
    assert gate["out_states"] == {"up": 8, "down": 0, "side": 2, "end": 0}
    assert (gate["correct_in"], gate["correct_out"]) == \
        (pytest.approx(0.4, abs=1e-12), pytest.approx(0.8, abs=1e-12))
    assert gate["efficiency"] == pytest.approx(2.0, rel=1e-12)
    assert gate["rejected_share"] == 0.0
    assert gate["rejects_per_s"] is None                  # the reject table knows no gate
    # along the path: every part passes each 1 mm bin in two frames (0.5 mm apart)
    assert o.census_x[5] == pytest.approx(5.5e-3, rel=0, abs=1e-15) and o.census_count[5] == 20
    assert o.census_fractions["up"][5] == pytest.approx(0.7, abs=1e-12)
    assert o.census_correct[5] == pytest.approx(0.4, abs=1e-12)
    assert o.census_fractions["side"][15] == pytest.approx(0.2, abs=1e-12)
    assert o.census_correct[15] == pytest.approx(0.8, abs=1e-12)
    assert o.correct_fraction == pytest.approx(0.8, abs=1e-12)        # as they leave


def test_a_station_crossed_in_the_window_only_counts_there(tmp_path):
    # the same gate, the window ending before the last four parts reach its in (9.7 mm at
    # exit - 0.206 s: 0.537 .. 0.657 s for parts 6-9)
    before = [yaw(0)] * 10
    exits = 0.503 + 0.04 * np.arange(10)
    path = feeder(tmp_path / "gate.h5", FRAMES, exits, speed=0.05, orientations=np.array(before),
                  body_template=BOX, lanes=np.arange(10) * 1e-3, variables=GATE)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=0.52).run().results
    (gate,) = o.stations
    # in: parts crossing 9.7 mm before 0.52 s: exit - 0.206 < 0.52, parts 0-5; out (10.6 mm,
    # exit - 0.188): parts 0-5 as well
    assert (gate["n_in"], gate["n_out"]) == (6, 6)


def test_a_part_already_past_a_station_s_way_in_at_the_start_counts_at_neither(tmp_path):
    # part 0 exits at 0.195 s: at t = 0 it is past the gate's in (9.7 mm, crossed at exit -
    # 0.206 s) and before its out (10.6 mm, at exit - 0.188 s = 0.007 s), as a part pre-filled
    # there: it crosses out without having crossed in, and would make the gate add a part
    exits = np.r_[0.195, 0.503 + 0.04 * np.arange(5)]
    path = feeder(tmp_path / "gate.h5", FRAMES, exits, speed=0.05, orientations=np.array([yaw(0)] * 6),
                  body_template=BOX, lanes=np.arange(6) * 1e-3, variables=GATE)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=1.0).run().results
    (gate,) = o.stations
    assert (gate["n_in"], gate["n_out"]) == (5, 5) and gate["rejected_share"] == 0.0


def test_a_part_that_appears_between_a_station_s_in_and_out_passes_in_where_it_appears(tmp_path):
    # part 0 is put on the track at 10.0 mm (the inlet's block may reach past a gate's way in,
    # 9.7 mm): it never crosses in, yet passes the gate; its first frame is its way in
    exits = 0.503 + 0.04 * np.arange(6)
    insert = np.r_[10e-3, np.zeros(5)]
    path = feeder(tmp_path / "gate.h5", FRAMES, exits, speed=0.05, orientations=np.array([yaw(0)] * 6),
                  body_template=BOX, lanes=np.arange(6) * 1e-3, variables=GATE, insert_x=insert)
    with Result(path) as r:
        o = Orientation(r, start=0.0, end=1.0).run().results
    (gate,) = o.stations
    assert (gate["n_in"], gate["n_out"]) == (6, 6)


# -- the body frame from the template ------------------------------------------------------
def test_a_template_laid_along_y_is_measured_along_its_own_length(tmp_path):
    along_y = BOX[:, [1, 0, 2, 3]]                  # the same box, long along the body's y
    # length: body y; width: body x, turned to -x so that +z stays the marked face
    assert body_axes(along_y) == pytest.approx(np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]]), abs=1e-12)
    q = np.array([yaw(0), yaw(90), yaw(-90), yaw(45)])
    exits = 0.2 + 0.1 * np.arange(4)
    path = feeder(tmp_path / "y.h5", FRAMES, exits, speed=0.05, orientations=q, body_template=along_y,
                  lanes=np.arange(4) * 1e-3)
    with Result(path) as r:
        o = Orientation(r, correct="up|down, lengthwise", start=0.0, end=1.0).run().results
    # unturned, its length lies across the track; turned a quarter either way, along it
    assert list(o.delivered_correct) == [False, True, True, False]


def test_the_body_axes_of_a_template_turned_in_its_frame():
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    turned = BOX.copy()
    turned[:, :2] = BOX[:, :2] @ np.array([[c, s], [-s, c]])   # rows turned 30 deg about z
    axes = body_axes(turned)
    assert axes[:, 0] == pytest.approx([c, s, 0], abs=1e-9)
    assert abs(axes[2, 2]) == pytest.approx(1.0, abs=1e-12)
    assert np.linalg.det(axes) == pytest.approx(1.0, abs=1e-12)


# -- the path's direction -----------------------------------------------------------------
def test_a_bowls_helix_runs_into_its_chute_and_a_line_along_x():
    bowl = Feeder.from_values({"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0,
                               "turns": 1.5, "wall_height": 1e-3, "chute_length": 8e-3, "part_size": 3e-4})
    b = bowl.bowl
    t, up = path_directions(bowl, [0.0, b.length - 1e-12, b.length + 1e-3])
    a = math.radians(3.0)
    chute = [math.cos(a), 0.0, math.sin(a)]
    assert t[1] == pytest.approx(chute, abs=1e-9) and t[2] == pytest.approx(chute, abs=1e-12)
    # at its start, 1.5 turns before its end (-90 deg): at +90 deg, running along -x
    assert t[0] == pytest.approx([-math.cos(a), 0.0, math.sin(a)], abs=1e-9)
    assert np.einsum("ni,ni->n", t, up) == pytest.approx([0, 0, 0], abs=1e-12)
    line, up = path_directions(None, [0.0, np.nan])
    assert line == pytest.approx(np.array([[1, 0, 0]] * 2), abs=1e-12)
    assert up == pytest.approx(np.array([[0, 0, 1]] * 2), abs=1e-12)


# -- what is refused ----------------------------------------------------------------------
def test_spheres_have_no_orientation(tmp_path):
    path = feeder(tmp_path / "spheres.h5", FRAMES, [0.2, 0.4])
    with Result(path) as r, pytest.raises(InputError, match="spheres have no orientation"):
        Orientation(r)


def test_a_state_that_does_not_exist_and_angles_out_of_range_are_refused(tmp_path):
    path, _ = outlet_run(tmp_path)
    with Result(path) as r:
        with pytest.raises(ParameterError, match=r"^--correct: no state named 'upside'"):
            Orientation(r, correct="upside, lengthwise", correct_name="--correct")
        for within in (0, -5, 95):
            with pytest.raises(InputError, match="within must be an angle"):
                Orientation(r, within=within)


def test_the_synthetic_track_is_the_one_the_analysis_reads():
    assert OUTLET_X == 0.02 and RADIUS == 1.5e-4   # (the gate's numbers above assume them)
