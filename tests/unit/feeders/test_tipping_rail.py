"""A skewed wiper, the tipping rail (vibrofeed.line, vibrofeed.feeders.linear): its bar runs
downstream from the reference wall to the far wall at ``wiper_skew`` degrees from straight
across, its underside ``wiper_height`` above the floor all along, its upstream face turned to push
a taller part towards the far wall; its footprint along the track is its length plus the skew's
run across; a bar that runs past its section's end or meets a gate's taper, or a skew outside
0..75 degrees, is refused in one line naming the key. Geometry against hand-computed vertices."""

import math

import numpy as np
import pytest

from vibrofeed.errors import ParameterError
from vibrofeed.feeders import Feeder
from vibrofeed.feeders.linear import deck_name
from vibrofeed.line import Section, section_mesh
from vibrofeed.parameters import rule_for

TOL = 1e-12
X0, WIDTH, H, LENGTH = 0.01, 1e-3, 4.2e-4, 1e-3
BOX = {"shape": 3, "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4}
LINE = {**BOX, "sections": 2, "track_length": 5e-3, "track_width": 1.4e-3, "gate_width": 9e-4,
        "gate_at": 0.6, "wall_height": 1.5e-3, "s2_length": 4e-3, "s2_width": 1e-3,
        "s2_wall_height": 1e-3, "s2_step": 5e-5, "s2_wiper_height": 4.2e-4, "s2_wiper_at": 0.25,
        "s2_wiper_skew": 60.0}


def section(**kw) -> Section:
    base = dict(x0=X0, length=8e-3, width=WIDTH, wall_height=1e-3, step=5e-5, cross_tilt=10.0,
                wiper_height=H, wiper_at=0.25, wiper_length=LENGTH, wiper_skew=60.0)
    return Section(**{**base, **kw})


def bar_vertices(s: Section) -> np.ndarray:
    """The vertices the wiper adds to the section's mesh (the mesh without it, compared)."""
    v, _ = section_mesh(s)
    bare, _ = section_mesh(Section(**{**s.__dict__, "wiper_height": 0.0}))
    return v[len(bare):]


def test_the_bar_runs_from_the_reference_wall_downstream_to_the_far_wall():
    s = section()
    w0 = X0 + 0.25 * 8e-3
    run = WIDTH * math.tan(math.radians(60))  # 1.732 mm along for 1 mm across
    assert s.wiper_run == pytest.approx(run, rel=1e-15)
    assert s.wiper_x == pytest.approx((w0, w0 + LENGTH + run), rel=0, abs=TOL)
    v = bar_vertices(s)
    under = v[np.isclose(v[:, 2], s.floor_z(v[:, 1]) + H, rtol=0, atol=TOL)]
    # the underside's corners: the upstream face at either wall, the bar's end one length on
    expected = [(w0, -WIDTH / 2), (w0 + run, WIDTH / 2), (w0 + LENGTH + run, WIDTH / 2),
                (w0 + LENGTH, -WIDTH / 2)]
    got = sorted({(round(x, 12), round(y, 12)) for x, y in under[:, :2]})
    assert got == sorted((round(x, 12), round(y, 12)) for x, y in expected)


def test_its_upstream_face_pushes_towards_the_far_wall():
    trimesh = pytest.importorskip("trimesh")
    for skew in (30.0, 60.0):
        s = section(wiper_skew=skew)
        v, t = section_mesh(s)
        m = trimesh.Trimesh(v, t, process=False)
        n, c = m.face_normals, m.triangles_center
        w0 = s.wiper_x[0]
        # the upstream face: vertical, its centre on the line from (w0, -w/2) at the skew
        line = c[:, 0] - (w0 + (c[:, 1] + WIDTH / 2) * math.tan(math.radians(skew)))
        face = (np.abs(n[:, 2]) < 1e-9) & np.isclose(line, 0, rtol=0, atol=1e-9)
        assert face.sum() == 2
        a = math.radians(skew)  # its normal: back along the track and across towards +y
        # (a unit vector to 1e-9: trimesh's cross products of mm-sized edges; 1 degree of skew
        # moves it by 1.7e-2)
        assert np.allclose(n[face], [-math.cos(a), math.sin(a), 0.0], rtol=0, atol=1e-9)


def test_straight_across_is_the_wiper_of_before():
    s = section(wiper_skew=0.0)
    v = bar_vertices(s)
    w0 = X0 + 0.25 * 8e-3
    assert s.wiper_run == 0.0 and s.wiper_x == (w0, w0 + LENGTH)
    assert set(np.round(v[:, 0], 12)) == {round(w0, 12), round(w0 + LENGTH, 12)}


def test_the_key_its_deck_name_and_its_station():
    assert deck_name(3, ("wiper", "skew")) == "s3_wiper_skew"
    assert deck_name(1, ("wiper", "skew")) is None  # a wiper stands on a later section only
    f = Feeder.from_values(LINE)
    f.check()
    w = f.elements[1].wiper
    assert w.skew == 60.0
    assert f.elements[1].wiper_reach == pytest.approx(1e-3 + 1e-3 * math.sqrt(3), rel=1e-15)
    (station,) = [st for st in f.stations if st.kind == "wiper"]
    start = 5e-3 + 0.25 * 4e-3
    assert station.start == pytest.approx(start, rel=0, abs=TOL)
    assert station.end == pytest.approx(start + 1e-3 + 1e-3 * math.sqrt(3), rel=0, abs=TOL)


@pytest.mark.parametrize("given, words", [
    ({"s2_wiper_at": 0.5}, "s2_wiper_at=0.5: the wiper's bar (0.00273205 m along the track) runs past "
                           "the outlet edge"),
    # on a section 8 mm long: the bar from 2 to 5.4 mm, the taper from 4 to 4.25 mm
    ({"s2_length": 8e-3, "s2_width": 1.4e-3, "s2_gate_width": 9e-4, "s2_gate_at": 0.5},
     "s2_wiper_skew=60: the skewed bar meets the gate's taper (s2_gate_at=0.5)"),
    # the bar from the joint, in the taper that starts there
    ({"s2_width": 1.4e-3, "s2_gate_width": 9e-4, "s2_gate_at": 0.0, "s2_wiper_at": 0.0},
     "s2_wiper_skew=60: the skewed bar meets the gate's taper (s2_gate_at=0)"),
])
def test_a_bar_that_does_not_fit_is_refused_in_one_line(given, words):
    with pytest.raises(ParameterError) as e:
        Feeder.from_values({**LINE, **given}).check()
    assert words in str(e.value) and "\n" not in str(e.value)


def test_a_bar_past_the_gates_taper_fits_and_runs_across_the_gates_width():
    f = Feeder.from_values({**LINE, "s2_width": 1.4e-3, "s2_gate_width": 9e-4, "s2_gate_at": 0.0,
                            "s2_wiper_at": 0.125})
    f.check()  # the taper ends at 0.25 mm, the bar starts at 0.5 mm
    s = f.elements[1].mesh_section()
    assert s.wiper_run == pytest.approx(9e-4 * math.sqrt(3), rel=1e-15)  # across the gate's 0.9 mm


@pytest.mark.parametrize("skew, bad", [(0.0, False), (75.0, False), (-5.0, True), (80.0, True)])
def test_the_skew_lies_in_0_to_75_degrees(skew, bad):
    for k in (2, 3):
        message = rule_for(f"s{k}_wiper_skew")(skew)
        assert (message is not None) == bad
