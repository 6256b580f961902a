"""The bowl feeder's geometry (vibrofeed.bowl): the mesh, the drive seen from the track, the
pre-fill's places and the refusals."""

from __future__ import annotations

import collections
import math

import numpy as np
import pytest

from vibrofeed.bowl import THETA_END, Bowl, bowl_mesh, check_bowl, fill_boxes, path_coordinate, track_drive
from vibrofeed.errors import ParameterError

BOWL = Bowl(radius=0.01, track_width=1.2e-3, helix_angle=3.0, turns=1.5, wall_height=1e-3,
            cone_angle=3.0, cross_tilt=3.0, lip_height=0.0, chute_length=8e-3)
PARAMS = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
          "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "lip_height": 0.0,
          "chute_length": 8e-3, "part_size": 3e-4, "part_thickness": 1.5e-4, "shape": 0,
          "size_spread": 0.0, "n_parts": 100, "n_track": 40}
LENGTH = 1e-9  # [m] coordinates are exact to round-off of mm-sized numbers


def edges(triangles):
    count = collections.Counter()
    for t in triangles:
        for i in range(3):
            count[tuple(sorted((int(t[i]), int(t[(i + 1) % 3]))))] += 1
    return count


def test_the_helix_rises_one_pitch_per_turn_at_the_helix_angle():
    # pitch = 2 pi r_mid tan(helix_angle), by hand for the centre line 9.4 mm
    assert math.isclose(BOWL.pitch, 2 * math.pi * 9.4e-3 * math.tan(math.radians(3)), rel_tol=1e-12)
    theta = np.linspace(BOWL.theta_start, THETA_END - 2 * math.pi, 7)
    for r in (BOWL.radius - BOWL.track_width, BOWL.r_mid, BOWL.radius):
        rise = BOWL.floor_z(theta + 2 * math.pi, r) - BOWL.floor_z(theta, r)
        assert np.allclose(rise, BOWL.pitch, rtol=0, atol=LENGTH)


def test_the_mesh_track_is_track_width_wide_and_its_floor_where_the_helix_says():
    vertices, triangles = bowl_mesh(BOWL)
    r = np.hypot(vertices[:, 0], vertices[:, 1])
    theta = np.arctan2(vertices[:, 1], vertices[:, 0])
    inner = np.isclose(r, BOWL.radius - BOWL.track_width, rtol=0, atol=LENGTH) & (vertices[:, 2] > 0)
    # the floor's inner edge: every such vertex lies on the helix at one of the turns' angles
    assert inner.sum() >= 60
    for z, t in zip(vertices[inner][:, 2], theta[inner]):
        turns = [t + 2 * math.pi * k for k in range(-3, 1)]
        heights = [float(BOWL.floor_z(a, BOWL.radius - BOWL.track_width)) for a in turns
                   if BOWL.theta_start - 1e-9 <= a <= THETA_END + 1e-9]
        on_floor = min(abs(z - h) for h in heights) < LENGTH
        riser_foot = z <= BOWL.bottom_z(BOWL.radius - BOWL.track_width) + LENGTH
        chute_wall_top = (abs(t - THETA_END) < 1e-9
                          and abs(z - heights[-1] - BOWL.wall_height) < LENGTH)  # its inner wall
        assert on_floor or riser_foot or chute_wall_top
    # the chute's end (its floor's outer corners) is the outlet edge x = outlet_x
    chute = vertices[np.abs(vertices[:, 1] + BOWL.radius) < LENGTH]
    assert chute[:, 0].max() == pytest.approx(BOWL.outlet_x, rel=0, abs=LENGTH)
    assert vertices[:, 2].min() == pytest.approx(0.0, rel=0, abs=LENGTH)
    assert vertices[:, 2].max() == pytest.approx(max(BOWL.top, BOWL.end_z + BOWL.chute_length
                                                     * math.sin(math.radians(3)) + BOWL.wall_height
                                                     + BOWL.track_width / 2 * math.tan(math.radians(3))),
                                                 rel=0, abs=1e-6)


def test_the_bowl_is_closed_where_it_holds_parts():
    vertices, triangles = bowl_mesh(BOWL)
    count = edges(triangles)
    assert max(count.values()) == 2  # a manifold surface: no edge shared by three faces
    open_edges = [e for e, c in count.items() if c == 1]
    z = vertices[:, 2]
    r = np.hypot(vertices[:, 0], vertices[:, 1])
    # the bottom meets the wall all round (no open edge at the foot of the wall) ...
    assert not [e for e in open_edges if np.all(np.abs(z[list(e)]) < LENGTH)]
    # ... and the wall has no open vertical seam below the slot's floor
    vertical = [e for e in open_edges
                if np.allclose(vertices[e[0], :2], vertices[e[1], :2], rtol=0, atol=LENGTH)]
    seam = [e for e in vertical if np.all(np.isclose(r[list(e)], BOWL.radius, rtol=0, atol=LENGTH))
            and min(z[list(e)]) < BOWL.end_z - BOWL.pitch]
    assert not seam
    # no face of zero area (LIGGGHTS refuses degenerate triangles)
    a = np.linalg.norm(np.cross(vertices[triangles[:, 1]] - vertices[triangles[:, 0]],
                                vertices[triangles[:, 2]] - vertices[triangles[:, 0]]), axis=1) / 2
    assert a.min() > 1e-12  # [m^2]: a micro-part's cross-section is 1e-8


def test_the_fill_boxes_lie_on_the_track_between_floor_and_the_next_turn():
    boxes = fill_boxes(BOWL, 3e-4, 2.5 * 3e-4)
    assert len(boxes) > 50
    coords = []
    for x0, x1, y0, y1, z0, z1 in boxes:
        # every corner, at the bottom and the top, is over the track (within its width and
        # less than a pitch above the floor under it: below the next turn)
        corners = np.array([(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)])
        s = path_coordinate(BOWL, corners)
        assert np.isfinite(s).all(), (x0, y0, z0)
        coords.append(float(path_coordinate(BOWL, [[(x0 + x1) / 2, (y0 + y1) / 2, z0]])[0]))
        # the bottom just above the floor under its centre (the helix's or the chute's)
        sc = coords[-1]
        alpha = math.radians(BOWL.helix_angle)
        if sc <= BOWL.length:
            theta = BOWL.theta_start + sc * math.cos(alpha) / BOWL.r_mid
            floor = float(BOWL.floor_z(theta, math.hypot((x0 + x1) / 2, (y0 + y1) / 2)))
        else:
            floor = BOWL.end_z + (x0 + x1) / 2 * math.tan(alpha)
        assert 0 <= z0 - floor < 3e-4  # [m] within a part
    # from a quarter turn after the start up the helix, then along the chute to its end
    coords = np.array(coords)
    assert (np.diff(coords) > 0).all()
    assert coords[0] == pytest.approx(BOWL.length * 0.25 / BOWL.turns, rel=0, abs=1e-3)
    assert coords[-1] > BOWL.length + BOWL.chute_length - 1.5e-3


@pytest.mark.parametrize("phase", [0.0, 30.0, -45.0])
@pytest.mark.parametrize("r", [None, 0.0095])
def test_the_drive_seen_from_the_track_is_the_projected_motion(phase, r):
    """The displacement time series of the bowl's point at radius r, projected on the
    helix's tangent and normal, fitted with sines: the linear drive track_drive gives."""
    amp_t, amp_n, freq, helix, r_mid = 5e-5, 3e-5, 100.0, 8.0, 9.4e-3
    d = track_drive(amp_t, amp_n, phase, freq, helix, r_mid, r)
    rr = r_mid if r is None else r
    alpha = math.atan(math.tan(math.radians(helix)) * r_mid / rr)
    w = 2 * math.pi * freq
    t = np.linspace(0, 1 / freq, 400, endpoint=False)
    tangential_bowl = rr / r_mid * amp_t * np.sin(w * t)
    vertical = amp_n * np.sin(w * t + math.radians(phase))
    along = tangential_bowl * math.cos(alpha) + vertical * math.sin(alpha)
    normal = -tangential_bowl * math.sin(alpha) + vertical * math.cos(alpha)
    basis = np.column_stack([np.sin(w * t), np.cos(w * t)])
    (a_s, a_c), *_ = np.linalg.lstsq(basis, along, rcond=None)
    (n_s, n_c), *_ = np.linalg.lstsq(basis, normal, rcond=None)
    assert d.amp_t == pytest.approx(math.hypot(a_s, a_c), rel=1e-9, abs=0)
    assert d.amp_n == pytest.approx(math.hypot(n_s, n_c), rel=1e-9, abs=0)
    lead = math.degrees(math.atan2(n_c, n_s) - math.atan2(a_c, a_s))
    assert (d.phase - lead + 180) % 360 - 180 == pytest.approx(0, abs=1e-6)  # [deg]
    assert d.incline == pytest.approx(math.degrees(alpha), rel=1e-12, abs=0)
    assert d.centripetal == pytest.approx(rr * (amp_t * w / r_mid) ** 2, rel=1e-12, abs=0)


def test_a_pure_torsion_on_a_helix_also_moves_the_floor_normal_to_itself():
    d = track_drive(5e-5, 0.0, 0.0, 100.0, 10.0, 9.4e-3)
    assert d.amp_n == pytest.approx(5e-5 * math.sin(math.radians(10)), rel=1e-12, abs=0)
    assert abs(abs(d.phase) - 180) < 1e-9  # [deg] the floor drops as it swings forward


@pytest.mark.parametrize("change, words", [
    ({"turns": 0}, "turns=0 must be > 0"),
    ({"helix_angle": 50}, "helix_angle=50"),
    ({"track_width": 2e-4}, "narrower than a part"),
    ({"helix_angle": 0.5}, "less than three parts"),
    ({"chute_length": 4e-3}, "ends inside the bowl"),
    ({"n_parts": 0, "n_track": 0}, "no part in the bowl"),
    ({"wall_height": 2e-4}, "no higher than a part"),
    ({"track_width": 6e-3}, "fill the bowl"),
])
def test_the_refusals_name_the_parameter(change, words):
    with pytest.raises(ParameterError, match=words):
        check_bowl({**PARAMS, **change})


def test_the_shipped_bowl_is_accepted_and_a_deck_without_a_bowl_is_not_checked():
    check_bowl(PARAMS)
    check_bowl({"track_width": 1e-5})


def test_the_prepare_hook_writes_numbers_liggghts_reads(tmp_path):
    """prepared.in: plain numbers only (a numpy scalar's repr, np.float64(...), is no number to
    LIGGGHTS), the bowl's geometry as vibrofeed.bowl computes it, one region per fill cube."""
    import re

    from vibrofeed.geometry import prepare_bowl_feeder

    values = {k: str(v) for k, v in PARAMS.items()} | {"seed": "5489"}
    prepared = prepare_bowl_feeder(values, tmp_path)
    number = r"-?\d+(\.\d+)?(e-?\d+)?"
    lines = (tmp_path / "prepared.in").read_text().splitlines()[1:]
    regions = 0
    for line in lines:
        if line.startswith("region track_fill_"):
            regions += 1
            assert re.fullmatch(rf"region track_fill_\d+ block( {number}){{6}} units box", line), line
        elif not line.startswith("region track_fill union"):
            assert re.fullmatch(rf"variable \w+ equal {number}", line), line
    got = dict(re.findall(r"variable (bowl_\w+) equal (\S+)", "\n".join(lines)))
    assert float(got["bowl_pitch"]) == pytest.approx(BOWL.pitch, rel=1e-15, abs=0)
    assert float(got["bowl_outlet_x"]) == pytest.approx(BOWL.outlet_x, rel=1e-15, abs=0)
    assert int(float(got["bowl_fill_boxes"])) == regions > 50
    assert (tmp_path / "bowl.stl").stat().st_size > 0
    np.testing.assert_array_equal(prepared.track[0], bowl_mesh(BOWL)[0])
