"""The mesh element (vibrofeed.feeders.mesh_element): a track from CAD as an STL, placed at its
joint, its path coordinate, its joint, its commands in the deck and its description, against
geometry by hand; and every way an STL can be wrong refused in one line naming the element
and the key, before anything runs.

The track: an S-bend channel 1.2 mm wide, walls 1 mm, whose floor's centre line runs
(0,0) -> (4,0) -> (8,3) -> (12,3) mm (legs of 4, 5 and 4 mm: 13 mm of path, 12 mm along x),
written in millimetres in a CAD frame turned by 90 degrees and moved by (10, 20, 5) mm, after a
4 mm linear section and 50 um below it."""

import math

import numpy as np
import pytest

from helpers import REPO, channel
from vibrofeed.decks import Deck
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.deck import line_files
from vibrofeed.feeders.description import read
from vibrofeed.feeders.mesh_element import MeshElement, path_text
from vibrofeed.mesh import write_stl
from vibrofeed.parameters import resolve

PLAN = np.array([(0, 0, 0), (4, 0, 0), (8, 3, 0), (12, 3, 0)], dtype=float)  # mm, the line's frame


def cad(points):
    """Points of the line's frame (mm) in the CAD frame: turned by +90 degrees, moved by (10, 20, 5)."""
    p = np.asarray(points, dtype=float)
    return np.column_stack([10 - p[:, 1], 20 + p[:, 0], 5 + p[:, 2]])


PATH = cad(PLAN)


def values(stl, path=PATH, unit=1e-3, **more):
    return {"sections": 2, "part_size": 3e-4, "track_length": 4e-3, "track_width": 1.2e-3,
            "wall_height": 1e-3, "freq": 100, "amp_t": 3.5e-5, "amp_n": 5e-5, "s2_kind": 2,
            "s2_file": str(stl), "s2_unit": unit, "s2_path": path_text(path), "s2_width": 1.2e-3,
            "s2_step": 5e-5, "s2_freq": 100, "s2_amp_t": 1e-4, "s2_amp_n": 5e-5, "s2_phase": -20,
            **more}


@pytest.fixture
def stl(tmp_path):
    path = tmp_path / "s_bend.stl"
    write_stl(*channel(PATH, 1.2, 1.0), path, "s_bend")
    return path


def test_the_mesh_is_placed_with_its_path_starting_at_the_joint_along_x(stl):
    f = Feeder.from_values(values(stl))
    e = f.elements[1]
    assert isinstance(e, MeshElement) and f.further_elements == (e,) and f.sections == 2
    want = np.column_stack([4e-3 + PLAN[:, 0] * 1e-3, PLAN[:, 1] * 1e-3, np.full(4, -5e-5)])
    assert np.abs(e.points - want).max() <= 1e-15
    assert e.path_length == pytest.approx(13e-3, abs=1e-15)
    assert (e.x0, e.x1) == (4e-3, pytest.approx(16e-3, abs=1e-15))
    assert f.bounds == [(0.0, 4e-3), (4e-3, pytest.approx(17e-3, abs=1e-15))]
    assert f.path_end == pytest.approx(17e-3, abs=1e-15) and f.catch_x == [0.0, 4e-3]
    assert f.mesh_start == 4e-3 and e.exit_level == pytest.approx(5e-5, abs=1e-18)
    assert e.exit_direction == (1.0, 0.0, 0.0)
    # its mesh placed alike (an STL holds single precision: 1e-9 m at 30 mm)
    v, _ = e.mesh()
    assert v[:, 0].min() == pytest.approx(4e-3, abs=1e-8) and v[:, 0].max() == pytest.approx(16e-3, abs=1e-8)
    assert v[:, 2].min() == pytest.approx(-5e-5, abs=1e-8) and e.lowest == pytest.approx(-5e-5, abs=1e-8)
    assert v[:, 2].max() == pytest.approx(-5e-5 + 1e-3, abs=1e-8)  # the walls' tops
    # the walls stand 0.6 mm either side of the path: at the start y = +-0.6 mm, at the end 3 +- 0.6 mm
    assert v[:, 1].min() == pytest.approx(-0.6e-3, abs=1e-8)
    assert v[:, 1].max() == pytest.approx(3.6e-3, abs=1e-8)
    f.check()


def test_the_joint_steps_down_onto_the_mesh_floor_by_the_step(stl):
    f = Feeder.from_values(values(stl))
    j = f.joints[0]
    assert j.at == 4e-3
    # section 1 and the mesh both level across: 50 um at both ends of the exit
    assert j.steps == (pytest.approx(5e-5, abs=1e-9), pytest.approx(5e-5, abs=1e-9))
    # one frequency: normal |5e-5 - 5e-5 e^{-20 deg}| = 2 a sin(10 deg), along |1e-4 - 3.5e-5|
    dz, dx = j.motion
    assert dz == pytest.approx(2 * 5e-5 * math.sin(math.radians(10)), rel=1e-12)
    assert dx == pytest.approx(6.5e-5, rel=1e-12)
    with pytest.raises(ParameterError, match=r"^s2_step=1e-05 m: the joint must step down by more than"):
        Feeder.from_values(values(stl, s2_step=1e-5)).check()


def test_the_path_coordinate_is_the_arc_length_along_the_path(stl):
    f = Feeder.from_values(values(stl))
    floor = -5e-5
    side = np.array([-0.6, 0.8, 0.0])  # across the diagonal leg (4, 3)/5, to its left
    mid = np.array([10e-3, 1.5e-3, floor])  # the diagonal leg's middle: 4 + 2.5 mm of path
    points = np.array([
        mid + [0, 0, 1.5e-4],  # a part on the floor there
        mid + 0.4e-3 * side + [0, 0, 1.5e-4],  # against its left wall: the same place along
        [6e-3, -0.3e-3, floor + 1.5e-4],  # on the first leg, 2 mm along
        [17e-3, 3e-3, floor],  # 1 mm past the path's end, on along its last leg
        mid + 0.85e-3 * side,  # within half the width and a part (0.9 mm) of the path
        mid + 0.95e-3 * side,  # beyond it: off the track
        [10e-3, 1.5e-3, floor - 2e-3],  # fallen 2 mm below it
    ])
    s = f.line_coordinate(points)
    want = [10.5e-3, 10.5e-3, 6e-3, 18e-3, 10.5e-3]
    assert np.abs(s[:5] - want).max() <= 1e-15
    assert np.isnan(s[5:]).all()
    # by section: the mesh is section 2 from the joint to the path's end; past it, none
    assert f.section_at(s[:4]).tolist() == [1, 1, 1, -1]


def test_its_deck_commands_are_a_sine_drive_and_its_placed_mesh_numbers(stl):
    files = line_files(Feeder.from_values(values(stl)))
    d = files["line_derived.in"]
    low = float(d.split("variable s2_low equal ")[1].split("\n")[0])
    assert low == pytest.approx(-5e-5, abs=1e-8)
    assert float(d.split("variable s2_length equal ")[1].split("\n")[0]) == pytest.approx(12e-3, abs=1e-15)
    # the box holds its bend: 3.6 mm across at most, then a part
    y = d.split("variable box_y equal (v_half_w+")[1].split("+")[0]
    assert float(y) == pytest.approx(3.6e-3, abs=1e-8)
    assert f"variable box_y equal (v_half_w+{y}+abs(v_half_w-{y}))/2+v_part_size" in d
    assert "variable outlet_x equal v_track_length+v_s2_length" in d
    assert "variable s2_catch equal v_s2_low-(v_s2_amp_n+2*v_r_ext)" in d
    m = files["line_motion.in"]
    assert "fix s2_shake_t all move/mesh mesh track_s2 wiggle amplitude ${s2_amp_t} 0 0" in m
    assert "fix s2_shake_n all move/mesh mesh track_s2 viblin axis 0 0 1" in m


def test_a_description_of_a_mesh_element_becomes_the_decks_words_and_numbers(tmp_path, stl):
    (tmp_path / "cad").mkdir()
    stl.rename(tmp_path / "cad" / "s_bend.stl")
    text = _description('"cad/s_bend.stl"', '"mm"', PATH.tolist())
    (tmp_path / "bend.toml").write_text(text)
    d = read(tmp_path / "bend.toml")
    assert d.kinds == ["linear", "mesh"]
    v = d.values
    assert v["s2_kind"] == "2" and v["s2_unit"] == "0.001" and v["s2_step"] == "5e-05"
    assert v["s2_file"] == str((tmp_path / "cad" / "s_bend.stl").resolve())
    assert np.array_equal(np.array(v["s2_path"].split(","), dtype=float), PATH.ravel())
    assert d.aliases["element.2.drive.amp_t"] == "s2_amp_t" and d.aliases["element.2.path"] == "s2_path"
    deck = Deck.find(tmp_path / "bend.toml")
    for name in ("s2_kind", "s2_file", "s2_unit", "s2_path", "s2_width", "s2_step", "s2_amp_t"):
        assert name in deck.tunables
    assert "s2_length" not in deck.tunables  # (its run along x is its mesh's, written for the run)
    resolved = resolve(deck, {"element.2.drive.amp_t": "8e-5"})
    f = Feeder.from_values(resolved)
    assert f.elements[1].drive.amp_t == 8e-5 and f.path_end == pytest.approx(17e-3, abs=1e-15)
    f.check()


def _description(file, unit, path, kinds=("mesh",)):
    out = ('[parts]\nsize = 3e-4\n[supply]\nn_parts = 10\n[[element]]\nkind = "linear"\nlength = 0.004\n'
           'width = 1.2e-3\ndrive = { freq = 100, amp_t = 3.5e-5, amp_n = 5e-5 }\n')
    for kind in kinds:
        if kind == "mesh":
            out += (f'[[element]]\nkind = "mesh"\nfile = {file}\nunit = {unit}\npath = {path}\n'
                    'width = 1.2e-3\nstep = 5e-5\ndrive = { freq = 100, amp_t = 1e-4, amp_n = 5e-5 }\n')
        else:
            out += ('[[element]]\nkind = "linear"\nlength = 0.002\nwidth = 1.2e-3\nstep = 5e-5\n'
                    'drive = { freq = 100, amp_t = 1e-4, amp_n = 5e-5 }\n')
    return out


@pytest.mark.parametrize("file, unit, path, kinds, words", [
    ('"s.stl"', '"cm"', [[0, 0, 0], [1, 0, 0]], ("mesh",),
     'element 2: unit = "cm": the STL\'s unit is "mm" (as CAD exports) or "m"'),
    ('"s.stl"', '"mm"', [[0, 0, 0]], ("mesh",), "element 2: path must be a list of at least two points"),
    ('"s.stl"', '"mm"', [[0, 0], [1, 0]], ("mesh",), "element 2: path must be a list of at least two points"),
    ('"a b/s.stl"', '"mm"', [[0, 0, 0], [1, 0, 0]], ("mesh",), "element 2: file: "),
])
def test_a_description_slip_on_a_mesh_element_is_one_line(tmp_path, file, unit, path, kinds, words):
    (tmp_path / "f.toml").write_text(_description(file, unit, path, kinds))
    with pytest.raises(ParameterError) as err:
        read(tmp_path / "f.toml")
    assert words in str(err.value) and "\n" not in str(err.value)


def test_a_mesh_element_without_its_file_is_refused(tmp_path):
    text = _description('"s.stl"', '"mm"', [[0, 0, 0], [1, 0, 0]]).replace('file = "s.stl"\n', "")
    (tmp_path / "f.toml").write_text(text)
    with pytest.raises(ParameterError, match="element 2 has no file: every mesh element states its own"):
        read(tmp_path / "f.toml")


def _refused(stl, words, **change):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values({**values(stl), **change}).check()
    message = str(err.value)
    assert "\n" not in message and words in message, message
    return message


def test_an_stl_open_where_parts_would_fall_through_is_refused(tmp_path):
    # the diagonal leg's floor missing left of the path, then both halves: its mitre on the
    # turn's inner side starts 0.24 tan(36.87 / 2) = 0.08 mm before the corner at 0.24 mm across,
    # so the first point looked at past it (every 13/87 mm from half a spacing: 3.96 mm) misses
    for holes in ([(1, 1)], [(1, -1), (1, 1)]):
        path = tmp_path / "holed.stl"
        write_stl(*channel(PATH, 1.2, 1.0, holes=holes), path, "holed")
        _refused(path, "s2_file: the floor has a hole at 3.96 mm along the path (near "
                       "10, 23.96, 5 in the STL), +0.24 mm across: parts would fall through")


def test_an_stl_with_inconsistent_normals_is_refused(tmp_path):
    path = tmp_path / "mixed.stl"
    write_stl(*channel(PATH, 1.2, 1.0, flipped=[5]), path, "mixed")
    _refused(path, "s2_file: the mesh's triangles are not wound alike (inconsistent "
                   "normals)")


def test_an_stl_whose_floor_faces_down_is_refused(tmp_path):
    v, t = channel(PATH, 1.2, 1.0)
    path = tmp_path / "down.stl"
    write_stl(v, t[:, ::-1], path, "down")  # every face wound the other way: consistent, but down
    _refused(path, "s2_file: the floor's normals face down under the path at 0.")


def test_an_stl_in_the_wrong_unit_is_refused(stl):
    # millimetres read as metres: a 13 m path, a mesh 12 m across (its run along x)
    m = _refused(stl, "s2_unit: the mesh is 12 m across and its path 13 m long at 1 m "
                      "per unit; a feeder's track is 1 mm to 1 m: is the unit mm?", s2_unit=1.0)
    assert m.startswith("s2_unit: ")
    _refused(stl, "s2_unit: 0.01 m per unit", s2_unit=0.01)


def test_a_path_that_leaves_the_mesh_is_refused(stl):
    # the last leg swerves 3 mm off to the left: past the wall, over nothing
    off = cad([(0, 0, 0), (4, 0, 0), (8, 3, 0), (12, 6, 0)])
    _refused(stl, "s2_path: the path leaves the mesh at ", s2_path=path_text(off))
    # above the floor: the path's points 0.4 mm up (more than half a part)
    _refused(stl, "s2_path: the path lies +0.4 mm above the floor at ",
             s2_path=path_text(PATH + [0, 0, 0.4]))


def test_a_mesh_beyond_its_path_or_before_its_joint_is_refused(stl):
    short = cad([(0, 0, 0), (4, 0, 0), (8, 3, 0), (10, 3, 0)])
    _refused(stl, "s2_path: the mesh reaches 2 mm beyond its path's end along x",
             s2_path=path_text(short))
    late = cad([(1, 0, 0), (4, 0, 0), (8, 3, 0), (12, 3, 0)])
    _refused(stl, "s2_path: the mesh reaches 1 mm back past its joint",
             s2_path=path_text(late))


def test_an_stl_that_cannot_be_read_is_refused(tmp_path, stl):
    _refused(stl, f"s2_file: no such file: {tmp_path / 'none.stl'}",
             s2_file=str(tmp_path / "none.stl"))
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"\x00\x01 not an STL")
    _refused(stl, f"s2_file: {bad} holds no triangles", s2_file=str(bad))
    with pytest.raises(ParameterError, match=r"^s2_path: give at least two points"):
        Feeder.from_values(values(stl, s2_path="1,2,3"))


def test_a_mesh_element_followed_by_another_ends_where_it_started_across(stl):
    # the S-bend ends 3 mm across: the next element would start beside the line
    more = {"sections": 3, "s3_length": 2e-3, "s3_width": 1.2e-3, "s3_wall_height": 1e-3, "s3_step": 5e-5,
            "s3_freq": 100, "s3_amp_t": 1e-4, "s3_amp_n": 5e-5}
    _refused(stl, "s2_path: an element follows it, so its path must end where it "
                  "started across, heading as it started (the next element starts there, along it); it "
                  "ends +3 mm across, turned 0 deg", **more)


def test_the_example_cad_feeder_describes_its_s_bend():
    deck = Deck.find(REPO / "feeders" / "cad_curved.toml")
    # (its STL is made by feeders/cad/make_curved_track.py: the path alone is read here)
    f = Feeder.from_values({name: v.default for name, v in deck.tunables.items()})
    e = f.elements[1]
    assert [x.kind for x in f.elements] == ["linear", "mesh"] and e.unit == 1e-3
    # 4 mm in, two 30 degree arcs of 20 mm, 4 mm out: 8 + 2 (20 pi / 6) mm; x: 8 + 2 (20 sin 30) mm
    # (the arcs by chords 5 degrees apart: 2 R sin 2.5 deg each)
    chords = 12 * 2 * 20 * math.sin(math.radians(2.5))
    assert e.path_length == pytest.approx((8 + chords) * 1e-3, rel=1e-9)
    assert e.x1 - e.x0 == pytest.approx(28e-3, abs=1e-9)
    assert e.points[-1, 1] == pytest.approx(-2 * 20e-3 * (1 - math.cos(math.radians(30))), abs=1e-9)
