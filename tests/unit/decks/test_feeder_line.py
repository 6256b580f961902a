"""Feeder lines (vibrofeed.line): section 2's mesh joins section 1 with a step down, is closed
where parts must stay on it and open only at the joint, the outlet, the wall tops and the side
drop; its cross tilt, drop and wiper have the asked dimensions; a line's parameters are checked
with one-line errors; and the reject bookkeeping adds up on parts whose fate is known."""

import math
from collections import Counter

import numpy as np
import pytest

from helpers import DECKS
from vibrofeed.decks import Deck
from vibrofeed.engine.outlet import LineOutlet, gravity_vector
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.feeder import section_from
from vibrofeed.geometry import prepare_bulk_feeder, track_mesh
from vibrofeed.line import Section, combined, section_mesh
from vibrofeed.parameters import resolve

L1, W1 = 0.01, 1.2e-3
TOL = 1e-12


def line_of(p: dict) -> Feeder:
    """The two-section feeder of ``p`` (absent numbers: zero, as the decks' tools)."""
    return Feeder.from_values({"sections": 2, "part_size": 3e-4, **p})


def joint_motion(p: dict) -> tuple[float, float]:
    return line_of(p).joints[0].motion


def joint_steps(p: dict) -> tuple[float, float]:
    return line_of(p).joints[0].steps


def check_line(p: dict) -> None:
    Feeder.from_values(p).check()


def section(**kw) -> Section:
    base = dict(x0=L1, length=8e-3, width=4.2e-4, wall_height=6e-4, step=5e-5, cross_tilt=10.0)
    return Section(**{**base, **kw})


def edges(triangles):
    e = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    return Counter(map(tuple, np.sort(e, axis=1)))


def open_edges(v, t):
    return [v[list(e)] for e, n in edges(t).items() if n == 1]


def same(a, b):
    """Coordinates (m) equal up to the mesh's rounding: TOL, with no relative part (numpy's default
    atol=1e-8 m and rtol=1e-5, 0.2 um at 2 cm, would take a gap's width for a coincidence)."""
    return np.isclose(a, b, rtol=0, atol=TOL)


def test_section_dimensions_and_cross_tilt():
    s = section()
    v, t = section_mesh(s)
    tilt = math.tan(math.radians(10.0))
    assert v[:, 0].min() == pytest.approx(L1, abs=TOL) and v[:, 0].max() == pytest.approx(L1 + 8e-3, abs=TOL)
    assert np.abs(v[:, 1]).max() == pytest.approx(2.1e-4, abs=TOL)
    # the floor descends across towards the reference wall at -w/2: 5e-5 + 4.2e-4 tan 10 deg down there
    assert s.lowest == pytest.approx(-(5e-5 + 4.2e-4 * tilt), abs=TOL)
    assert v[:, 2].min() == pytest.approx(s.lowest, abs=TOL)
    assert v[:, 2].max() == pytest.approx(-5e-5 + 6e-4, abs=TOL)  # wall tops
    floor = np.array([c for c in v if c[2] < -5e-5 + 1e-9])  # at or below the floor's high edge
    assert np.allclose(floor[:, 2], -5e-5 - (2.1e-4 - floor[:, 1]) * tilt, rtol=0, atol=TOL)


@pytest.mark.parametrize("drop", [False, True])
def test_closed_along_the_walls_open_only_where_parts_may_leave(drop):
    kw = dict(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4) if drop else {}
    s = section(**kw)
    v, t = section_mesh(s)
    counts = edges(t)
    assert set(counts.values()) <= {1, 2}
    lo, hi, top = -s.width / 2, s.width / 2, -s.step + s.wall_height
    a, b = s.drop_x if drop else (np.inf, np.inf)
    inner = lo + s.drop_width
    for p, q in open_edges(v, t):
        x, y, z = (p + q) / 2
        at_ends = same(p[0], q[0]) and (same(x, s.x0) or same(x, s.x1))
        on_top = same(p[2], top) and same(q[2], top)
        at_drop_ends = same(x, a) or same(x, b)
        wall_end = drop and same(p[0], q[0]) and same(y, hi) and at_drop_ends
        drop_edge = drop and same(p[1], inner) and same(q[1], inner) and a - TOL <= x <= b + TOL
        drop_step = drop and same(p[0], q[0]) and at_drop_ends and y > inner
        assert at_ends or on_top or wall_end or drop_edge or drop_step, (p, q)
    # the floor edge along the reference wall is never open; along the other wall only over the drop
    for p, q in open_edges(v, t):
        along = not same(p[0], q[0])
        assert not (along and same(p[1], lo) and same(q[1], lo) and p[2] < top - TOL)
        if along and same(p[1], hi) and same(q[1], hi) and p[2] < top - TOL:
            pytest.fail(f"the floor's edge at +w/2 is open at x = {p[0]:g}..{q[0]:g} m")
    if drop:  # over the drop no floor reaches past the drop width
        over = (v[:, 0] > a + TOL) & (v[:, 0] < b - TOL)
        assert over.any() and v[over, 1].max() == pytest.approx(inner, abs=TOL)


def test_normals_face_into_the_section():
    trimesh = pytest.importorskip("trimesh")
    s = section(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4, wiper_height=3.5e-4, wiper_at=0.7,
                wiper_length=3e-4)
    v, t = section_mesh(s)
    m = trimesh.Trimesh(v, t, process=False)
    n, c = m.face_normals, m.triangles_center
    floor = np.isclose(c[:, 2], s.floor_z(c[:, 1]), rtol=0, atol=1e-9)
    assert floor.any() and np.all(n[floor, 2] > 0.98)  # cos 10 deg
    side = np.abs(n[:, 1]) > 0.99
    assert side.any() and np.all(n[side, 1] * c[side, 1] < 0)  # the walls face the centre line
    under = n[:, 2] < -0.98
    assert under.any()  # the wiper's underside faces the floor
    upstream = n[:, 0] < -0.99
    assert upstream.any() and np.allclose(c[upstream, 0], s.wiper_x[0], rtol=0, atol=TOL)


def test_wiper_underside_follows_the_floor_at_its_height():
    s = section(wiper_height=3.5e-4, wiper_at=0.5, wiper_length=3e-4)
    v, t = section_mesh(s)
    w0, w1 = s.wiper_x
    assert w0 == pytest.approx(L1 + 4e-3, abs=TOL) and w1 - w0 == pytest.approx(3e-4, abs=TOL)
    bar = v[(v[:, 0] >= w0 - TOL) & (v[:, 0] <= w1 + TOL)]
    under = bar[np.isclose(bar[:, 2], s.floor_z(bar[:, 1]) + 3.5e-4, rtol=0, atol=TOL)]
    # both ends of the bar, on both walls: the clearance is the same across the tilted floor
    assert len(under) == 4 and np.allclose(np.sort(np.abs(under[:, 1])), 2.1e-4, rtol=0, atol=TOL)


def test_no_vertex_of_a_section_lies_below_its_floor():
    s = section(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4, wiper_height=3.5e-4, wiper_at=0.7,
                wiper_length=3e-4)
    v, _ = section_mesh(s)
    assert (v[:, 2] >= s.floor_z(v[:, 1]) - TOL).all()


def test_a_drop_needs_a_length_and_must_leave_a_floor():
    assert section(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4).has_drop
    assert not section(drop_from=0.3, drop_to=0.3, drop_width=2.5e-4).has_drop  # no length
    assert not section(drop_from=0.25, drop_to=0.5, drop_width=4.2e-4).has_drop  # as wide as the track
    assert not section(drop_from=0.25, drop_to=0.5, drop_width=0.0).has_drop  # no floor left: none


def test_each_section_has_its_own_drive():
    p = {"freq": 100.0, "amp_t": 1e-5, "amp_n": 2e-5, "phase": 30.0, "waveform": 2,
         "s2_freq": 120.0, "s2_amp_t": 3e-5, "s2_amp_n": 4e-5, "s2_phase": 45.0,
         "sections": 2, "part_size": 3e-4}
    feeder = Feeder.from_values(p)
    assert feeder.section_values(1) == p
    assert feeder.section_values(2) == {**p, "freq": 120.0, "amp_t": 3e-5, "amp_n": 4e-5,
                                        "phase": 45.0, "waveform": 0}  # section 2 runs a sine


def test_section_joins_section_one_with_a_step_down():
    v1, t1 = track_mesh(L1, W1, 1e-3, gate_width=4.2e-4, gate_x=0.6 * L1)
    s = section()
    v2, t2 = section_mesh(s)
    exit_y = np.abs(v1[same(v1[:, 0], L1) & (v1[:, 2] == 0), 1]).max()
    start = v2[same(v2[:, 0], L1)]
    assert start[:, 1].min() <= -exit_y + TOL and start[:, 1].max() >= exit_y - TOL  # covers the exit
    floor_start = start[start[:, 2] < -s.step + 1e-9, 2]
    assert floor_start.max() == pytest.approx(-5e-5, abs=TOL)  # a step of s2_step at the high edge
    v, t = combined((v1, t1), (v2, t2))
    assert len(v) == len(v1) + len(v2) and len(t) == len(t1) + len(t2)
    assert np.array_equal(v[t[len(t1):]], v2[t2])


def test_tooling_that_does_not_fit_is_refused():
    with pytest.raises(ParameterError, match="wiper"):
        section_mesh(section(wiper_height=3.5e-4, wiper_at=0.99, wiper_length=3e-4))


def line_values(**given):
    base = {"sections": "2", "n_parts": "200", "track_length": "0.01", "track_width": "1.2e-3",
            "gate_width": "4.2e-4", "gate_at": "0.6", "fill_from": "0.05", "fill_to": "0.6",
            "s2_width": "4.2e-4", "s2_wall_height": "6e-4", "s2_cross_tilt": "10"}
    return {**base, **{k: str(v) for k, v in given.items()}}


def test_prepare_writes_each_section_its_own_mesh(tmp_path):
    from stl import mesh as stl_mesh

    deck = Deck(DECKS / "bulk_feeder.liggghts")
    values = resolve(deck, line_values(s2_drop_from=0.3, s2_drop_to=0.6, s2_drop_width=2.5e-4))
    prepared = prepare_bulk_feeder(values, tmp_path)
    v2, t2 = section_mesh(section_from(values))
    stl = stl_mesh.Mesh.from_file(str(tmp_path / "track_s2.stl"))
    assert np.allclose(stl.vectors, v2[t2], rtol=0, atol=1e-8)  # STL is float32: ~2e-9 m at 2 cm
    v1, t1 = track_mesh(0.01, 1.2e-3, 1e-3, 4.2e-4, 0.006)
    v, t = prepared.track  # the line at rest: both sections
    assert np.array_equal(v, np.concatenate([v1, v2])) and len(t) == len(t1) + len(t2)


def test_a_single_section_is_the_bulk_feeder_unchanged(tmp_path):
    deck = Deck(DECKS / "bulk_feeder.liggghts")
    values = resolve(deck, {})
    assert values["sections"] == "1"
    prepared = prepare_bulk_feeder(values, tmp_path)
    assert not (tmp_path / "track_s2.stl").exists()
    v, t = track_mesh(0.02, 2e-3, 1e-3, 0.0, 0.7 * 0.02)
    assert np.array_equal(prepared.track[0], v) and np.array_equal(prepared.track[1], t)


@pytest.mark.parametrize("given, words", [
    ({"s2_width": 3e-4}, "narrower than section 1's exit"),
    ({"s2_width": 2e-4}, "narrower than a part"),
    # spheres: the largest is 4.35e-4 m across (the exit, 4.5e-4 m, takes it)
    ({"size_spread": 0.45, "gate_width": 4.5e-4, "s2_width": 4.3e-4}, "narrower than a part"),
    ({"s2_step": 2e-5, "s2_phase": -30}, "must step down by more than"),
    ({"s2_step": 3e-4}, "not a small step"),
    ({"s2_step": 3e-4}, "(with the cross tilts it is"),  # the step at the gate's low end, as asked
    ({"s2_step": 3e-4, "s2_cross_tilt": 0}, "not a small step"),  # a part's thickness exactly
    ({"s2_amp_t": 2.6e-4}, "joint opens"),
    ({"s2_amp_t": 2.6e-4}, "more than half a part (0.00015 m)"),  # part_size 3e-4 m
    ({"amp_t": 2.5e-5, "s2_amp_t": 1.75e-4}, "joint opens"),  # by exactly half a part
    ({"s2_wiper_height": 2e-4}, "lower than a part's thickness"),
    ({"s2_wiper_height": 7e-4}, "not below the walls"),
    ({"s2_wiper_height": 6e-4}, "not below the walls"),  # as high as the walls
    ({"s2_wiper_height": 4e-4, "s2_wiper_at": 0.99}, "runs past the outlet"),
    ({"s2_drop_to": 0.5, "s2_drop_width": 1e-4}, "less than half a part (0.00015 m across it"),
    # a box rides lengthwise: half its width W, not of its length, is what the drop must hold
    ({"shape": "box", "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4, "track_width": 2e-3,
      "wall_height": 1.5e-3, "s2_width": 2e-3, "s2_wall_height": 1e-3, "s2_drop_to": 0.5,
      "s2_drop_width": 2.4e-4, "gate_width": 0, "n_parts": 10},
     "less than half a part (0.00025 m across it in a file)"),
    ({"shape": "box", "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4, "track_width": 2e-3,
      "wall_height": 1.5e-3, "s2_width": 2e-3, "gate_width": 4.9e-4}, "(0.0005 m across riding lengthwise)"),
    ({"s2_drop_to": 0.5, "s2_drop_width": 0}, "must be > 0"),  # a drop's extent with no floor left
    ({"s2_drop_to": 0.5, "s2_drop_width": 5e-4}, "narrower than s2_width"),
    ({"s2_drop_to": 0.5, "s2_drop_width": 4.2e-4}, "narrower than s2_width"),  # as wide
    ({"s2_wall_height": 1e-4}, "no higher than a part's centre"),
    ({"s2_wall_height": 1.5e-4}, "no higher than a part's centre"),  # exactly there
    ({"waveform": 1}, "sines"),
    ({"hamaker": 1e-19}, "section 1's floor only"),
    ({"air_viscosity": 1.81e-5}, "section 1's floor only"),  # air's
    # no gate (gate_width 0): section 1's exit is its whole width, 1.2e-3 m
    ({"gate_width": 0, "s2_width": 1e-3}, "narrower than section 1's exit (0.0012 m)"),
    # two frequencies: the floors part by amp_n + s2_amp_n = 1e-4 m at most; a step of just
    # that does not clear it (no cross tilt at the gate's high end: the step there is s2_step)
    ({"s2_freq": 120, "s2_step": 1e-4}, "must step down by more than"),
    ({"s2_amp_n": 0.005}, "s2_amp_n=0.005 m at s2_freq=100 Hz"),
    ({"sections": 3}, "sections=3: deck bulk_feeder declares sections 1 to 2"),
])
def test_line_refusals_are_one_line(given, words):
    deck = Deck(DECKS / "bulk_feeder.liggghts")
    with pytest.raises(ParameterError) as err:
        resolve(deck, line_values(**given))
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_step_without_cross_tilts_is_named_alone():
    with pytest.raises(ParameterError) as err:
        resolve(Deck(DECKS / "bulk_feeder.liggghts"), line_values(s2_step=3e-4, s2_cross_tilt=0))
    assert "cross tilts" not in str(err.value)  # the step is s2_step everywhere


def test_the_same_values_pass_with_one_section():
    deck = Deck(DECKS / "bulk_feeder.liggghts")
    resolve(deck, {"s2_width": "3e-4", "s2_step": "1e-3"})  # sections=1: the s2_* are unused


def test_joint_motion_closed_forms():
    a, b = 5e-5, 1e-4
    p = {"freq": 100, "s2_freq": 100, "amp_n": a, "s2_amp_n": a, "amp_t": a, "s2_amp_t": b,
         "phase": 0, "s2_phase": -60}
    dz, dx = joint_motion(p)
    assert dz == pytest.approx(a, rel=1e-12)  # two equal sines 60 degrees apart differ by one amplitude
    assert dx == pytest.approx(b - a, rel=1e-12)
    dz, dx = joint_motion({**p, "s2_freq": 120})
    assert dz == pytest.approx(2 * a, rel=1e-12) and dx == pytest.approx(a + b, rel=1e-12)


def body(ids, x, z, vz=-0.1):
    n = len(ids)
    return {"id": np.array(ids), "position": np.column_stack([x, np.zeros(n), z]),
            "velocity": np.tile([0.0, 0.0, vz], (n, 1))}


def test_rejects_and_exits_add_up_by_construction():
    g = gravity_vector(9.81, 0.0)
    o = LineOutlet(0.018, -5e-4, g, (0.0, 0.01))
    # frame 1: five parts on the line; frame 2: 2 falls off section 2's side, 4 off section 1,
    # 5 leaves over the outlet edge; frame 3: 3 vanishes without an event (lost), 2 is gone
    ev, rej, c = o.step(0.0, body([1, 2, 3, 4, 5], [1e-3, 0.012, 0.013, 0.005, 0.0179], [1e-4] * 5), 5)
    assert ev is None and rej is None and c == {"inserted": 5, "on_track": 5, "exited": 0, "rejected": 0,
                                                 "lost": 0}
    ev, rej, c = o.step(0.01, body([1, 2, 3, 4, 5], [1e-3, 0.012, 0.013, 0.005, 0.0185],
                                   [1e-4, -6e-4, 1e-4, -7e-4, -6e-4]), 6)
    assert list(ev["id"]) == [5] and sorted(rej["id"]) == [2, 4]
    assert dict(zip(rej["id"], rej["section"])) == {2: 2, 4: 1}
    assert np.allclose(rej["position"][:, 2], -5e-4, rtol=0, atol=1e-12)  # timed at the catch plane
    assert c == {"inserted": 6, "on_track": 2, "exited": 1, "rejected": 2, "lost": 1}
    ev, rej, c = o.step(0.02, body([1], [1e-3], [1e-4]), 6)
    assert ev is None and rej is None
    assert c == {"inserted": 6, "on_track": 1, "exited": 1, "rejected": 2, "lost": 2}


def write_line_result(path, rejected_counts):
    """A two-frame line result: part 1 stays, part 2 falls off section 2's side in frame 2."""
    from helpers import write_line_frames

    frames = [([1, 2], [[1e-3, 0, 1e-4], [0.012, 2e-4, z2]]) for z2 in (1e-4, -6e-4)]
    return write_line_frames(path, frames, [2, 2], [{"rejected": n} for n in rejected_counts])


def test_a_line_result_is_checked_with_its_rejects(tmp_path):
    from vibrofeed.results.check import check_file
    from vibrofeed.results.reader import Result

    good = write_line_result(tmp_path / "good.h5", [0, 1])
    report = check_file(good)
    assert report.ok, [str(p) for p in report.problems]
    with Result(good) as r:
        assert list(r.rejects["id"]) == [2] and list(r.rejects["section"]) == [2]
        assert list(r.mass_balance["rejected"]) == [0, 1] and len(r.outlet["id"]) == 0
    bad = write_line_result(tmp_path / "bad.h5", [0, 0])  # the reject not counted
    problems = " ".join(str(p) for p in check_file(bad).problems)
    assert "inserted differs from on_track + exited + rejected + lost" in problems


def test_feedrate_reports_a_lines_rejects(tmp_path):
    from vibrofeed.cli.feedrate import table
    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.results.reader import Result

    with Result(write_line_result(tmp_path / "line.h5", [0, 1])) as r:
        s = FeedRate(r).run().summary()
    assert (s["inserted"], s["on_track"], s["exited"], s["rejected"], s["lost"]) == (2, 1, 0, 1, 0)
    s["model_velocity"], s["model_note"] = None, "synthetic"
    assert "exited 0, rejected 1, lost 0" in table(s)


def test_joint_steps_with_cross_tilts_closed_forms():
    w, step, t = 1.2e-3, 5e-5, math.tan(math.radians(10.0))
    p = {"track_width": w, "gate_width": 0.0, "s2_width": w, "s2_step": step, "track_length": 4e-3,
         "s2_length": 5e-3, "part_size": 3e-4}
    # both floors tilted alike across the same width: a uniform step
    lo, hi = joint_steps({**p, "cross_tilt": 10.0, "s2_cross_tilt": 10.0})
    assert lo == pytest.approx(step, rel=1e-9) and hi == pytest.approx(step, rel=1e-9)
    # section 2 level after a tilted section 1: section 1's floor drops w tan(10) below it at -y
    lo, hi = joint_steps({**p, "cross_tilt": 10.0, "s2_cross_tilt": 0.0})
    assert lo == pytest.approx(step - w * t, rel=1e-9) and hi == pytest.approx(step, rel=1e-9)
    # a gate: only its exit meets section 2 (a level section 1 into a tilted section 2)
    lo, hi = joint_steps({**p, "gate_width": 4e-4, "cross_tilt": 0.0, "s2_cross_tilt": 10.0})
    assert lo == pytest.approx(step + (w - 4e-4) / 2 * t, rel=1e-9)
    assert hi == pytest.approx(step + (w + 4e-4) / 2 * t, rel=1e-9)


def test_a_tilted_section_one_must_still_step_down_everywhere():
    deck = Deck(DECKS / "bulk_feeder.liggghts")
    level = line_values(gate_width=0, s2_width=1.2e-3, s2_cross_tilt=0, cross_tilt=10, n_parts=0,
                        inlet_rate=30)
    with pytest.raises(ParameterError) as err:
        resolve(deck, level)
    assert "must step down by more than" in str(err.value) and "at its least" in str(err.value)
    resolve(deck, {**level, "s2_cross_tilt": "10"})  # tilted alike: a uniform 50 um step


@pytest.mark.parametrize("given", [
    {"s2_amp_t": 1.9e-4},  # the joint opens by 1.4e-4 m, just under half a part (1.5e-4 m)
    {"s2_freq": 120, "s2_step": 1.01e-4},  # a step just over the floors' 1e-4 m apart
    {"s2_wiper_height": 3e-4},  # a wiper exactly a part's thickness high lets it pass
    {"s2_drop_to": 0.5, "s2_drop_width": 1.5e-4},  # a ledge of exactly half a part
    # the wiper's bar, one part size long, ends exactly at the outlet edge (binary fractions:
    # 0.96875 * 2^-7 + 2^-12 = 2^-7 m exactly)
    {"track_length": 0.015625, "s2_length": 0.0078125, "part_size": 0.000244140625,
     "s2_wiper_height": 4e-4, "s2_wiper_at": 0.96875},
])
def test_a_line_just_within_its_limits_passes(given):
    values = resolve(Deck(DECKS / "bulk_feeder.liggghts"), line_values(**given))
    s = section_from(values)
    v, _ = section_mesh(s)  # and prepare meshes it
    assert v[:, 0].max() == pytest.approx(s.x1, abs=TOL)
    if s.has_wiper:
        assert s.wiper_x[1] - s.wiper_x[0] == pytest.approx(float(values["part_size"]), abs=TOL)
        assert s.wiper_x[1] <= s.x1
        if "s2_wiper_at" in given:
            assert s.wiper_x[1] == s.x1  # at the edge to the bit


def test_a_wiper_just_past_the_outlet_edge_is_refused():
    given = {"track_length": 0.015625, "s2_length": 0.0078125, "part_size": 0.000244140625,
             "s2_wiper_height": 4e-4, "s2_wiper_at": 0.97}  # its bar ends 2.3e-6 m past the edge
    with pytest.raises(ParameterError) as err:
        resolve(Deck(DECKS / "bulk_feeder.liggghts"), line_values(**given))
    # the bar is one part size long
    assert f"the wiper's bar ({2**-12:g} m along the track) runs past the outlet edge" in str(err.value)


def minimal_line(**kw):
    """A line's parameters given only what has no neutral value (no drive, no gate, no tooling)."""
    return {"sections": 2, "part_size": 3e-4, "track_width": 4e-4, "s2_width": 4e-4,
            "s2_length": 5e-3, "s2_wall_height": 6e-4, "s2_step": 5e-5, **kw}


def test_check_line_takes_absent_options_as_off():
    # absent: spheres without spread, no gate, no drive, no surface forces, sines
    check_line(minimal_line())
    # a spread given alone applies to spheres: the largest (4.35e-4 m) is wider than section 2
    with pytest.raises(ParameterError, match="narrower than a part"):
        check_line(minimal_line(size_spread=0.45))


def test_joint_motion_depends_on_the_phase_difference_only():
    a = 5e-5
    p = {"freq": 100, "s2_freq": 100, "amp_n": a, "s2_amp_n": a}
    # 30 and 90 degrees: 60 apart, equal sines differ by one amplitude; 0 and 60 alike
    for phases in [(30, 90), (0, 60), (90, 30)]:
        dz, _ = joint_motion({**p, "phase": phases[0], "s2_phase": phases[1]})
        assert dz == pytest.approx(a, rel=1e-12), phases


def test_joint_motion_takes_absent_drive_values_as_zero():
    # no frequencies or phases given: one drive, the same sine for both (equal amplitudes: no gap)
    assert joint_motion({"amp_n": 5e-5, "s2_amp_n": 5e-5, "amp_t": 2e-5, "s2_amp_t": 2e-5}) == (0.0, 0.0)
    # a section's amplitude not given: it does not move
    assert joint_motion({"freq": 100, "s2_freq": 100, "s2_amp_n": 4e-5, "s2_amp_t": 3e-5}) == (4e-5, 3e-5)


def test_joint_motion_of_nearly_equal_amplitudes_in_phase():
    # in phase the gap is |a1 - a2| = 7e-14 m; the closed form a1^2 + a2^2 - 2 a1 a2 rounds to
    # -8e-25 m^2 for these two, which must count as no gap, not a domain error
    a1, a2 = 5e-5, 5.000000007e-5
    dz, dx = joint_motion({"freq": 100, "s2_freq": 100, "amp_n": a1, "s2_amp_n": a2, "phase": 0,
                           "s2_phase": 0})
    # cancellation leaves sqrt(4 eps) a1 ~ 1.5e-12 m of accuracy
    assert dz == pytest.approx(a2 - a1, abs=1e-11) and dx == 0.0


def x_stations(v):
    return np.unique(np.round(v[:, 0], 12))


@pytest.mark.parametrize("width, n", [(4.2e-4, 20), (1.2e-3, 8)])
def test_stations_are_the_fewest_uniform_ones_within_the_width_and_1_mm(width, n):
    # 8 mm: 8 / 0.42 = 19.05 -> 20 spaces of 0.4 mm; a section over 1 mm wide: 8 spaces of 1 mm
    s = section(width=width)
    xs = x_stations(section_mesh(s)[0])
    assert np.allclose(xs, np.linspace(s.x0, s.x1, n + 1), rtol=0, atol=TOL)


@pytest.mark.parametrize("times", [2.0, 1e10])
def test_a_spacing_longer_than_the_section_leaves_just_its_ends(times):
    s = section()
    xs = x_stations(section_mesh(s, spacing=times * s.length)[0])
    assert np.allclose(xs, [s.x0, s.x1], rtol=0, atol=TOL)


def areas(s, v, t):
    """Area of the floor seen from above and of the wall at +w/2, each from its own triangles."""
    c = v[t]
    on_floor = np.all(same(c[:, :, 2], s.floor_z(c[:, :, 1])), axis=1)
    on_hi = np.all(same(c[:, :, 1], s.width / 2), axis=1)
    cross = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0]) / 2
    return np.abs(cross[on_floor, 2]).sum(), np.abs(cross[on_hi, 1]).sum()


@pytest.mark.parametrize("drop_from, drop_to", [(0.26, 0.51), (0.0, 0.3), (0.5, 1.0)])
def test_the_side_drop_spans_exactly_its_fractions(drop_from, drop_to):
    # ends off the 0.4 mm stations (0.26, 0.51) and at the section's ends (0, 1)
    s = section(drop_from=drop_from, drop_to=drop_to, drop_width=2.5e-4)
    v, t = section_mesh(s)
    floor, wall = areas(s, v, t)
    span = (drop_to - drop_from) * s.length
    # m^2; vertices rounded to 1e-12 m over 8 mm: ~1e-14 m^2 (a station off moves 7e-8 m^2)
    assert floor == pytest.approx(s.length * s.width - span * (s.width - 2.5e-4), abs=1e-13)
    assert wall == pytest.approx((s.length - span) * s.wall_height, abs=1e-13)


def test_a_drop_whose_ends_round_to_one_point_is_refused():
    # drop_to > drop_from by one ulp: on the section both ends are x = 0.012 m to the bit
    s = section(drop_from=0.25, drop_to=float(np.nextafter(0.25, 1.0)), drop_width=2.5e-4)
    assert s.has_drop and s.drop_x[0] == s.drop_x[1]
    with pytest.raises(ParameterError, match="side drop does not fit"):
        section_mesh(s)


def test_a_wiper_may_stand_at_the_joint():
    s = section(wiper_height=3.5e-4, wiper_at=0.0, wiper_length=3e-4)
    v, _ = section_mesh(s)
    assert s.wiper_x[0] == s.x0
    under = v[same(v[:, 2], s.floor_z(v[:, 1]) + 3.5e-4)]
    assert np.allclose(np.unique(np.round(under[:, 0], 12)), [s.x0, s.x0 + 3e-4], rtol=0, atol=TOL)


def test_a_section_is_a_value():
    import dataclasses

    s = section(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4)
    assert s == section(drop_from=0.25, drop_to=0.5, drop_width=2.5e-4) and hash(s) == hash(section(
        drop_from=0.25, drop_to=0.5, drop_width=2.5e-4))
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.step = 0.0


def test_a_wiper_may_end_at_the_outlet_edge():
    # binary fractions: the bar ends at x1 = 2^-7 + 2^-7 m to the bit
    s = section(x0=2**-7, length=2**-7, wiper_height=3.5e-4, wiper_at=0.75, wiper_length=2**-9)
    assert s.wiper_x[1] == s.x1
    v, _ = section_mesh(s)
    upstream = v[same(v[:, 0], s.wiper_x[0]) & (v[:, 2] > s.floor_z(v[:, 1]) + TOL)]
    assert len(upstream)  # the bar is there


@pytest.mark.parametrize("x0", [0.01, 0.01 + 3e-12, 0.0123456789012])
def test_section_two_starts_where_section_one_ends(x0):
    # any track length: both meshes put the joint at the same x, to their 1e-12 m rounding
    v1, _ = track_mesh(x0, W1, 1e-3, gate_width=4.2e-4, gate_x=0.6 * x0)
    v2, _ = section_mesh(section(x0=x0))
    assert v2[:, 0].min() == pytest.approx(v1[:, 0].max(), abs=TOL)
    assert v2[:, 0].min() == pytest.approx(x0, abs=TOL)


def test_a_sections_tooling_defaults_are_the_decks():
    import dataclasses

    deck = resolve(Deck(DECKS / "bulk_feeder.liggghts"), {})
    defaults = {f.name: f.default for f in dataclasses.fields(Section)}
    for name in ("cross_tilt", "drop_from", "drop_to", "drop_width", "wiper_height", "wiper_at"):
        assert defaults[name] == float(deck[f"s2_{name}"]), name
    # section_from without s2_wiper_at: the deck's place (mid-length)
    given = {"track_length": 0.01, "s2_length": 8e-3, "s2_wiper_height": 4e-4, "part_size": 3e-4}
    assert section_from(given).wiper_at == float(deck["s2_wiper_at"])


def test_a_narrower_section_two_tilted_alike_says_the_step_its_floor_leaves():
    # each floor is tilted about its own centre line: a 1.4 mm section 1 into a 1.0 mm section 2,
    # both at 15 deg, leaves s2_step - (1.4 - 1.0) mm / 2 * tan(15 deg) = 0.1 - 0.0536 mm at
    # every y across the gate (0.9 mm), below the drives' relative normal motion (5e-5 m)
    deck = Deck(DECKS / "bulk_feeder.liggghts")
    values = line_values(track_width=1.4e-3, gate_width=9e-4, cross_tilt=15, amp_n=6e-5, s2_width=1e-3,
                         s2_cross_tilt=15, s2_step=1e-4, s2_amp_n=1e-5, n_parts=0, inlet_rate=30)
    with pytest.raises(ParameterError, match=r"s2_step=0.0001 m: .*leave a step of 4.64e-05 m at its least"):
        resolve(deck, values)


# ------------------------------------------------------------- a later section's gate
def test_a_later_gate_brings_both_walls_in_at_45_degrees_and_leaves_no_floor_beyond():
    """Section of 1.2 mm, gate 0.9 mm at 0.25 of 8 mm: both walls stand at +-0.6 mm up to
    x0 + 2 mm, at +-0.45 mm from x0 + 2.15 mm on (45 degrees: as far along as in), and on the
    lines between; no floor lies beyond them there, the whole width before."""
    s = section(width=1.2e-3, gate_width=9e-4, gate_at=0.25)
    assert s.has_gate and s.gate_x == pytest.approx((L1 + 2e-3, L1 + 2.15e-3), abs=TOL)
    v, t = section_mesh(s)
    top = -s.step + s.wall_height
    wall = v[same(v[:, 2], top)]  # the walls' top edges
    want = np.interp(wall[:, 0], [L1 + 2e-3, L1 + 2.15e-3], [6e-4, 4.5e-4])
    assert np.allclose(np.abs(wall[:, 1]), want, rtol=0, atol=TOL)
    for y in (6e-4, 4.5e-4, -6e-4, -4.5e-4):
        assert same(wall[:, 1], y).any()
    tri = v[t]
    floor = np.all(tri[:, :, 2] < top - TOL, axis=1) & (np.ptp(tri[:, :, 1], axis=1) > 0)
    past = floor & np.all(tri[:, :, 0] >= L1 + 2.15e-3 - TOL, axis=1)
    assert past.any() and np.abs(tri[past][:, :, 1]).max() == pytest.approx(4.5e-4, abs=TOL)
    before = floor & np.all(tri[:, :, 0] <= L1 + 2e-3 + TOL, axis=1)
    assert np.abs(tri[before][:, :, 1]).max() == pytest.approx(6e-4, abs=TOL)
    for e, k in edges(t).items():  # a floor quad's diagonal under a taper's foot: three faces
        if k > 2:
            (x0, y0, _), (x1, y1, _) = v[list(e)]
            assert k == 3 and abs(y1 - y0) == pytest.approx(abs(x1 - x0), abs=TOL)
            assert min(abs(y0), abs(y1)) == pytest.approx(4.5e-4, abs=TOL)


def test_a_later_gate_that_does_not_fit_is_refused():
    with pytest.raises(ParameterError, match="taper does not fit"):
        section_mesh(section(width=1.2e-3, gate_width=9e-4, gate_at=0.99))


def later_gate(**given):
    return {"sections": 3, "part_size": 3e-4, "track_width": 1.2e-3, "track_length": 4e-3,
            "s2_length": 5e-3, "s2_width": 1.2e-3, "s2_wall_height": 6e-4, "s2_step": 5e-5,
            "s2_gate_width": 6e-4, "s2_gate_at": 0.5, "s3_length": 5e-3, "s3_width": 6e-4,
            "s3_wall_height": 6e-4, "s3_step": 5e-5, **given}


def test_a_later_gate_s_exit_is_the_next_section_s_least_width():
    """Section 2 gated to 0.6 mm of 1.2 mm: a section 3 of 0.6 mm takes its exit, one narrower
    does not (the joint names the gate's width); the step is measured across that exit."""
    t = math.tan(math.radians(10.0))
    feeder = Feeder.from_values(later_gate(s3_cross_tilt=10.0))
    feeder.check()
    lo, hi = feeder.joints[1].steps  # a level section 2 into a tilted section 3 of the same width
    assert lo == pytest.approx(5e-5, rel=1e-9) and hi == pytest.approx(5e-5 + 6e-4 * t, rel=1e-9)
    with pytest.raises(ParameterError) as err:
        Feeder.from_values(later_gate(s3_width=5.9e-4)).check()
    assert "s3_width=0.00059 m is narrower than section 2's exit (0.0006 m)" in str(err.value)


@pytest.mark.parametrize("given, words", [
    ({"s2_gate_width": 2.9e-4}, "s2_gate_width=0.00029 m is narrower than a part (0.0003 m"),
    ({"s2_gate_width": 1.2e-3}, "s2_gate_width=0.0012 m must be narrower than s2_width=0.0012 m"),
    ({"s2_gate_at": 0.95}, "s2_gate_at=0.95: the gate's 45 degree taper (0.0003 m long) runs past"),
    ({"s2_drop_from": 0.2, "s2_drop_to": 0.6, "s2_drop_width": 4e-4},
     "s2_drop_to: the side drop reaches past the gate (s2_gate_at=0.5)"),
    ({"s2_slot_from": 0.45, "s2_slot_to": 0.55, "s2_slot_width": 2e-4},
     "s2_slot_to: the slot reaches past the gate (s2_gate_at=0.5)"),
])
def test_a_later_gate_s_refusals_name_its_parameter(given, words):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values(later_gate(**given)).check()
    assert words in str(err.value) and "\n" not in str(err.value)


def test_tools_before_a_later_gate_pass():
    Feeder.from_values(later_gate(s2_drop_from=0.1, s2_drop_to=0.5, s2_drop_width=4e-4)).check()


def test_a_wiper_past_a_later_gate_spans_its_narrowed_walls():
    """A wiper's bar stands between the walls where it is: past a 0.9 mm gate on a 1.2 mm
    section, +-0.45 mm; before it, +-0.6 mm (its underside's four corners)."""
    for at, half in ((0.5, 4.5e-4), (0.1, 6e-4)):
        s = section(width=1.2e-3, gate_width=9e-4, gate_at=0.25, wiper_height=3.5e-4, wiper_at=at,
                    wiper_length=3e-4)
        v, _ = section_mesh(s)
        w0, w1 = s.wiper_x
        bar = v[(v[:, 0] >= w0 - TOL) & (v[:, 0] <= w1 + TOL)]
        under = bar[same(bar[:, 2], s.floor_z(bar[:, 1]) + 3.5e-4)]
        assert len(under) == 4 and np.allclose(np.abs(under[:, 1]), half, rtol=0, atol=TOL)
    Feeder.from_values(later_gate(s2_wiper_height=4e-4, s2_wiper_at=0.6)).check()


@pytest.mark.parametrize("given, words", [
    ({"gate_width": 2.9e-4}, "gate_width=0.00029 m is narrower than a part (0.0003 m across)"),
    ({"gate_width": 1.2e-3}, "gate_width=0.0012 m must be narrower than track_width=0.0012 m"),
    # 4 mm, the taper 0.3 mm long from 3.8 mm: past section 1's end, the joint, not the outlet
    ({"gate_width": 6e-4, "gate_at": 0.95}, "gate_at=0.95: the gate's 45 degree taper (0.0003 m long) "
                                            "runs past the end of section 1; lower gate_at"),
])
def test_section_one_s_gate_has_the_same_rules_as_a_later_one(given, words):
    """One rule for every section's gate (LinearSection.check_gate), section 1's named by the
    bulk deck's names and measured to the joint in a line."""
    from vibrofeed.decks import Deck
    from vibrofeed.parameters import resolve

    line = {"sections": 2, "part_size": 3e-4, "track_width": 1.2e-3, "track_length": 4e-3, "s2_length": 5e-3,
            "s2_width": 1.2e-3, "s2_wall_height": 6e-4, "s2_step": 5e-5, **given}
    values = {k: str(v) for k, v in line.items()}
    with pytest.raises(ParameterError) as err:
        resolve(Deck.find("bulk_feeder"), {**values, "n_parts": "0", "inlet_rate": "10"})
    assert words in str(err.value) and "\n" not in str(err.value)
