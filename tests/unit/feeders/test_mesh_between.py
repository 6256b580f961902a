"""A mesh element with an element after it, and its tooling (vibrofeed.feeders.mesh_element), against
geometry by hand.

The line: a 4 mm linear section, then a detour channel from CAD 1.2 mm wide (walls 1 mm) whose
floor's centre line runs (0,0) -> (4,0) -> (8,3) -> (12,3) -> (16,0) -> (20,0) mm (legs of 4, 5,
4, 5 and 4 mm: 22 mm of path for 20 mm along x, back on the line's centre line heading +x),
50 um below section 1; then a 2 mm linear section 50 um below the detour's end. Along the path
the third element lies 2 mm further than along x."""

import math

import numpy as np
import pytest

from helpers import DETOUR, channel, detour_stl
from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.deck import line_files
from vibrofeed.feeders.description import read
from vibrofeed.feeders.mesh_element import TOOL_SINK, TOOL_TOP, path_text
from vibrofeed.mesh import write_stl

PLAN = DETOUR
FLOOR = -5e-5  # the detour's floor [m]
SIZE = 3e-4  # the parts' size [m]


@pytest.fixture
def stl(tmp_path):
    return detour_stl(tmp_path)


def values(stl, **more):
    return {"sections": 3, "part_size": SIZE, "track_length": 4e-3, "track_width": 1.2e-3,
            "wall_height": 1e-3, "freq": 100, "amp_t": 3.5e-5, "amp_n": 5e-5,
            "s2_kind": 2, "s2_file": str(stl), "s2_unit": 1e-3, "s2_path": path_text(PLAN),
            "s2_width": 1.2e-3, "s2_step": 5e-5, "s2_freq": 100, "s2_amp_t": 1e-4, "s2_amp_n": 5e-5,
            "s3_length": 2e-3, "s3_width": 1.2e-3, "s3_wall_height": 1e-3, "s3_step": 5e-5,
            "s3_freq": 100, "s3_amp_t": 1e-4, "s3_amp_n": 5e-5, **more}


def test_the_element_after_a_mesh_lies_further_along_the_path_than_along_x(stl):
    f = Feeder.from_values(values(stl))
    f.check()
    mesh, third = f.elements[1], f.elements[2]
    assert (mesh.x0, mesh.x1) == (4e-3, pytest.approx(24e-3, abs=1e-15))
    assert mesh.path_length == pytest.approx(22e-3, abs=1e-15)
    assert (third.x0, third.x1) == (pytest.approx(24e-3, abs=1e-15), pytest.approx(26e-3, abs=1e-15))
    assert third.level == pytest.approx(1e-4, abs=1e-18)  # two steps of 50 um
    assert f.offsets == [0.0, 0.0, pytest.approx(2e-3, abs=1e-15)]
    assert f.path_is_x is False  # (the feed-rate table's sections: along the path, not x)
    want = [(0.0, 4e-3), (4e-3, 26e-3), (26e-3, 28e-3)]
    assert np.abs(np.array(f.bounds) - want).max() <= 1e-15
    assert f.path_end == pytest.approx(28e-3, abs=1e-15)
    assert f.catch_x == [0.0, 4e-3, pytest.approx(24e-3, abs=1e-15)]  # (the deck's x: by x a reject falls)
    # the joint from the mesh: its floor (level) 50 um above the third's at both ends of its exit
    j = f.joints[1]
    assert j.steps == (pytest.approx(5e-5, abs=1e-9), pytest.approx(5e-5, abs=1e-9))
    derived = line_files(f)["line_derived.in"]
    assert "variable outlet_x equal v_track_length+v_s2_length+v_s3_length" in derived


def test_the_path_coordinate_runs_on_over_the_elements_after_the_mesh(stl):
    f = Feeder.from_values(values(stl))
    up = [0.0, 0.0, 1.5e-4]
    points = np.array([
        [6e-3, 0.0, FLOOR],  # the detour's first leg, 2 mm along its path
        [22e-3, 0.0, FLOOR],  # its last leg: 18 + 2 mm of path
        [24.5e-3, 0.0, FLOOR - 5e-5],  # the third section, 0.5 mm on: 24.5 + 2 mm
        [25.8e-3, 0.3e-3, FLOOR - 5e-5],  # ... near its end, off-centre
        [24.5e-3, 0.0, FLOOR - 3e-3],  # fallen below it
    ]) + up
    s = f.line_coordinate(points)
    assert np.abs(s[:4] - [6e-3, 24e-3, 26.5e-3, 27.8e-3]).max() <= 1e-15
    assert np.isnan(s[4])
    assert f.section_at(s[:4]).tolist() == [1, 1, 2, 2]
    # where a reject fell, as its x tells: on the first diagonal leg at x 10 mm (plan 6 mm, 2.5 mm
    # into the 5 mm leg: 6.5 mm of path), on the third section x plus 2 mm
    assert np.abs(f.path_at_x([10e-3, 25e-3, 2e-3]) - [10.5e-3, 27e-3, 4e-3]).max() <= 1e-15


def test_a_mesh_elements_wiper_and_gate_are_built_along_its_path(stl):
    f = Feeder.from_values(values(stl, s2_wiper_height=4e-4, s2_wiper_at=0.5, s2_gate_width=8e-4,
                                  s2_gate_at=0.8))
    f.check()
    e = f.elements[1]
    assert e.exit_width == 8e-4
    st = {s.name: s for s in f.stations}
    # the wiper from 11 mm of path (4 + 11 = 15 mm) on by a part's size; the gate's taper from
    # 0.8 x 22 = 17.6 mm of path (21.6 mm) by (1.2 - 0.8) / 2 = 0.2 mm
    assert (st["s2.wiper"].start, st["s2.wiper"].end) == (pytest.approx(15e-3, abs=1e-15),
                                                          pytest.approx(15.3e-3, abs=1e-15))
    assert (st["s2.gate"].start, st["s2.gate"].end) == (pytest.approx(21.6e-3, abs=1e-15),
                                                        pytest.approx(21.8e-3, abs=1e-15))
    assert st["s2.wiper"].section == st["s2.gate"].section == 2
    v, t = e.tools_mesh()
    # the wiper's underside: 0.4 mm above the floor, across the middle leg (plan y 3 +- 0.6 mm),
    # from plan x 10 to 10.3 mm (deck 14 to 14.3 mm); its upstream face up to the tools' top
    under = v[np.isclose(v[:, 2], FLOOR + 4e-4, rtol=0, atol=1e-12)]
    assert len(under) == 4
    assert sorted({round(x, 9) for x in under[:, 0]}) == [14e-3, 14.3e-3]
    assert sorted({round(y, 9) for y in under[:, 1]}) == [2.4e-3, 3.6e-3]
    assert v[:, 2].max() == pytest.approx(FLOOR + TOOL_TOP * SIZE, abs=1e-15)
    assert v[:, 2].min() == pytest.approx(FLOOR - TOOL_SINK * SIZE, abs=1e-15)
    # the gate's walls at the path's end (deck x 24 mm): 0.4 mm either side
    end = v[np.isclose(v[:, 0], 24e-3, rtol=0, atol=1e-12)]
    assert sorted({round(y, 9) for y in end[:, 1]}) == [-0.4e-3, 0.4e-3]
    # at the corner (plan (16, 0)) the left wall is mitred: (16 + 0.4/3, 0.4) mm, 0.4 mm from both legs
    corner = v[np.isclose(v[:, 0], 20e-3 + 0.4e-3 / 3, rtol=0, atol=1e-12)]
    assert sorted({round(y, 9) for y in corner[:, 1]}) == [0.4e-3]
    # at the taper's start (17.6 mm of path, 4.6 mm down the fourth leg (4, -3)/5: plan (15.68,
    # 0.24)) 0.6 mm off the path to its left, (3, 4)/5
    left_normal = np.array([3.0, 4.0]) / 5
    start = np.array([15.68e-3 + 4e-3, 0.24e-3]) + 0.6e-3 * left_normal
    assert np.abs(v[:, :2] - start).sum(axis=1).min() <= 1e-12
    # the tools are in the STL the run reads, after the CAD's own triangles
    mv, mt = e.mesh()
    assert len(mt) == len(e.placed.faces) + len(t) and np.array_equal(mv[-len(v):], v)
    # every triangle of the tools has a face (none of zero area)
    area = np.linalg.norm(np.cross(v[t[:, 1]] - v[t[:, 0]], v[t[:, 2]] - v[t[:, 0]]), axis=1)
    assert area.min() > 0


@pytest.mark.parametrize("change, words", [
    ({"s2_path": path_text(PLAN[:-1])},
     "s2_path: the mesh reaches 4 mm beyond its path's end along x"),
    ({"s2_gate_width": 2e-4}, "s2_gate_width: 0.0002 m is narrower than a part"),
    ({"s2_gate_width": 1.2e-3}, "s2_gate_width: 0.0012 m must be narrower than"),
    ({"s2_gate_width": 8e-4, "s2_gate_at": 0.995},
     "s2_gate_at: 0.995: the gate's 45 degree taper (0.0002 m long) runs past"),
    ({"s2_wiper_height": 2e-4}, "s2_wiper_height: 0.0002 m is lower than a part"),
    ({"s2_wiper_height": 7e-4}, "s2_wiper_height: 0.0007 m: the tools stand 2"),
    ({"s2_wiper_height": 4e-4, "s2_wiper_at": 0.99},
     "s2_wiper_at: 0.99: the wiper's bar (0.0003 m long) runs past its path's end"),
])
def test_a_mesh_elements_slips_are_one_line_naming_the_key(stl, change, words):
    with pytest.raises(ParameterError) as err:
        Feeder.from_values(values(stl, **change)).check()
    assert words in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_a_path_that_ends_turned_is_refused_when_an_element_follows(tmp_path):
    # the last leg heads 3 degrees off +x, ending on the centre line: it would hand over askew
    # (its end cut along x = 20 mm, as a CAD model may be, not square to the leg)
    turned = PLAN.copy()
    turned[4] = (16, -4 * math.tan(math.radians(3)), 0)
    v, t = channel(turned, 1.2, 1.0)
    v[:, 0] = np.minimum(v[:, 0], 20.0)
    write_stl(v, t, tmp_path / "t.stl", "t")
    with pytest.raises(ParameterError, match=r"it ends \+0 mm across, turned 3 deg: bend it back"):
        Feeder.from_values(values(tmp_path / "t.stl", s2_path=path_text(turned))).check()


@pytest.mark.parametrize("tool, words", [
    ("side_drop = { from = 0.2, to = 0.5, width = 5e-4 }", "a side drop cuts the floor, which is the STL's"),
    ("slot = { from = 0.2, to = 0.5, width = 2e-4 }", "a slot cuts the floor, which is the STL's"),
])
def test_a_tool_a_mesh_element_does_not_build_is_refused_in_one_line(tmp_path, stl, tool, words):
    text = ('[parts]\nsize = 3e-4\n[[element]]\nkind = "linear"\nlength = 0.004\nwidth = 1.2e-3\n'
            'drive = { freq = 100, amp_t = 3.5e-5, amp_n = 5e-5 }\n'
            f'[[element]]\nkind = "mesh"\nfile = "{stl.name}"\nunit = "mm"\npath = {PLAN.tolist()}\n'
            f'width = 1.2e-3\nstep = 5e-5\ndrive = {{ freq = 100, amp_t = 1e-4, amp_n = 5e-5 }}\n{tool}\n')
    (tmp_path / "f.toml").write_text(text)
    with pytest.raises(ParameterError) as err:
        read(tmp_path / "f.toml")
    assert f"element 2: {tool.split()[0]}: " in str(err.value) and words in str(err.value)


def test_the_path_runs_along_the_mesh_then_along_x_again(stl):
    from vibrofeed.postproc.orientation import path_directions

    f = Feeder.from_values(values(stl))
    # at 10.5 mm of path (6.5 mm into the mesh) the first diagonal leg (4, 3)/5; at 24 mm its last
    # leg; 27 mm the third section; beyond the outlet (29 mm) on along x; 19.5 mm the fourth leg,
    # (4, -3)/5
    t, up = path_directions(f, [10.5e-3, 24e-3, 27e-3, 29e-3, 4e-3 + 15.5e-3])
    want = [(0.8, 0.6, 0), (1, 0, 0), (1, 0, 0), (1, 0, 0), (0.8, -0.6, 0)]
    assert np.abs(t - want).max() <= 1e-12
    assert np.abs(up - [0, 0, 1]).max() <= 1e-12
