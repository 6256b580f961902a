"""The side drop on a bowl's helix (the feeder lines' tooling): between drop_from and drop_to
of the helix's length, at the track's stations, the floor is drop_width wide from the wall;
a part beyond it has no floor under it and falls back into the bowl. Over the first turn the
riser that closes the shelf follows the narrower floor, closed at both ends. No fill cube
over the drop; no path coordinate beyond its floor; the refusals at their boundaries."""

import math
from dataclasses import replace

import numpy as np
import pytest

from vibrofeed.bowl import THETA_END, Bowl, bowl_from, bowl_mesh, check_bowl, fill_boxes, path_coordinate
from vibrofeed.errors import ParameterError

W, DW, PART = 1.2e-3, 4e-4, 3e-4  # [m] track, the floor over the drop, a part
BOWL = Bowl(radius=0.01, track_width=W, helix_angle=3.0, turns=1.5, wall_height=1e-3, cone_angle=3.0,
            cross_tilt=3.0, chute_length=8e-3, drop_from=0.7, drop_to=0.9, drop_width=DW)
PARAMS = {"bowl_diameter": 0.02, "track_width": W, "helix_angle": 3.0, "turns": 1.5, "wall_height": 1e-3,
          "cone_angle": 3.0, "cross_tilt": 3.0, "chute_length": 8e-3, "part_size": PART,
          "drop_from": 0.7, "drop_to": 0.9, "drop_width": DW}
LENGTH = 1e-9  # [m]
# [m] the floor's faces are flat between stations 6 deg apart: at a station's middle they lie
# within a micrometre of the helicoid (tan(cross_tilt) times the chord's sagitta, 0.7 um)
FACET = 1e-5


def crossings(vertices, triangles, x, y):
    """Heights at which the vertical line through (x, y) passes through the mesh's faces."""
    p = vertices[triangles]
    a, b, c = p[:, 0], p[:, 1], p[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
    ok = np.abs(det) > 1e-18  # (vertical faces: the line does not cross them)
    u = ((x - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (y - a[:, 1])) / np.where(ok, det, 1)
    v = ((b[:, 0] - a[:, 0]) * (y - a[:, 1]) - (x - a[:, 0]) * (b[:, 1] - a[:, 1])) / np.where(ok, det, 1)
    hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1)
    z = a[:, 2] + u * (b[:, 2] - a[:, 2]) + v * (c[:, 2] - a[:, 2])
    return np.sort(z[hit])


def test_the_drop_lies_on_the_stations_nearest_its_fractions():
    t = BOWL.stations
    n = len(t) - 1
    assert BOWL.drop == (t[round(0.7 * n)], t[round(0.9 * n)])
    assert np.diff(t).max() <= math.radians(6.0) + 1e-12
    a, b = BOWL.drop
    w = BOWL.width_at(np.array([a - 1e-6, a, (a + b) / 2, b - 1e-6, b]))
    assert w.tolist() == [W, DW, DW, DW, W]  # its start included, its end not
    assert replace(BOWL, drop_to=0.0).drop is None and (replace(BOWL, drop_to=0.0).width_at([a]) == W).all()


@pytest.mark.parametrize("b", [BOWL, replace(BOWL, turns=0.5, drop_from=0.5, drop_to=0.8)])
def test_over_the_drop_only_the_narrow_floor_is_under_a_part(b):
    """Up the helix, a vertical line between the narrow floor's edge and the track's inner edge
    passes through the floor of its turn outside the drop, not over it (there only the bottom,
    or the turns below); a line over the narrow floor passes through it everywhere."""
    vertices, triangles = bowl_mesh(b)
    a, e = b.drop
    t = b.stations
    for t0, t1 in zip(t[:-1], t[1:]):
        mid = (t0 + t1) / 2
        floor_beyond = float(b.floor_z(mid, b.radius - (W + DW) / 2))
        floor_narrow = float(b.floor_z(mid, b.radius - DW / 2))
        for r, floor, always in ((b.radius - (W + DW) / 2, floor_beyond, False),
                                 (b.radius - DW / 2, floor_narrow, True)):
            z = crossings(vertices, triangles, r * math.cos(mid), r * math.sin(mid))
            here = np.abs(z - floor) < FACET
            assert here.any() == (always or not a <= mid < e), (mid, r)
    # over the first turn the shelf is closed down to the bottom, with the narrow floor too:
    # between the two edges there is no face under the floor but the bottom
    first = [m for m in (t[:-1] + t[1:]) / 2 if a <= m < e and m <= b.theta_start + 2 * math.pi]
    for mid in first:
        r = b.radius - (W + DW) / 2
        z = crossings(vertices, triangles, r * math.cos(mid), r * math.sin(mid))
        assert z[0] == pytest.approx(float(b.bottom_z(r)), rel=0, abs=FACET)


def test_the_first_turns_narrow_shelf_is_closed_at_both_ends_and_the_mesh_has_no_t_junction():
    b = replace(BOWL, turns=0.5, drop_from=0.5, drop_to=0.8)
    vertices, triangles = bowl_mesh(b)
    count = {}
    for tri in triangles:
        for e in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[0], tri[2])):
            count[tuple(sorted(e))] = count.get(tuple(sorted(e)), 0) + 1
    assert max(count.values()) == 2
    # each end: a radial face from the track's inner edge to the narrow floor's, bottom to floor
    for t in b.drop:
        corners = [(b.radius - W, True), (b.radius - DW, True), (b.radius - W, False), (b.radius - DW, False)]
        for r, top in corners:
            z = float(b.floor_z(t, r)) if top else float(b.bottom_z(r))
            point = np.array([r * math.cos(t), r * math.sin(t), z])
            assert np.min(np.linalg.norm(vertices - point, axis=1)) < LENGTH, (t, r, top)
        # the edge between the wide floor's end and the narrow floor's: shared by two faces
        i = np.argmin(np.linalg.norm(vertices - b.helix_point(t, b.radius - DW), axis=1))
        j = np.argmin(np.linalg.norm(vertices - b.helix_point(t, b.radius), axis=1))
        assert count[tuple(sorted((int(i), int(j))))] == 2


def test_no_fill_cube_over_the_drop_nor_a_side_either_side_and_no_coordinate_beyond_its_floor():
    side = 0.6 * W
    dtheta = side / BOWL.r_mid
    a, e = BOWL.drop
    boxes = np.array(fill_boxes(BOWL, PART, 2.5 * PART))
    centres = np.column_stack([(boxes[:, 0] + boxes[:, 1]) / 2, (boxes[:, 2] + boxes[:, 3]) / 2, boxes[:, 4]])
    s = path_coordinate(BOWL, centres)
    on_helix = s <= BOWL.length
    # the track's angle of each cube on the helix (its turn's): none within a side of the drop
    t = BOWL.theta_start + s[on_helix] * math.cos(math.radians(3.0)) / BOWL.r_mid
    assert on_helix.sum() > 20 and not ((t >= a - dtheta) & (t <= e + dtheta)).any()
    assert len(boxes) < len(fill_boxes(replace(BOWL, drop_to=0.0), PART, 2.5 * PART))
    mid = (a + e) / 2
    beyond = BOWL.helix_point(mid, BOWL.radius - (W + DW) / 2) + [0, 0, 1e-4]
    narrow = BOWL.helix_point(mid, BOWL.radius - DW / 2) + [0, 0, 1e-4]
    s = path_coordinate(BOWL, np.array([beyond, narrow]))
    assert np.isnan(s[0]) and s[1] == pytest.approx(float(BOWL.arc_length(mid)), rel=0, abs=1e-7)


@pytest.mark.parametrize("change, words", [
    ({"drop_from": 0.9, "drop_to": 0.7}, "0 <= drop_from < drop_to <= 1"),
    ({"drop_from": 0.7, "drop_to": 0.7}, "0 <= drop_from < drop_to <= 1"),
    ({"drop_to": 1.01}, "0 <= drop_from < drop_to <= 1"),
    ({"drop_from": -0.01}, "0 <= drop_from < drop_to <= 1"),
    ({"drop_from": 0.0, "drop_to": 0.0, "drop_width": DW}, None),      # no drop asked: accepted
    # (1.5 turns, 540 deg, in 90 stations: 6 deg apart)
    ({"drop_from": 0.70, "drop_to": 0.705}, r"fall on one station of the helix's mesh \(6 deg apart\)"),
    ({"drop_width": math.nextafter(PART, 0.0)}, "must hold a part"),
    ({"drop_width": math.nextafter(W - PART / 4, 1.0)}, r"a quarter part narrower .*at most 0\.00112 m"),
    ({"drop_from": 0.05, "drop_to": 0.2}, "less than a part"),          # the first turn's low shelf
])
def test_the_drops_refusals_at_their_boundaries(change, words):
    if words is None:
        check_bowl({**PARAMS, **change})
        return
    with pytest.raises(ParameterError, match=words):
        check_bowl({**PARAMS, **change})


@pytest.mark.parametrize("change", [{"drop_width": PART}, {"drop_width": W - PART / 4},
                                    {"drop_from": 0.5, "drop_to": 1.0, "turns": 2.0}])  # up to the chute
def test_just_inside_the_drops_boundaries_is_accepted(change):
    check_bowl({**PARAMS, **change})


def test_a_narrow_step_under_a_tall_shelf_is_cut_into_rows_not_slivers():
    """A 9 deg helix of one turn narrowed by a quarter part up to its end: the riser's end face
    there is 75 um wide and 9.4 mm high (a single quad's triangles: 0.46 deg, which LIGGGHTS
    refuses); in rows at most ten times as high as it is wide, its faces keep 5 deg."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_bowl_mesh_quality import smallest_angles

    b = Bowl(radius=0.01, track_width=W, helix_angle=9.0, turns=1.0, wall_height=1e-3, chute_length=0.02,
             drop_from=0.05, drop_to=1.0, drop_width=W - PART / 4)
    check_bowl({**PARAMS, "helix_angle": 9.0, "turns": 1.0, "cone_angle": 0.0, "cross_tilt": 0.0,
                "chute_length": 0.02, "drop_from": 0.05, "drop_to": 1.0, "drop_width": W - PART / 4})
    vertices, triangles = bowl_mesh(b)
    on_end = np.all(np.abs(vertices[triangles][..., 0]) < LENGTH, axis=1) & np.all(
        np.hypot(vertices[triangles][..., 0], vertices[triangles][..., 1]) < b.radius - W + PART / 4 + LENGTH,
        axis=1)  # the end face at theta = -90 deg (x = 0), between the two inner edges
    assert on_end.sum() >= 2 * math.ceil(0.00935 / (10 * PART / 4))
    assert smallest_angles(vertices, triangles[on_end]).min() > 5.0  # [deg]


def test_the_drop_adds_one_face_at_each_end_of_the_floor_and_none_elsewhere():
    """Over an upper turn (no riser there) the narrowed floor has as many faces as the full
    one, and each wide segment beside the drop gains the corner where the narrow floor's edge
    meets it: one triangle more at each end."""
    plain = bowl_mesh(replace(BOWL, drop_to=0.0))[1]
    dropped = bowl_mesh(BOWL)[1]
    assert BOWL.drop[0] > BOWL.theta_start + 2 * math.pi  # an upper turn's stretch
    assert len(dropped) == len(plain) + 2


def polar_face(vertices, triangles, theta, r_lo, r_hi):
    """The triangles all of whose corners lie on the radial line at polar angle ``theta``,
    between radii r_lo and r_hi: a radial face's, as (n, 3, 3) corners."""
    p = vertices[triangles]
    r = np.hypot(p[..., 0], p[..., 1])
    on = np.abs(np.angle(np.exp(1j * (np.arctan2(p[..., 1], p[..., 0]) - theta)))) < 1e-9
    return p[np.all(on & (r > r_lo - LENGTH) & (r < r_hi + LENGTH), axis=1)]


@pytest.mark.parametrize("k, cone, tilt, start, rows", [
    (12.0, 0.0, 0.0, 10, (2, 12)),  # exactly ten widths high each: 12 / 6 and 12
    (11.5, 0.0, 0.0, 20, (4, 12)),  # ceil(11.5 / 3) and ceil(11.5), the start on the +y side
    (5.0, 0.0, 0.0, 10, (1, 5)),    # ceil(5 / 6): one row at the start
    (12.0, 4.0, 1.0, 10, (3, 13)),  # the narrow edge 0.0052 rows higher: ceil(2.0052), ceil(12.0052)
])
def test_the_drops_end_faces_over_the_first_turn_are_in_the_fewest_rows_ten_widths_high(k, cone, tilt, start,
                                                                                        rows):
    """A 9 deg helix of one turn (60 stations) narrowed from its station ``start`` (drop_from
    start / 60; 10: at -30 deg, 20: at +30 deg) to its end, the step Delta = pitch / (10 k) wide.
    With the cone at least as steep as the tilt the track's inner edge starts on the cone, so
    it stands rise = pitch i / 60 above the bottom at station i, the narrow floor's edge
    Delta (tan cone - tan tilt) higher. Each end face: a trapezoid from the bottom to the floor
    at both edges (its corners on the cone and the helicoid), in n = ceil(highest edge /
    (10 Delta)) equal rows: at most ten times as high as wide, none more."""
    r_mid = 0.01 - W / 2
    pitch = 2 * math.pi * r_mid * math.tan(math.radians(9.0))
    step = pitch / (10 * k)
    b = Bowl(radius=0.01, track_width=W, helix_angle=9.0, turns=1.0, wall_height=1e-3, chute_length=0.02,
             cone_angle=cone, cross_tilt=tilt, drop_from=start / 60, drop_to=1.0, drop_width=W - step)
    check_bowl({**PARAMS, "helix_angle": 9.0, "turns": 1.0, "cone_angle": cone, "cross_tilt": tilt,
                "chute_length": 0.02, "drop_from": start / 60, "drop_to": 1.0, "drop_width": W - step})
    assert b.drop == pytest.approx((b.theta_start + math.pi * start / 30, THETA_END), rel=0, abs=1e-12)
    vertices, triangles = bowl_mesh(b)
    r_in, r_narrow = b.radius - W, b.radius - b.drop_width
    extra = step * (math.tan(math.radians(cone)) - math.tan(math.radians(tilt)))
    for t, i, n in zip(b.drop, (start, 60), rows):
        rise = pitch * i / 60
        face = polar_face(vertices, triangles, t, r_in, r_narrow)
        area = 0.5 * np.linalg.norm(np.cross(face[:, 1] - face[:, 0], face[:, 2] - face[:, 0]), axis=1).sum()
        # (to the vertices' rounding to 1e-12 m along the face's 20 mm outline)
        assert area == pytest.approx(step * (rise + rise + extra) / 2, rel=0, abs=1e-14)
        corners = face.reshape(-1, 3)
        radius = np.hypot(corners[:, 0], corners[:, 1])
        for r, high in ((r_in, rise), (r_narrow, rise + extra)):
            z = np.unique(np.round(corners[np.abs(radius - r) < LENGTH, 2], 12))
            bottom = float(b.bottom_z(r))
            assert z[-1] == pytest.approx(float(b.floor_z(t, r)), rel=0, abs=LENGTH)
            assert z == pytest.approx(np.linspace(bottom, bottom + high, n + 1), rel=0, abs=LENGTH), (t, r)
            assert np.diff(z).max() <= 10 * step + LENGTH
        assert len(face) == 2 * n


@pytest.mark.parametrize("cone, tilt", [(5.0, 1.0), (1.0, 5.0)])
def test_a_first_turn_shelf_exactly_a_part_high_over_the_drop_is_accepted_a_hair_lower_refused(cone, tilt):
    """The narrow floor's edge (drop_width from the wall) at the drop's start, station 4 of 90
    (drop_from 0.04) in the first turn: the floor there stands z_start + pitch 4 / 60 - (R - DW -
    r_mid) tan(tilt) over the axis' level, the cone DW tan(cone) at that radius, z_start =
    max(w/2 tan(tilt), w tan(cone) - w/2 tan(tilt)). Spheres exactly that high pass; a hair taller
    are refused. (With the cone and the tilt unequal, the shelf at any other radius differs.)"""
    tan_c, tan_t = math.tan(math.radians(cone)), math.tan(math.radians(tilt))
    p = {**PARAMS, "cone_angle": cone, "cross_tilt": tilt, "drop_from": 0.04, "drop_to": 0.3}
    b = bowl_from(p)
    a, _ = b.drop
    assert a == pytest.approx(b.theta_start + math.radians(24.0), rel=0, abs=1e-12)
    r_mid = 0.01 - W / 2
    z_start = max(W / 2 * tan_t, W * tan_c - W / 2 * tan_t)
    shelf = z_start + b.pitch * 4 / 60 - (0.01 - DW - r_mid) * tan_t - DW * tan_c
    # (the same height from the bowl's own surfaces, to the bit: the boundary itself)
    exact = float(b.floor_z(a, b.radius - DW) - b.bottom_z(b.radius - DW))
    assert exact == pytest.approx(shelf, rel=0, abs=1e-15)
    assert 1e-4 < shelf < DW  # (a sphere that high fits the narrow floor)
    check_bowl({**p, "part_size": exact})
    with pytest.raises(ParameterError, match="the first turn's shelf is .* less than a part"):
        check_bowl({**p, "part_size": math.nextafter(exact, 1.0)})
