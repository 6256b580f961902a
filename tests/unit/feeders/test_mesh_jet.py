"""An air jet on a mesh element (vibrofeed.feeders.mesh_element, vibrofeed.engine.jets), against
geometry by hand: its camera senses by path coordinate, its block is six planes turned with the
path at the camera, it blows across to the path's left; its slips are one line naming the key.

The line: a 4 mm linear section, then a detour channel from CAD 1.2 mm wide whose floor's centre
line runs (0,0) -> (4,0) -> (8,3) -> (12,3) -> (16,0) -> (20,0) mm (legs of 4, 5, 4, 5 and 4 mm,
22 mm of path), 50 um below section 1. A jet at 0.3 of it senses at 6.6 mm of path: 2.6 mm down
the leg (4, 3)/5, plan (6.08, 1.56) mm, the deck's (10.08, 1.56) mm; along the path there (0.8,
0.6), to its left (-0.6, 0.8)."""

import math

import numpy as np
import pytest

from helpers import DETOUR, detour_stl
from vibrofeed.engine.jets import Jets
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.mesh_element import KEYS, deck_name, path_text

PLAN = DETOUR
FLOOR = -5e-5
BOX = {"shape": 3, "part_size": 4e-4, "part_width": 3e-4, "part_thickness": 1e-4}
# lengthwise on the leg (4, 3)/5, turned 36.87 degrees about z: marked face (+z) up, or turned
# over about its long axis, face down (quaternions w, x, y, z)
HALF = math.atan2(3, 4) / 2
UP = (math.cos(HALF), 0.0, 0.0, math.sin(HALF))
DOWN = (0.0, math.cos(HALF), math.sin(HALF), 0.0)
TOL = 1e-12


@pytest.fixture
def stl(tmp_path):
    return detour_stl(tmp_path)


def values(stl, **more):
    return {"sections": 2, **BOX, "track_length": 4e-3, "track_width": 1.2e-3, "wall_height": 1e-3,
            "freq": 100, "amp_t": 3.5e-5, "amp_n": 5e-5, "s2_kind": 2, "s2_file": str(stl),
            "s2_unit": 1e-3, "s2_path": path_text(PLAN), "s2_width": 1.2e-3, "s2_step": 5e-5,
            "s2_freq": 100, "s2_amp_t": 1e-4, "s2_amp_n": 2e-5, "s2_jet_force": 2e-6, "s2_jet_at": 0.3,
            "s2_jet_keep": "up", "s2_jet_mode": "ideal", **more}


def test_its_keys_deck_names_and_station(stl):
    assert {key[1] for key in KEYS if key[0] == "jet"} == {
        "force", "at", "keep", "delay", "duration", "offset", "length", "angle", "mode", "headway"}
    assert deck_name(3, ("jet", "keep")) == "s3_jet_keep"
    f = Feeder.from_values(values(stl))
    f.check()
    e = f.elements[1]
    assert e.jet.force == 2e-6 and e.jet.mode == "ideal" and str(e.jet.keep).startswith("up")
    assert f.has_jets
    assert e.sensing == pytest.approx(4e-3 + 6.6e-3, abs=1e-15)  # a path coordinate
    (st,) = [s for s in f.stations if s.kind == "jet"]
    # one part size (0.4 mm) centred on the camera, along the path, over section 2
    assert (st.start, st.end, st.section) == (pytest.approx(10.4e-3, abs=1e-15),
                                              pytest.approx(10.8e-3, abs=1e-15), 2)


def test_its_block_is_turned_with_the_path_at_the_camera(stl):
    f = Feeder.from_values(values(stl, s2_jet_length=1e-3, s2_jet_offset=2e-4, s2_jet_angle=60))
    e, part = f.elements[1], f.part
    c, t, n = e.jet_frame(part.size)
    # the block's centre 0.2 mm past the camera: 6.8 mm of path, 2.8 mm down the leg
    assert np.abs(c - [4e-3 + 4e-3 + 2.24e-3, 1.68e-3, FLOOR]).max() <= TOL
    assert np.abs(t - [0.8, 0.6, 0.0]).max() <= TOL and np.abs(n - [-0.6, 0.8, 0.0]).max() <= TOL
    planes = e.jet_planes(part)
    inside = np.array([c + [0.0, 0.0, 1e-4]])  # just above the floor at the block's centre
    half_w = 0.6e-3 + 2 * part.widest
    probes = {  # just inside and just outside each face, along its normal
        "back": c - 0.5e-3 * t, "front": c + 0.5e-3 * t, "right": c - half_w * n, "left": c + half_w * n}
    def within(p):
        return all(np.dot(p - q, m) >= 0 for q, m in planes)
    assert within(inside[0])
    for name, face in probes.items():
        way = (face - c) / np.linalg.norm(face - c)
        assert within(face - 1e-6 * way + [0, 0, 1e-4]), name
        assert not within(face + 1e-6 * way + [0, 0, 1e-4]), name
    bottom = c[2] - e.drive.amp_n - part.widest
    assert within(np.array([c[0], c[1], bottom + 1e-7])) and not within(np.array([c[0], c[1], bottom - 1e-7]))
    # its top a part above the channel's walls (1 mm: higher than the tools' two part sizes,
    # 0.8 mm), so that a part blown up is pushed until it clears them
    top = FLOOR + 1e-3 + e.drive.amp_n + part.widest
    assert planes[5][0][2] == pytest.approx(top, abs=1e-12)
    assert e.height_across(c, t, 0.6e-3) == pytest.approx(FLOOR + 1e-3, abs=1e-12)
    assert e.height_across(c, t, 0.5e-3) == pytest.approx(FLOOR, abs=1e-12)  # the floor only
    a = math.radians(60)
    want = [-0.6 * math.cos(a), 0.8 * math.cos(a), math.sin(a)]  # a unit vector, to 1e-15
    assert np.allclose(e.jet_direction(), want, rtol=0, atol=1e-15)


def test_its_deck_commands_are_six_planes_their_intersection_and_the_turned_force(stl):
    f = Feeder.from_values(values(stl))
    e = f.elements[1]
    lines = e.jet_commands(f.part, origin=(0.0, 0.0, 0.0))
    planes = [line for line in lines if " plane " in line]
    assert len(planes) == 6 and all(line.endswith("units box") for line in planes)
    assert "region s2_jet intersect 6 s2_jet_1 s2_jet_2 s2_jet_3 s2_jet_4 s2_jet_5 s2_jet_6" in lines
    assert "variable s2_jet_on atom 0" in lines  # ideal: the sensed body's atoms only
    fx = next(line for line in lines if line.startswith("variable s2_jet_fx"))
    assert fx.endswith("*cos(v_s2_jet_angle*PI/180)*-0.6)") or "*-0.6" in fx  # its left, x
    assert "fix s2_jet s2_jet_parts addforce v_s2_jet_fx v_s2_jet_fy v_s2_jet_fz region s2_jet" in lines
    assert lines.index("group s2_jet_parts subtract all all") < lines.index(  # created empty first
        "fix s2_jet s2_jet_parts addforce v_s2_jet_fx v_s2_jet_fy v_s2_jet_fz region s2_jet")
    # shifted with the line's origin (after a bowl)
    moved = e.jet_commands(f.part, origin=(1.0, 2.0, 3.0))
    first, shifted = planes[0].split(), next(line for line in moved if " plane " in line).split()
    assert [float(shifted[i]) - float(first[i]) for i in (3, 4, 5)] == pytest.approx([1.0, 2.0, 3.0],
                                                                                     abs=1e-12)


def test_the_driver_senses_a_part_crossing_the_camera_along_the_path(stl):
    f = Feeder.from_values(values(stl))
    jets = Jets(f)
    (s,) = jets.stations
    assert s.x_sense == pytest.approx(10.6e-3, abs=1e-15) and s.section == 2
    assert np.allclose(s.tangent, (0.8, 0.6, 0.0), rtol=0, atol=TOL)
    leg = np.array([0.8, 0.6, 0.0])
    start = np.array([8e-3, 0.0, FLOOR + 5e-5])  # the leg's start in the deck's frame (plan (4, 0))

    def frame(ids, arcs, q):  # parts on the diagonal leg, ``arcs`` [m] down it
        return {"id": np.asarray(ids), "position": start + np.outer(arcs, leg),
                "orientation": np.asarray(q, dtype=float).reshape(len(ids), 4)}

    assert jets.step(None, 0.0, frame([1, 2], [2.5e-3, 2.4e-3], [DOWN, UP])) == (["unfix s2_jet"], None)
    # both cross 2.6 mm down the leg between 0 and 10 ms, lengthwise along it: the face-down one
    # is fired at, at its crossing (2.5 -> 2.7 mm: halfway, 5 ms), the face-up one is not (its
    # long axis 37 degrees off x: judged along the path, not along x)
    commands, table = jets.step(None, 0.01, frame([1, 2], [2.7e-3, 2.8e-3], [DOWN, UP]))
    assert table["id"].tolist() == [1] and table["time"] == pytest.approx([0.005], abs=1e-12)
    assert commands[:2] == ["group s2_jet_parts delete", "group s2_jet_parts id -1:-1"]  # (no atoms given)
    assert commands[2].startswith("variable s2_jet_on atom")
    assert commands[3] == "fix s2_jet s2_jet_parts addforce v_s2_jet_fx v_s2_jet_fy v_s2_jet_fz region s2_jet"
    # their x (10.0 -> 10.16 mm) never reaches the camera's path coordinate (10.6 mm): sensed
    # along x, as on a straight section, neither would have crossed
    assert start[0] + 2.8e-3 * 0.8 < s.x_sense


@pytest.mark.parametrize("change, words", [
    ({"s2_jet_at": 0.999, "s2_jet_length": 1e-3},
     "s2_jet_offset=0 m, s2_jet_length=0.001 m: the jet's block"),
    ({"s2_jet_keep": "up|down|side|end"}, "s2_jet_keep=\"up|down|side|end\" keeps every state"),
    ({"s2_jet_angle": 95}, "s2_jet_angle=95 deg must be in [0, 90]"),
    ({"s2_jet_mode": "spray"}, "s2_jet_mode=spray must be region or ideal"),
    ({"shape": 0}, "a jet sorts parts by their orientation, and spheres (shape 0) have none"),
])
def test_a_mesh_jets_slips_are_one_line_naming_the_key(stl, change, words):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values(values(stl, **change)).check()
    assert words in str(err.value) and "\n" not in str(err.value)


def test_its_throw_is_bounded_by_its_block_and_duration(stl):
    """Blowing straight across (angle 0) the bound is hand-computable, as a linear section's: the
    whole force for the duration or across the block (the right wall to two part sizes past the
    left one), then a fall from the block's top to a part below its bottom."""
    f = Feeder.from_values(values(stl, s2_jet_angle=0, s2_jet_duration=0.02))
    e, part = f.elements[1], f.part
    mass, g, w = 1e-8, 9.81, part.widest
    across = 1.2e-3 + 2 * w
    height = 1e-3 + 2 * 2e-5 + 2 * w  # the walls (1 mm), the normal stroke both ways, a part
    push = 2e-6 / mass
    speed = min(push * 0.02, (2 * push * across) ** 0.5)
    fall = (2 * g * (height + w)) ** 0.5 / g
    got = e.jet_throw(part, mass, g)
    assert got[0] == pytest.approx(speed, rel=1e-12)
    assert got[1] == pytest.approx(2 * w + speed * fall, rel=1e-12)


def test_a_mesh_jet_that_would_throw_parts_past_what_check_accepts_is_warned_of(tmp_path, stl,
                                                                                monkeypatch):
    from vibrofeed.decks import Deck
    from vibrofeed.errors import ParameterWarning
    from vibrofeed.parameters import resolve

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    text = ('[parts]\nshape = "box"\nsize = 4e-4\nwidth = 3e-4\nthickness = 1e-4\n[supply]\nn_parts = 5\n'
            '[[element]]\nkind = "linear"\nlength = 0.004\nwidth = 1.2e-3\n'
            'drive = { freq = 100, amp_t = 3.5e-5, amp_n = 5e-5 }\n'
            f'[[element]]\nkind = "mesh"\nfile = "{stl.name}"\nunit = "mm"\npath = {PLAN.tolist()}\n'
            'width = 1.2e-3\nstep = 5e-5\ndrive = { freq = 100, amp_t = 1e-4, amp_n = 2e-5 }\n'
            'jet = { force = FORCE, at = 0.3, keep = "up" }\n')
    path = tmp_path / "f.toml"
    path.write_text(text.replace("FORCE", "1e-3"))  # hundreds of weights
    with pytest.warns(ParameterWarning, match=r"element\.2\.jet\.force=0\.001 N .* may throw"):
        resolve(Deck.find(path), {})
    import warnings

    path.write_text(text.replace("FORCE", "1e-6"))  # a few weights: no word
    with warnings.catch_warnings():
        warnings.simplefilter("error", ParameterWarning)
        resolve(Deck.find(path), {})
