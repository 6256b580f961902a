"""The bowl feeder's geometry (vibrofeed.bowl): the mesh face by face, the drive seen from the
track, the parts' sizes, the refusals at their boundaries, the pre-fill's places and where a
point is along the track; the expected values from the closed forms, by hand."""

from __future__ import annotations

import collections
import math
from dataclasses import FrozenInstanceError, replace

import numpy as np
import pytest

from vibrofeed.bowl import (
    THETA_END,
    Bowl,
    bowl_from,
    bowl_mesh,
    check_bowl,
    fill_boxes,
    part_reach,
    path_coordinate,
    tallest_part,
    track_drive,
    widest_part,
)
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
    assert -180 <= d.phase < 180  # the lead as the linear deck takes it
    assert d.incline == pytest.approx(math.degrees(alpha), rel=1e-12, abs=0)
    assert d.centripetal == pytest.approx(rr * (amp_t * w / r_mid) ** 2, rel=1e-12, abs=0)


def test_a_pure_torsion_on_a_helix_also_moves_the_floor_normal_to_itself():
    d = track_drive(5e-5, 0.0, 0.0, 100.0, 10.0, 9.4e-3)
    assert d.amp_n == pytest.approx(5e-5 * math.sin(math.radians(10)), rel=1e-12, abs=0)
    assert abs(abs(d.phase) - 180) < 1e-9  # [deg] the floor drops as it swings forward
    assert -180 <= d.phase < 180  # as every lead: -180, not 180


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


def test_parts_too_big_for_the_cubes_along_the_track_are_refused_there_and_allowed_in_the_pile():
    # a 1.0 x 0.5 x 0.35 mm box's clump (36 spheres) reaches 0.54 mm from its centre: 1.08 mm
    # across, more than the 0.72 mm cubes (0.6 of a 1.2 mm track) LIGGGHTS would insert it in
    box = {**PARAMS, "shape": 3, "part_size": 1e-3, "part_width": 5e-4, "part_thickness": 3.5e-4,
           "clump_spacing": 1.0}
    with pytest.raises(ParameterError) as info:
        check_bowl(box)
    said = str(info.value)
    assert said.startswith("n_track=40: ") and "n_parts" in said and "\n" not in said
    reach = float(said.split("needs ")[1].split(" m")[0]) / 2
    assert reach == pytest.approx(0.54e-3, abs=0.01e-3)  # [m] the clump's, by hand to 10 um
    check_bowl({**box, "n_track": 0})  # the pile takes them
    # a die of the demo's (0.5 x 0.5 x 0.25 mm): its clump 0.60 mm across fits the 0.72 mm cubes
    check_bowl({**PARAMS, "shape": 1, "part_size": 5e-4, "part_thickness": 2.5e-4})


def test_theta_at_is_the_inverse_of_arc_length_up_the_helix():
    b = bowl_from(PARAMS)
    theta = np.linspace(b.theta_start, b.theta_start + 2 * math.pi * b.turns, 7)
    assert np.abs(b.theta_at(b.arc_length(theta)) - theta).max() <= 1e-12  # [rad]
    assert float(b.theta_at(0.0)) == b.theta_start


def test_the_shipped_bowl_is_accepted_and_a_deck_without_a_bowl_is_not_checked():
    check_bowl(PARAMS)
    check_bowl({"track_width": 1e-5})


def test_the_prepare_hook_writes_numbers_liggghts_reads(tmp_path):
    """prepared.in: plain numbers only (a numpy scalar's repr, np.float64(...), is no number to
    LIGGGHTS), the bowl's geometry as vibrofeed.bowl computes it, one region per fill cube."""
    import re

    from vibrofeed.geometry import prepare_bowl_feeder

    values = {k: str(v) for k, v in PARAMS.items()} | {"seed": "5489", "drop_from": "0", "drop_to": "0",
                                                         "drop_width": "0", "wiper_height": "0",
                                                         "wiper_at": "0.5"}
    prepared = prepare_bowl_feeder(values, tmp_path)
    number = r"-?\d+(\.\d+)?(e-?\d+)?"
    lines = (tmp_path / "prepared.in").read_text().splitlines()[1:]
    regions = 0
    for line in lines:
        if line.startswith("region track_fill_"):
            regions += 1
            assert re.fullmatch(rf"region track_fill_\d+ block( {number}){{6}} units box", line), line
        elif line.startswith("if "):  # a run by hand held to the values checked (vibrofeed.feeders.deck)
            assert re.fullmatch(rf'if "\$\{{\w+\}} != {number}" then &', line), line
        elif line.startswith("  \"print 'Invalid "):
            assert line.endswith("run vibrofeed prepare again with the new value'\" \"quit\""), line
        elif not line.startswith("region track_fill union"):
            assert re.fullmatch(rf"variable \w+ equal {number}", line), line
    got = dict(re.findall(r"variable (bowl_\w+) equal (\S+)", "\n".join(lines)))
    assert float(got["bowl_pitch"]) == pytest.approx(BOWL.pitch, rel=1e-15, abs=0)
    assert float(got["bowl_outlet_x"]) == pytest.approx(BOWL.outlet_x, rel=1e-15, abs=0)
    assert int(float(got["bowl_fill_boxes"])) == regions > 50
    assert (tmp_path / "bowl.stl").stat().st_size > 0
    np.testing.assert_array_equal(prepared.track[0], bowl_mesh(BOWL)[0])


# ------------------------------------------------------------------ the closed forms, by hand
def tan(deg):
    return math.tan(math.radians(deg))


def hand_floor(b, theta, r):
    """The floor's height from the module docstring, by hand: the shelf starts on the bottom
    (its outer edge on it at the wall, height 0, or its inner edge on the cone where the cone
    is the steeper), rises tan(helix_angle) per unit of centre-line arc and falls
    tan(cross_tilt) per unit of radius outwards."""
    w, r_mid = b.track_width, b.radius - b.track_width / 2
    z0 = max(w / 2 * tan(b.cross_tilt), w * tan(b.cone_angle) - w / 2 * tan(b.cross_tilt))
    start = -math.pi / 2 - 2 * math.pi * b.turns
    return (z0 + r_mid * tan(b.helix_angle) * (np.asarray(theta) - start)
            - (np.asarray(r) - r_mid) * tan(b.cross_tilt))


def areas(vertices, triangles):
    e1 = vertices[triangles[:, 1]] - vertices[triangles[:, 0]]
    e2 = vertices[triangles[:, 2]] - vertices[triangles[:, 0]]
    return np.linalg.norm(np.cross(e1, e2), axis=1) / 2


def on_radius(vertices, r):
    return np.abs(np.hypot(vertices[:, 0], vertices[:, 1]) - r) < LENGTH


def has_vertex(vertices, point):
    return float(np.min(np.linalg.norm(vertices - np.asarray(point, dtype=float), axis=1))) < LENGTH


def distinct_angles(vertices, origin=0.0):
    """The polar angles of ``vertices`` in [origin, origin + 2 pi), each once (to 1e-9 rad)."""
    a = np.mod(np.arctan2(vertices[:, 1], vertices[:, 0]) - origin, 2 * math.pi)
    a = np.sort(np.where(a > 2 * math.pi - 1e-9, 0.0, a))
    return a[np.r_[True, np.diff(a) > 1e-9]]


STEP = math.radians(6.0)  # the mesh's stations: 1.5 turns are 90 steps of 6 deg, a turn 60
ANGLE = 1e-9  # [rad]
AREA = 1e-15  # [m^2]: round-off of the mm^2-sized faces


LOW = 0.02  # of the track's width: a step of the first shelf lower than that gets no face


def riser_heights(b, stations):
    """The riser's height at ``stations`` of the first turn: from the cone (w tan(cone_angle)
    at the track's inner radius) up to the floor's inner edge; 0 where that is no more than
    LOW of the track's width (no face: it would be a sliver, and no part fits under it)."""
    r_in = b.radius - b.track_width
    h = hand_floor(b, stations, r_in) - b.track_width * tan(b.cone_angle)
    return np.where(h > LOW * b.track_width, h, 0.0)


def first_turn_riser_area(b, stations):
    """The riser's area, by hand: over each step a vertical trapezoid on the chord between two
    stations at the track's inner radius, :func:`riser_heights` high at either end."""
    h = riser_heights(b, stations)
    chord = 2 * (b.radius - b.track_width) * np.sin(np.diff(stations) / 2)
    return float(np.sum(chord * (h[:-1] + h[1:]) / 2))


def start_plane(b, vertices):
    """Vertices in the radial half-plane of the track's start, between the track's radii."""
    ts = -math.pi / 2 - 2 * math.pi * b.turns
    along = vertices[:, 0] * math.cos(ts) + vertices[:, 1] * math.sin(ts)
    across = vertices[:, 0] * math.sin(ts) - vertices[:, 1] * math.cos(ts)
    return ((np.abs(across) < LENGTH) & (along > b.radius - b.track_width - LENGTH)
            & (along < b.radius + LENGTH))


# ------------------------------------------------------------------ the mesh, face by face
@pytest.mark.parametrize("lip", [2e-4, 1e-3])
def test_the_lip_stands_lip_height_above_the_floors_inner_edge_along_the_whole_helix(lip):
    b = replace(BOWL, lip_height=lip)
    vertices, triangles = bowl_mesh(b)
    r_in = b.radius - b.track_width
    stations = -math.pi / 2 - 3 * math.pi + STEP * np.arange(91)
    for t in stations:
        edge = np.array([r_in * math.cos(t), r_in * math.sin(t), float(hand_floor(b, t, r_in))])
        assert has_vertex(vertices, edge) and has_vertex(vertices, edge + [0, 0, lip]), t
    # the faces at the inner radius: the riser under the first turn and the lip, all vertical;
    # the lip is lip high over every chord of the helix
    inner = triangles[np.all(on_radius(vertices, r_in)[triangles], axis=1)]
    e1, e2 = (vertices[inner[:, k]] - vertices[inner[:, 0]] for k in (1, 2))
    n = np.cross(e1, e2)
    assert np.all(np.abs(n[:, 2]) <= 1e-9 * np.linalg.norm(n, axis=1))
    lip_area = 90 * 2 * r_in * math.sin(STEP / 2) * lip
    riser = first_turn_riser_area(b, stations[:61])
    assert areas(vertices, inner).sum() == pytest.approx(riser + lip_area, rel=1e-9, abs=AREA)


@pytest.mark.parametrize("lip", [0.0, -2e-4])
def test_no_lip_unless_lip_height_is_positive(lip):
    """0 is the deck's "no lip"; a negative height (the parameter rules refuse it) must not
    hang a face down from the floor's edge either."""
    b = replace(BOWL, lip_height=lip)
    vertices, triangles = bowl_mesh(b)
    r_in = b.radius - b.track_width
    inner = triangles[np.all(on_radius(vertices, r_in)[triangles], axis=1)]
    stations = -math.pi / 2 - 3 * math.pi + STEP * np.arange(61)
    assert areas(vertices, inner).sum() == pytest.approx(first_turn_riser_area(b, stations),
                                                         rel=1e-9, abs=AREA)


@pytest.mark.parametrize("cone, tilt, turns, helix", [
    (3.0, 3.0, 1.5, 3.0),   # the shipped bowl
    (5.0, 3.0, 1.5, 3.0),   # the cone steeper: the shelf's inner edge starts on the cone
    (1.0, 3.0, 1.5, 3.0),   # the tilt steeper: its outer edge starts on the bottom at the wall
    (0.0, 0.0, 2.5, 3.0),   # flat: only the first of the turns stands on a riser
    (4.0, 2.0, 0.6, 3.0),   # less than a turn: the riser runs under the whole track
    (3.0, 3.0, 1.5, 1.0),   # a shallow helix: its first step, 17 um, is below 2 % of w (24 um)
    (2.0, 3.0, 1.5, 1.0),   # ... over an edge 21 um above the cone: the first two are
])
def test_the_riser_closes_the_first_turn_down_to_the_cone_and_no_more(cone, tilt, turns, helix):
    b = replace(BOWL, cone_angle=cone, cross_tilt=tilt, turns=turns, helix_angle=helix)
    vertices, triangles = bowl_mesh(b)
    r_in = b.radius - b.track_width
    start = -math.pi / 2 - 2 * math.pi * turns
    steps = round(turns * 60)  # 6 deg stations: 60 a turn (turns are multiples of 0.1 here)
    stations = start + np.arange(min(steps, 60) + 1) * (2 * math.pi * turns / steps)
    # its foot on the cone at every station of the first turn where it stands (or where the
    # floor's edge itself is on the cone), none where the edge is just above it
    foot = b.track_width * tan(cone)
    above = hand_floor(b, stations, r_in) - foot
    on_cone = (above > LOW * b.track_width) | (above < LENGTH)
    if len(stations) == 61:  # a whole turn: its last station is over its first
        on_cone[0] = on_cone[-1] = on_cone[0] | on_cone[-1]
    for t, there in zip(stations, on_cone):
        assert has_vertex(vertices, [r_in * math.cos(t), r_in * math.sin(t), foot]) == there, t
    inner = triangles[np.all(on_radius(vertices, r_in)[triangles], axis=1)]
    assert areas(vertices, inner).sum() == pytest.approx(first_turn_riser_area(b, stations),
                                                         rel=1e-9, abs=AREA)


@pytest.mark.parametrize("turns", [1.0, 1.25, 1.5])
@pytest.mark.parametrize("cone, tilt", [(5.0, 3.0), (4.0, 0.0), (1.0, 3.0), (0.0, 2.0), (3.0, 3.0),
                                        (0.0, 0.0)])
def test_the_first_shelf_is_closed_at_its_start_where_it_stands_above_the_bottom(cone, tilt, turns):
    """The start's face, in the radial plane there: a triangle w wide and w |tan(cone_angle) -
    tan(cross_tilt)| high (the edge of the shelf above the bottom: its outer one at the wall
    when the cone is the steeper, its inner one over the cone when the tilt is); none when
    the two angles agree (the shelf's start lies on the bottom)."""
    b = replace(BOWL, cone_angle=cone, cross_tilt=tilt, turns=turns)
    vertices, triangles = bowl_mesh(b)
    w = b.track_width
    face = triangles[np.all(start_plane(b, vertices)[triangles], axis=1)]
    want = w * w * abs(tan(cone) - tan(tilt)) / 2
    assert areas(vertices, face).sum() == pytest.approx(want, rel=1e-9, abs=AREA)
    if want > 0:  # its corners: on the bottom at the wall and on the cone at the inner radius
        ts = -math.pi / 2 - 2 * math.pi * turns
        c, s = math.cos(ts), math.sin(ts)
        corners = vertices[np.unique(face)]
        assert has_vertex(corners, [b.radius * c, b.radius * s, 0.0])
        assert has_vertex(corners, [(b.radius - w) * c, (b.radius - w) * s, w * tan(cone)])


@pytest.mark.parametrize("turns", [1.0, 1.5])
@pytest.mark.parametrize("side", [1.0, -1.0])  # the cone a hair steeper than the tilt, or the tilt
@pytest.mark.parametrize("gap", [7e-13, 0.01, 0.019, 0.021, 0.05])  # of w; the first in m
def test_a_start_edge_lower_than_2_percent_of_the_width_gets_no_face(gap, side, turns):
    """A start face no more than 2 % of the track's width high would be a sliver LIGGGHTS
    refuses (and no part fits under it): none, down to the picometre the mesh's vertices keep
    apart; above that, the triangle w wide and that high."""
    w = BOWL.track_width
    height = gap if gap < 1e-6 else gap * w
    cone = math.degrees(math.atan(tan(3.0) + side * height / w))
    b = replace(BOWL, cone_angle=cone, cross_tilt=3.0, turns=turns)
    vertices, triangles = bowl_mesh(b)
    face = triangles[np.all(start_plane(b, vertices)[triangles], axis=1)]
    want = w * height / 2 if height > LOW * w else 0.0
    assert areas(vertices, face).sum() == pytest.approx(want, rel=1e-9, abs=AREA)


@pytest.mark.parametrize("cone", [0.0, 3.0, 10.0])
def test_the_bottom_is_a_fan_from_the_cones_apex_on_the_axis(cone):
    b = replace(BOWL, cone_angle=cone)
    vertices, triangles = bowl_mesh(b)
    apex = np.nonzero(np.linalg.norm(vertices - [0.0, 0.0, b.radius * tan(cone)], axis=1) < LENGTH)[0]
    assert len(apex) == 1
    fan = triangles[(triangles == apex[0]).any(axis=1)]
    rim = vertices[np.unique(fan[fan != apex[0]])]
    assert np.allclose(np.hypot(rim[:, 0], rim[:, 1]), b.radius, rtol=0, atol=LENGTH)
    assert np.allclose(rim[:, 2], 0.0, rtol=0, atol=LENGTH)
    # one triangle per station step round the bowl (60 of 6 deg): seen from above, the 60-gon
    # on the rim
    assert len(fan) == 60
    seen = b.radius ** 2 / 2 * 60 * math.sin(STEP)
    e1, e2 = (vertices[fan[:, k], :2] - vertices[fan[:, 0], :2] for k in (1, 2))
    assert np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]).sum() / 2 == pytest.approx(
        seen, rel=1e-9, abs=AREA)  # (the vertices are kept to 1e-12 m)


def test_the_wall_and_the_bottom_share_stations_6_deg_apart_and_the_slot_ends_at_one():
    """As few stations round the bowl as keep them within STATION (6 deg: 60 a turn), from the
    track's end: the wall's foot is the bottom's rim. The wall stands on every step up to the
    slot's floor (the end's outer floor edge), and up to the top except over the slot, which
    ends at the first station past where the chute's inner edge leaves the wall
    (acos((R - w) / R) = 28.4 deg after the track's end: at 30 deg)."""
    vertices, triangles = bowl_mesh(BOWL)
    R = BOWL.radius
    foot = vertices[on_radius(vertices, R) & (np.abs(vertices[:, 2]) < LENGTH)]
    got = distinct_angles(foot, origin=THETA_END)
    assert len(got) == 60 and np.allclose(got, STEP * np.arange(60), rtol=0, atol=ANGLE)
    z_slot = float(hand_floor(BOWL, THETA_END, R))
    top = z_slot + BOWL.wall_height
    wall = triangles[np.all(on_radius(vertices, R)[triangles], axis=1)]
    chord = 2 * R * math.sin(STEP / 2)
    assert areas(vertices, wall).sum() == pytest.approx(chord * (60 * z_slot + 55 * (top - z_slot)),
                                                        rel=1e-9, abs=AREA)
    high = vertices[np.unique(wall)]
    high = high[np.abs(high[:, 2] - top) < LENGTH]
    assert np.allclose(distinct_angles(high, origin=THETA_END), np.r_[0.0, STEP * np.arange(5, 60)],
                       rtol=0, atol=ANGLE)


def test_the_tracks_stations_are_as_few_as_keep_them_within_6_deg():
    """1.37 turns, 493.2 deg: 83 equal steps of 5.94 deg (82 would be 6.01 deg apart)."""
    b = replace(BOWL, turns=1.37)
    vertices, _ = bowl_mesh(b)
    r_in = b.radius - b.track_width
    start = -math.pi / 2 - 2 * math.pi * 1.37
    stations = start + np.arange(84) * (2 * math.pi * 1.37 / 83)
    want = np.sort(np.unique(np.round(np.mod(stations, 2 * math.pi), 9)))
    got = distinct_angles(vertices[on_radius(vertices, r_in)])  # floor's edge, riser, chute's start
    assert len(got) == 84 and np.allclose(got, want, rtol=0, atol=ANGLE)
    # a track shorter than a station: one step
    b = replace(BOWL, turns=0.01)
    vertices, _ = bowl_mesh(b)
    got = distinct_angles(vertices[on_radius(vertices, r_in)])
    assert np.allclose(got, np.sort(np.mod([-math.pi / 2 - 0.02 * math.pi, -math.pi / 2], 2 * math.pi)),
                       rtol=0, atol=ANGLE)


WIDE = Bowl(radius=0.01, track_width=4e-3, helix_angle=3.0, turns=1.5, wall_height=1e-3,
            cone_angle=3.0, cross_tilt=3.0, chute_length=1e-2)  # a chute shorter than 4 track widths


@pytest.mark.parametrize("b, n", [(BOWL, 2), (WIDE, 1), (replace(BOWL, chute_length=2e-2), 5)])
def test_the_chute_is_split_into_as_few_equal_pieces_as_keep_them_within_four_track_widths(b, n):
    # 8 mm / 4.8 mm: 2; 10 mm / 16 mm: 1; 20 mm / 4.8 mm: 5
    vertices, _ = bowl_mesh(b)
    outer = vertices[np.abs(vertices[:, 1] + b.radius) < LENGTH]  # the chute's outer side
    got = np.unique(np.round(outer[:, 0], 12))
    want = np.arange(n + 1) * b.chute_length / n * math.cos(math.radians(b.helix_angle))
    assert len(got) == n + 1 and np.allclose(got, want, rtol=0, atol=LENGTH)


# ------------------------------------------------------------------ parts and refusals
CHIP_REACH = (3e-4 - 1e-4) / math.sqrt(2) + 1e-4 / 2  # its corner sphere's far side


@pytest.mark.parametrize("part, wide, tall, reach", [
    ({"shape": 0, "part_size": 3e-4}, 3e-4, 3e-4, 1.5e-4),
    ({"shape": 0, "part_size": 3e-4, "size_spread": 0.2}, 3.6e-4, 3.6e-4, 1.8e-4),  # the largest
    ({"part_size": 3e-4, "size_spread": 0.2}, 3.6e-4, 3.6e-4, 1.8e-4),  # no shape: a sphere
    ({"shape": 1, "part_size": 3e-4, "part_thickness": 1e-4, "size_spread": 0.2}, 3e-4, 1e-4, CHIP_REACH),
    ({"shape": 1, "part_size": 3e-4}, 3e-4, 3e-4, 1.5e-4),  # as thick as wide: one sphere
    ({"shape": 2, "part_size": 3e-4, "part_thickness": 1e-4, "size_spread": 0.2}, 3e-4, 1e-4, 1.5e-4),
    ({"shape": 2, "part_size": 3e-4}, 3e-4, 3e-4, 1.5e-4),
])
def test_a_parts_width_height_and_reach_from_its_shape(part, wide, tall, reach):
    assert widest_part(part) == pytest.approx(wide, rel=1e-12, abs=0)
    assert tallest_part(part) == pytest.approx(tall, rel=1e-12, abs=0)
    assert part_reach(part) == pytest.approx(reach, rel=1e-12, abs=0)


def test_the_pile_and_the_track_are_filled_unless_both_are_set_to_zero():
    check_bowl({**PARAMS, "n_parts": 0, "n_track": 1})
    check_bowl({**PARAMS, "n_parts": 1, "n_track": 0})
    without = {k: v for k, v in PARAMS.items() if k not in ("n_parts", "n_track")}
    check_bowl(without)  # absent: the deck's defaults fill both
    check_bowl({**without, "n_parts": 0})
    check_bowl({**without, "n_track": 0})


def test_the_chute_must_leave_the_bowl_by_more_than_a_part():
    """Its inner edge leaves the wall after sqrt(R^2 - (R - w)^2) / cos(helix_angle); the
    chute must reach beyond that by more than the widest part: at exactly that, refused."""
    b = bowl_from(PARAMS)
    exit_length = math.sqrt(0.01 ** 2 - 0.0088 ** 2) / math.cos(math.radians(3))
    assert b.chute_exit_length == pytest.approx(exit_length, rel=1e-12, abs=0)
    edge = b.chute_exit_length + 3e-4
    with pytest.raises(ParameterError, match="ends inside the bowl"):
        check_bowl({**PARAMS, "chute_length": edge})
    check_bowl({**PARAMS, "chute_length": math.nextafter(edge, 1.0)})
    # the widest part of a spread: 3.6e-4
    with pytest.raises(ParameterError, match="ends inside the bowl"):
        check_bowl({**PARAMS, "size_spread": 0.2, "chute_length": edge + 5e-5})
    check_bowl({**PARAMS, "size_spread": 0.2, "chute_length": edge + 7e-5})


def test_three_parts_must_fit_between_a_turn_and_the_lip_of_the_next_at_exactly_three_accepted():
    b = bowl_from(PARAMS)
    size = 0.3 * b.pitch  # a large sphere, so that a lip of 0.1 pitch leaves room for exactly three
    lip = b.pitch - 3 * size
    assert b.pitch - lip == 3 * size  # (exact: the boundary itself)
    # (none along the track: a sphere a third of a pitch wide does not fit the pre-fill's cubes)
    tall = {**PARAMS, "part_size": size, "wall_height": 2e-3, "n_track": 0}
    check_bowl({**tall, "lip_height": lip})
    with pytest.raises(ParameterError, match="less than three parts"):
        check_bowl({**tall, "lip_height": lip * (1 + 1e-9)})
    # without a lip the whole pitch: a sphere a hair under a third of it fits, a hair over not
    third = b.pitch / 3
    check_bowl({**tall, "part_size": third * (1 - 1e-9)})
    with pytest.raises(ParameterError, match="less than three parts"):
        check_bowl({**tall, "part_size": third * (1 + 1e-9)})
    # a chip counts by its thickness, not its width
    check_bowl({**tall, "shape": 1, "part_size": 1.1e-3, "part_thickness": third * (1 - 1e-9)})


def test_a_lip_half_way_to_the_next_turn_is_refused_just_below_accepted():
    half = bowl_from(PARAMS).pitch / 2
    with pytest.raises(ParameterError, match="reaches half way"):
        check_bowl({**PARAMS, "lip_height": half})
    check_bowl({**PARAMS, "lip_height": math.nextafter(half, 0.0)})


@pytest.mark.parametrize("change, words", [
    ({"turns": 0.0}, "turns=0 must be > 0"),
    ({"turns": -0.5}, "turns=-0.5 must be > 0"),
    ({"helix_angle": 0.0}, "helix_angle=0 deg must be in"),
    ({"helix_angle": 45.0}, "helix_angle=45 deg must be in"),
    ({"track_width": math.nextafter(3e-4, 0.0)}, "narrower than a part"),
    ({"size_spread": 0.2, "track_width": 3.5e-4}, "narrower than a part"),
    ({"track_width": 5e-3, "chute_length": 2e-2}, "fill the bowl"),
    ({"wall_height": 3e-4}, "no higher than a part"),
    ({"shape": 1, "part_thickness": 1e-4, "wall_height": 1e-4}, "no higher than a part"),
])
def test_the_refusals_at_their_boundaries(change, words):
    with pytest.raises(ParameterError, match=words):
        check_bowl({**PARAMS, **change})


@pytest.mark.parametrize("change", [
    {"turns": 0.1},
    {"helix_angle": 44.9},
    {"track_width": 3e-4, "n_track": 0},                         # exactly a part wide (the pre-fill's
    {"size_spread": 0.2, "track_width": 3.6e-4, "n_track": 0},   # cubes hold none): the largest
    {"track_width": math.nextafter(5e-3, 0.0), "chute_length": 2e-2},  # just under a quarter
    {"wall_height": math.nextafter(3e-4, 1.0)},                  # just higher than a part
    {"shape": 1, "part_thickness": 1e-4, "wall_height": 1.5e-4},  # a chip: higher than it is thick
])
def test_just_inside_the_boundaries_is_accepted(change):
    check_bowl({**PARAMS, **change})


def test_a_bowl_without_the_optional_keys_has_no_cone_tilt_lip_or_chute():
    required = {k: PARAMS[k] for k in ("bowl_diameter", "track_width", "helix_angle", "turns", "wall_height")}
    b = bowl_from(required)
    assert (b.radius, b.track_width, b.helix_angle, b.turns, b.wall_height) == (0.01, 1.2e-3, 3.0, 1.5, 1e-3)
    assert (b.cone_angle, b.cross_tilt, b.lip_height, b.chute_length) == (0.0, 0.0, 0.0, 0.0)
    assert (b.drop_from, b.drop_to, b.drop_width) == (0.0, 0.0, 0.0) and b.drop is None
    assert (b.wiper_height, b.wiper_at, b.wiper_length) == (0.0, 0.5, 0.0) and b.wiper is None
    bare = Bowl(radius=0.01, track_width=1.2e-3, helix_angle=3.0, turns=1.5, wall_height=1e-3)
    assert (bare.cone_angle, bare.cross_tilt, bare.lip_height, bare.chute_length) == (0.0, 0.0, 0.0, 0.0)
    assert (bare.drop_from, bare.drop_to, bare.drop_width) == (0.0, 0.0, 0.0)
    assert (bare.wiper_height, bare.wiper_at, bare.wiper_length) == (0.0, 0.5, 0.0) and bare.wiper is None
    # a wiper given its height only: half way up the helix (and, from a deck, a part long)
    wiper = bowl_from({**required, "wiper_height": 4e-4, "part_size": 3e-4})
    t0, t1 = wiper.wiper
    assert wiper.arc_length(t0) == pytest.approx(wiper.length / 2, rel=1e-12, abs=0)
    assert wiper.arc_length(t1) - wiper.arc_length(t0) == pytest.approx(3e-4, rel=1e-9, abs=0)
    # so: a flat bottom, a floor level across, no chute
    assert bare.bottom_z(0.0) == 0.0 and bare.floor_z(-2.0, 0.0088) == bare.floor_z(-2.0, 0.01)
    assert bare.outlet_x == 0.0


def test_a_bowl_and_the_drive_it_gives_are_values():
    with pytest.raises(FrozenInstanceError):
        BOWL.radius = 0.02
    assert hash(BOWL) == hash(replace(BOWL))
    with pytest.raises(FrozenInstanceError):
        track_drive(5e-5, 3e-5, 0.0, 100.0, 3.0, 9.4e-3).phase = 10.0


@pytest.mark.parametrize("phase", [0.0, 30.0, 180.0, -90.0])
def test_with_one_of_the_motions_zero_the_phase_is_zero(phase):
    """On a level track (helix_angle 0) the torsion is all tangential and the lift all normal:
    with one of them zero the phase between them means nothing and is 0 (not NaN, not the
    drive's phase)."""
    lift = track_drive(0.0, 3e-5, phase, 100.0, 0.0, 9.4e-3)
    assert lift.amp_t == 0.0 and lift.phase == 0.0
    assert lift.amp_n == pytest.approx(3e-5, rel=1e-12, abs=0)
    torsion = track_drive(5e-5, 0.0, phase, 100.0, 0.0, 9.4e-3)
    assert torsion.amp_n == 0.0 and torsion.phase == 0.0
    assert torsion.amp_t == pytest.approx(5e-5, rel=1e-12, abs=0)
    still = track_drive(0.0, 0.0, phase, 100.0, 3.0, 9.4e-3)
    assert (still.amp_t, still.amp_n, still.phase, still.centripetal) == (0.0, 0.0, 0.0, 0.0)


# ------------------------------------------------------------------ the pre-fill's cubes
FILLED = [BOWL, replace(BOWL, cone_angle=5.0, cross_tilt=10.0),
          replace(BOWL, cone_angle=0.0, cross_tilt=0.0, chute_length=1.1e-2)]


def expected_cubes(b, start, size):
    """By hand: cube centres every side (0.6 track_width) along the centre line from ``start``
    turns and one side after the track's start up to half a side before its end, then back
    from a part's ``size`` before the outlet edge (the last cube's end there) every side along
    the chute while a whole side clear of the helix's end."""
    side, r_mid = 0.6 * b.track_width, b.radius - b.track_width / 2
    step = side / r_mid
    first = -math.pi / 2 - 2 * math.pi * b.turns + 2 * math.pi * start + step
    thetas = []
    while first + len(thetas) * step < -math.pi / 2 - step / 2:
        thetas.append(first + len(thetas) * step)
    last = b.chute_length * math.cos(math.radians(b.helix_angle)) - size  # a part short of the edge
    xs = last - side / 2 - side * np.arange(math.floor((last - side / 2) / side + 1e-9))
    return np.array(thetas), xs[::-1]


@pytest.mark.parametrize("b", FILLED)
@pytest.mark.parametrize("start", [None, 0.5])
def test_the_fill_cubes_lie_a_side_apart_along_the_centre_line_from_start_turns_on(b, start):
    size, height = 3e-4, 7.5e-4
    boxes = np.array(fill_boxes(b, size, height) if start is None else fill_boxes(b, size, height, start))
    thetas, xs = expected_cubes(b, 0.25 if start is None else start, size)
    assert len(boxes) == len(thetas) + len(xs)
    side, r_mid = 0.6 * b.track_width, b.radius - b.track_width / 2
    x0, x1, y0, y1, z0, z1 = boxes.T
    assert np.allclose(x1 - x0, side, rtol=0, atol=LENGTH) and np.allclose(y1 - y0, side, rtol=0, atol=LENGTH)
    assert np.allclose(z1 - z0, height, rtol=0, atol=LENGTH)
    centre = np.column_stack([(x0 + x1) / 2, (y0 + y1) / 2])
    n = len(thetas)
    assert np.allclose(centre[:n], r_mid * np.column_stack([np.cos(thetas), np.sin(thetas)]),
                       rtol=0, atol=LENGTH)
    assert np.allclose(centre[n:], np.column_stack([xs, np.full(len(xs), -r_mid)]), rtol=0, atol=LENGTH)
    # the first cube: one side past start turns along the path
    cos_a = math.cos(math.radians(b.helix_angle))
    s = path_coordinate(b, [[*centre[0], z0[0]]])[0]
    assert s == pytest.approx((2 * math.pi * r_mid * (0.25 if start is None else start) + side) / cos_a,
                              rel=0, abs=LENGTH)
    # on the chute: a twentieth of a part above its floor's highest point under the cube, at
    # its far inner corner (the chute rises along x and is tilted down outwards); the last
    # cube ends a part's size before the outlet edge
    end_z = float(hand_floor(b, -math.pi / 2, r_mid))
    floor = end_z + (xs + side / 2) * tan(b.helix_angle) + side / 2 * tan(b.cross_tilt)
    assert np.allclose(z0[n:], floor + 0.05 * size, rtol=0, atol=LENGTH)
    assert x1[-1] == pytest.approx(b.chute_length * cos_a - size, rel=0, abs=LENGTH)


def test_the_fill_cubes_keep_half_a_side_before_the_helixs_end_and_a_side_after_it():
    """A start putting a cube's centre 0.4 of a side before the helix's end (it would reach
    into the chute's first cube: none there, the last 1.4 sides before the end), and a chute
    11.5 sides and a part long (its first cube exactly a side past the end: there)."""
    side, r_mid, a = 0.72e-3, 9.4e-3, math.radians(3.0)
    b = replace(BOWL, chute_length=(11.5 * side + 3e-4) / math.cos(a))
    step = side / r_mid
    span = 3 * math.pi
    k = math.floor(span / step - 1.4)
    start = (span - (1.4 + k) * step) / (2 * math.pi)
    boxes = np.array(fill_boxes(b, 3e-4, 7.5e-4, start))
    thetas, xs = expected_cubes(b, start, 3e-4)
    assert len(thetas) == k and len(xs) == 11 and len(boxes) == k + 11
    centre = np.column_stack([(boxes[:, 0] + boxes[:, 1]) / 2, (boxes[:, 2] + boxes[:, 3]) / 2])
    last = -math.pi / 2 - 1.4 * step
    assert np.allclose(centre[k - 1], [r_mid * math.cos(last), r_mid * math.sin(last)], rtol=0, atol=LENGTH)
    assert np.allclose(centre[k:, 0], side * np.arange(1, 12), rtol=0, atol=LENGTH)


@pytest.mark.parametrize("size", [3e-4, 1e-3])
def test_the_prepared_lines_hold_the_bowls_geometry_and_one_region_per_cube_from_1(tmp_path, size):
    import re

    from vibrofeed.bowl import write_bowl

    lines = write_bowl({k: str(v) for k, v in {**PARAMS, "part_size": size}.items()}, tmp_path)
    got = {k: float(v) for k, v in re.findall(r"variable bowl_(\w+) equal (\S+)", "".join(lines))}
    r_mid, a, t = 9.4e-3, math.radians(3.0), math.tan(math.radians(3.0))
    pitch = 2 * math.pi * r_mid * t
    z0 = 0.6e-3 * t  # the start's centre line: w/2 tan(tilt), the cone as steep as the tilt
    want = {"r_mid": r_mid, "pitch": pitch, "end_z": z0 + 1.5 * pitch,
            "top": z0 + 1.5 * pitch - 0.6e-3 * t + 1e-3,
            "outlet_x": 8e-3 * math.cos(a), "length": 3 * math.pi * r_mid / math.cos(a),
            "theta_start": -3.5 * math.pi, "slot": math.acos(0.88)}
    for name, value in want.items():
        assert got[name] == pytest.approx(value, rel=1e-12, abs=1e-15), name
    boxes = [line.split() for line in lines if line.startswith("region track_fill_")]
    n = int(got["fill_boxes"])
    assert n == len(boxes) > 50
    assert [b[1] for b in boxes] == [f"track_fill_{k}" for k in range(1, n + 1)]
    union = f"region track_fill union {n} {' '.join(f'track_fill_{k}' for k in range(1, n + 1))} units box\n"
    assert lines[-1] == union
    corners = np.array([[float(c) for c in b[3:9]] for b in boxes])
    # the cubes' height: 2.5 part reaches (r_ext, here the radius) up, below 1.5 parts under the
    # next turn (a 1 mm sphere: 1.6 mm, not 2.5)
    height = min(2.5 * size, pitch - 1.5 * size)
    assert np.allclose(corners[:, 5] - corners[:, 4], height, rtol=0, atol=LENGTH)


@pytest.mark.parametrize("dz", [-0.6e-3, 0.0, 1.5e-4])
def test_the_chute_begins_on_the_ends_radial_line(dz):
    """From x = 0 on, the chute decides where a point over it is: at x = 0 as just after, at
    the helix's end (the chute takes points down to a track width under its floor)."""
    r_mid, a = 9.4e-3, math.radians(3.0)
    end = float(hand_floor(BOWL, -math.pi / 2, r_mid))
    length = 3 * math.pi * r_mid / math.cos(a)
    for x in (0.0, 1e-6, 1e-3):
        z = end + x * math.tan(a) + dz
        s = path_coordinate(BOWL, [[x, -r_mid, z]])[0]
        assert s == pytest.approx(length + x / math.cos(a), rel=0, abs=LENGTH), x


@pytest.mark.parametrize("b", FILLED + [replace(BOWL, cross_tilt=30.0),
                                        replace(BOWL, cross_tilt=45.0, turns=2.3),
                                        replace(BOWL, helix_angle=8.0, cross_tilt=0.0),
                                        replace(BOWL, track_width=2.4e-3, cross_tilt=0.0)])
def test_each_fill_cube_stands_a_twentieth_of_a_part_above_the_highest_floor_under_it(b):
    """LIGGGHTS inserts parts anywhere in a cube (all_in): its bottom must clear the floor
    everywhere under it. The cubes are the region blocks, square to x and y, so round the
    helix they stand turned against it, up to 45 deg: the highest floor under one (the helix's,
    by hand, on a fine grid over the cube) is then at a corner reaching up the helix or inwards
    as much as at its side's middle."""
    size = 3e-4
    thetas, _ = expected_cubes(b, 0.25, size)
    boxes = fill_boxes(b, size, 7.5e-4)
    g = np.linspace(0.0, 1.0, 121)  # 6 um apart: the grid's maximum is the floor's to 1e-10 m
    for t, (x0, x1, y0, y1, z0, _z1) in zip(thetas, boxes):
        x, y = np.meshgrid(x0 + (x1 - x0) * g, y0 + (y1 - y0) * g)
        theta = t + np.mod(np.arctan2(y, x) - t + math.pi, 2 * math.pi) - math.pi
        highest = float(np.max(hand_floor(b, theta, np.hypot(x, y))))
        assert z0 == pytest.approx(highest + 0.05 * size, rel=0, abs=LENGTH), (t, z0 - highest)


def test_the_refusals_say_what_is_wrong_in_numbers():
    """Each message names the parameter with its value and the number it fails (by hand)."""
    pitch = 2 * math.pi * 9.4e-3 * tan(0.5)
    pitch15 = 2 * math.pi * 9.4e-3 * tan(1.5)
    exit_length = math.sqrt(0.01 ** 2 - 0.0088 ** 2) / math.cos(math.radians(3))
    for change, message in [
        ({"turns": 0}, "turns=0 must be > 0: the track climbs at least part of a turn"),
        ({"helix_angle": 50}, "helix_angle=50 deg must be in (0, 45): the track climbs"),
        ({"track_width": 2e-4}, "track_width=0.0002 m is narrower than a part (0.0003 m across)"),
        ({"size_spread": 0.5, "track_width": 4e-4},
         "track_width=0.0004 m is narrower than a part (0.00045 m across)"),
        ({"helix_angle": 0.5}, f"helix_angle=0.5 deg rises {pitch:.3g} m per turn, less than three parts "
                               "(0.0009 m) above the turn below"),
        ({"shape": 1, "part_thickness": 2e-4, "helix_angle": 0.5},
         f"rises {pitch:.3g} m per turn, less than three parts (0.0006 m)"),
        ({"chute_length": 4e-3},
         f"chute_length=0.004 m ends inside the bowl: its inner edge leaves the wall after "
         f"{exit_length:.3g} m; make it longer than {exit_length + 3e-4:.3g} m"),
        ({"wall_height": 2e-4}, "wall_height=0.0002 m is no higher than a part (0.0003 m)"),
        ({"shape": 2, "part_thickness": 1e-4, "wall_height": 1e-4},
         "wall_height=0.0001 m is no higher than a part (0.0001 m)"),
        ({"track_width": 6e-3}, "track_width=0.006 m is more than a quarter of bowl_diameter=0.02 m"),
        ({"lip_height": 2e-3}, "lip_height=0.002 m reaches half way to the next turn"),
        # the lip stands in the room between turns: its height is named with the helix's
        ({"helix_angle": 1.5, "lip_height": 7e-4},
         f"helix_angle=1.5 deg rises {pitch15:.3g} m per turn, and lip_height=0.0007 m leaves "
         f"{pitch15 - 7e-4:.3g} m of it, less than three parts (0.0009 m) above the turn below: parts "
         "would jam between turns; a lower lip, a steeper helix or a wider bowl"),
        ({"lip_height": 1e9}, "lip_height=1e+09 m reaches half way to the next turn"),
    ]:
        with pytest.raises(ParameterError) as refused:
            check_bowl({**PARAMS, **change})
        assert message in str(refused.value), (change, str(refused.value))


def test_beside_the_chute_and_off_the_track_there_is_no_coordinate():
    """NaN: in the pile on the cone (inside the track's inner edge, at any angle, however high
    the floor's extension inwards would be), just outside the wall at a turn's height, and
    beside the chute, outside its walls."""
    r_in, r_mid = 8.8e-3, 9.4e-3
    points = []
    for theta in np.linspace(-math.pi, math.pi, 13)[:-1]:
        for r in (2e-3, 5e-3, 8.5e-3):  # resting on the cone: its centre a part's radius above
            points.append([r * math.cos(theta), r * math.sin(theta), (0.01 - r) * tan(3) + 1.5e-4])
    for theta in (-9.0, -6.0, -4.0, -2.0):  # outside the wall, level with a turn over its floor
        r, z = 0.0105, float(hand_floor(BOWL, theta, 0.01)) + 1.5e-4
        points.append([r * math.cos(theta), r * math.sin(theta), z])
    end = float(hand_floor(BOWL, -math.pi / 2, r_mid))
    for x in (1e-3, 3e-3, 7e-3):
        z = end + x * tan(3) + 1.5e-4
        points += [[x, -0.01 - 3e-4, z], [x, -0.01 - 1e-5, z]]  # outside the outer chute wall
    s = path_coordinate(BOWL, points)
    assert np.isnan(s).all(), np.array(points)[np.isfinite(s)]
    # ... while just inside the chute's walls it is on the chute
    for x in (1e-3, 7e-3):
        inside = [[x, y, end + x * tan(3) + 1.5e-4] for y in (-0.01 + 1e-5, -r_in - 1e-5)]
        length = 3 * math.pi * r_mid / math.cos(math.radians(3)) + x / math.cos(math.radians(3))
        assert np.allclose(path_coordinate(BOWL, inside), length, rtol=0, atol=LENGTH)


@pytest.mark.parametrize("b, n", [(BOWL, 2), (WIDE, 1),
                                  (replace(BOWL, chute_length=2e-2, cross_tilt=8.0), 5)])
def test_the_chutes_floor_and_walls_stand_on_the_helixs_end_along_its_tangent(b, n):
    """Its vertices by hand: at each piece's end x_k, the floor's edges at y = -(R - w) and
    y = -R, as high as the helix's end there plus x_k tan(helix_angle), and the walls' tops
    wall_height above; outside the bowl's radius the mesh has no other vertex."""
    vertices, _ = bowl_mesh(b)
    R, w, a = b.radius, b.track_width, math.radians(b.helix_angle)
    want = []
    for x in np.arange(n + 1) * b.chute_length / n * math.cos(a):
        for r in (R - w, R):
            z = float(hand_floor(b, -math.pi / 2, r)) + x * math.tan(a)
            want += [[x, -r, z], [x, -r, z + b.wall_height]]
    want = np.array(want)
    for p in want:
        assert has_vertex(vertices, p), p
    outside = vertices[np.hypot(vertices[:, 0], vertices[:, 1]) > R + LENGTH]
    assert len(outside) > 0
    for p in outside:
        assert has_vertex(want, p), p


TEN_ARCS = 10 * 0.01 * STEP / (2 * math.pi * 9.4e-3 * tan(3.0))  # turns: a slot floor ten arcs up


@pytest.mark.parametrize("turns, rows", [(1.5, 1), (3.5, 2), (6.0, 2), (10.0, 3), (TEN_ARCS, 1)])
def test_the_wall_below_the_slot_is_in_rows_no_higher_than_ten_station_arcs(turns, rows):
    """Faces no thinner than 5 deg (LIGGGHTS refuses slivers): the wall up to the slot's floor
    (z_slot, 4.6 mm for 1.5 turns, 10.8 mm for 3.5, 18.5 mm for 6, 30.9 mm for 10, 10.5 mm
    for 3.38: one pitch a turn above the bottom at the wall, the cone as steep as the tilt) in
    as few equal rows as keep them within ten arcs of 6 deg at R = 10 mm (10.5 mm), over the
    slot's floor one band to the top."""
    b = replace(BOWL, turns=turns)
    vertices, triangles = bowl_mesh(b)
    R = b.radius
    z_slot = float(hand_floor(b, -math.pi / 2, R))
    wall = triangles[np.all(on_radius(vertices, R)[triangles], axis=1)]
    far = vertices[np.unique(wall)]
    far = far[np.abs(far[:, 0] - (-R)) < LENGTH]  # the station opposite the track's end
    assert np.allclose(np.sort(far[:, 2]), np.r_[np.linspace(0, z_slot, rows + 1), z_slot + b.wall_height],
                       rtol=0, atol=LENGTH)
    chord = 2 * R * math.sin(STEP / 2)
    assert areas(vertices, wall).sum() == pytest.approx(chord * (60 * z_slot + 55 * b.wall_height),
                                                        rel=1e-9, abs=AREA)
    corners = vertices[wall]
    smallest = []
    for k in range(3):
        u = corners[:, (k + 1) % 3] - corners[:, k]
        v = corners[:, (k + 2) % 3] - corners[:, k]
        cos = np.sum(u * v, axis=1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        smallest.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    assert np.min(smallest) > 5.0


@pytest.mark.parametrize("r", ["inner", "outer"])
def test_the_tracks_width_includes_both_its_edges(r):
    """A point over the floor's inner edge (r = R - w) or at the wall (r = R), at polar angle
    90 deg (the first turn's start, and half a turn up the second), resting a part's radius
    above the floor, is on the track."""
    radius = BOWL.radius - BOWL.track_width if r == "inner" else BOWL.radius
    a = math.radians(3.0)
    for turn in (0, 1):
        theta = math.pi / 2 + 2 * math.pi * (turn - 2)
        z = float(hand_floor(BOWL, theta, radius)) + 1.5e-4
        s = path_coordinate(BOWL, [[0.0, radius, z]])[0]
        assert s == pytest.approx(2 * math.pi * turn * 9.4e-3 / math.cos(a), rel=0, abs=LENGTH), turn


def test_a_negative_lip_counts_as_none_in_the_refusals_too():
    """(The parameter rules refuse it.) The room between turns is the whole pitch, no more."""
    big = {**PARAMS, "part_size": 1.1e-3, "wall_height": 2e-3}  # 3.3 mm: more than the pitch
    with pytest.raises(ParameterError, match="less than three parts"):
        check_bowl({**big, "lip_height": -5e-4})


def test_past_the_tracks_end_above_the_last_turn_there_is_no_coordinate():
    """Past the helix's end (polar angles -66 to -36 deg, beside the chute), where the last turn
    would go on if it did not end: no turn, a pitch over the turn below. Just below, on that
    turn below, a coordinate a turn back."""
    r_mid, a = 9.4e-3, math.radians(3.0)
    for deg in (-66.0, -50.0, -36.0):
        theta = math.radians(deg)
        on_next = float(hand_floor(BOWL, theta, r_mid))  # the last turn's floor, continued
        point = [r_mid * math.cos(theta), r_mid * math.sin(theta), on_next + 1.5e-4]
        assert np.isnan(path_coordinate(BOWL, [point])[0]), deg
        point[2] -= 2 * math.pi * r_mid * math.tan(a)  # a pitch down: on the turn below
        s = path_coordinate(BOWL, [point])[0]
        below = theta - 2 * math.pi
        assert s == pytest.approx((below + 3.5 * math.pi) * r_mid / math.cos(a), rel=0, abs=LENGTH)


@pytest.mark.parametrize("tilt", [3.0, 10.0])
def test_the_chute_holds_points_from_a_width_under_its_floor_to_a_pitch_over_it(tilt):
    """Over the chute, off its centre line too (its floor tilted across), from a track width
    under its floor (a part sunk in) up to, not including, a pitch over it (where the next
    turn would be): at 1 um inside either edge on the chute, 1 um outside not."""
    b = replace(BOWL, cross_tilt=tilt)
    r_mid, w, a = 9.4e-3, 1.2e-3, math.radians(3.0)
    pitch = 2 * math.pi * r_mid * math.tan(a)
    end = float(hand_floor(b, -math.pi / 2, r_mid))
    for x in (3e-3, 7e-3):
        for off in (-0.5e-3, 0.0, 0.5e-3):  # outwards, on the centre line, inwards
            floor = end + x * math.tan(a) + off * tan(tilt)
            y = -r_mid + off
            inside = path_coordinate(b, [[x, y, floor - w + 1e-6], [x, y, floor + pitch - 1e-6]])
            want = (3 * math.pi * r_mid + x) / math.cos(a)
            assert np.allclose(inside, want, rtol=0, atol=LENGTH)
            above = path_coordinate(b, [[x, y, floor + pitch + 1e-6]])[0]
            assert np.isnan(above), (x, off)


def test_the_chutes_width_includes_its_walls():
    """A point exactly in the plane of either chute wall, |y + r_mid| = w / 2 to the last bit,
    is on the chute (as the track's edges are on the helix). (A bowl of binary fractions,
    R = 2^-7 m, w = 2^-10 m, so that the walls' planes are numbers exactly.)"""
    R, w, a = 2.0 ** -7, 2.0 ** -10, math.radians(3.0)
    b = Bowl(radius=R, track_width=w, helix_angle=3.0, turns=1.5, wall_height=1e-3, cross_tilt=3.0,
             chute_length=8e-3)
    r_mid = R - w / 2
    x = 4e-3
    for y in (-R, -(R - w)):
        assert abs(y + b.r_mid) == w / 2
        z = float(hand_floor(b, -math.pi / 2, -y)) + x * math.tan(a) + 1.5e-4
        s = path_coordinate(b, [[x, y, z]])[0]
        assert s == pytest.approx((3 * math.pi * r_mid + x) / math.cos(a), rel=0, abs=LENGTH), y


def test_the_prepare_hook_builds_the_bowl_from_every_one_of_its_fields(tmp_path):
    """Each field of Bowl is a deck parameter the prepare hook reads: a bowl with every field
    away from its default (a side drop too) is the mesh the hook writes and hands on, and
    its stored file has as many faces (a field the hook left out built another bowl: the
    side drop once reached the refusals but not the mesh)."""
    import dataclasses

    from stl import mesh as stl_mesh

    from vibrofeed.bowl import GEOMETRY, bowl_from
    from vibrofeed.geometry import prepare_bowl_feeder

    params = {**PARAMS, "bowl_diameter": 0.024, "track_width": 1.3e-3, "helix_angle": 4.0, "turns": 1.25,
              "wall_height": 1.1e-3, "cone_angle": 4.0, "cross_tilt": 2.0, "lip_height": 2e-4,
              "chute_length": 9e-3, "drop_from": 0.6, "drop_to": 0.85, "drop_width": 5e-4,
              "wiper_height": 4.5e-4, "wiper_at": 0.3}
    b = bowl_from(params)
    defaults = {f.name: f.default for f in dataclasses.fields(Bowl)}
    # every field differs from its default and from the module's BOWL
    for f in dataclasses.fields(Bowl):
        assert getattr(b, f.name) != getattr(BOWL, f.name), f.name
        assert f.default is dataclasses.MISSING or getattr(b, f.name) != defaults[f.name], f.name
    # (the wiper's bar is a part size long: part_size is among the parts' parameters)
    assert set(GEOMETRY) >= {"bowl_diameter", *[f.name for f in dataclasses.fields(Bowl)
                                                if f.name not in ("radius", "wiper_length")]}
    values = {k: str(v) for k, v in params.items()} | {"seed": "5489"}
    prepared = prepare_bowl_feeder(values, tmp_path)
    want_v, want_t = bowl_mesh(b)
    np.testing.assert_array_equal(prepared.track[0], want_v)
    np.testing.assert_array_equal(prepared.track[1], want_t)
    assert len(stl_mesh.Mesh.from_file(str(tmp_path / "bowl.stl")).vectors) == len(want_t)
