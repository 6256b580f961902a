"""The wiper on a bowl's helix (the feeder lines' tooling): a bar across the track at
wiper_at of the helix's length, a part size long, its underside wiper_height above the floor
and its upstream face up to WIPER_REACH of a pitch above the floor (or the wall's top): a part
lying flat passes under it, a taller one is stopped. No fill cube under it; the refusals at
their boundaries."""

import math
from dataclasses import replace

import numpy as np
import pytest
from test_bowl_drop import FACET, crossings

from vibrofeed.bowl import THETA_END, WIPER_REACH, bowl_from, bowl_mesh, check_bowl, fill_boxes
from vibrofeed.errors import ParameterError

SIZE, THICK, H = 3e-4, 1.5e-4, 2.5e-4  # [m] chips' edge and thickness, the wiper's clearance
PARAMS = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
          "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "chute_length": 8e-3,
          "shape": 1, "part_size": SIZE, "part_thickness": THICK, "wiper_height": H, "wiper_at": 0.2}
B = bowl_from(PARAMS)
LENGTH = 1e-9  # [m]
AREA = 1e-15  # [m^2]


def test_the_wiper_stands_at_its_fraction_of_the_helix_and_is_a_part_long():
    t0, t1 = B.wiper
    assert B.arc_length(t0) == pytest.approx(0.2 * B.length, rel=1e-12, abs=0)
    assert B.arc_length(t1) - B.arc_length(t0) == pytest.approx(SIZE, rel=1e-9, abs=0)
    assert bowl_from({**PARAMS, "wiper_height": 0}).wiper is None


@pytest.mark.parametrize("r", [B.radius - 1.1e-3, B.r_mid, B.radius - 0.1e-3])
def test_under_the_bar_a_part_lying_flat_has_its_clearance_and_beside_it_none(r):
    """A vertical line through the bar (in the first turn, a turn above it) meets the bottom,
    the floor, the underside wiper_height above it (to the floor's faceting) and the next
    turn; just upstream of the face, the bottom, the floor and the next turn only."""
    vertices, triangles = bowl_mesh(B)
    t0, t1 = B.wiper
    for theta, want in ((0.5 * (t0 + t1), [0.0, H, None]), (t0 - 0.5 * (t1 - t0), [0.0, None])):
        floor, turn = float(B.floor_z(theta, r)), float(B.floor_z(theta + 2 * math.pi, r))
        z = crossings(vertices, triangles, r * math.cos(theta), r * math.sin(theta))
        heights = [float(B.bottom_z(r))] + [floor + w if w is not None else turn for w in want]
        assert z == pytest.approx(heights, rel=0, abs=FACET)


def test_the_bars_face_rises_from_its_underside_to_under_the_next_turn():
    """The wiper adds its underside (2 triangles) and its face: a radial trapezoid at the
    face's polar angle from wiper_height above the floor to WIPER_REACH of a pitch above it,
    whose area its triangles sum to exactly."""
    plain_v, plain_t = bowl_mesh(replace(B, wiper_height=0.0))
    vertices, triangles = bowl_mesh(B)
    extra = triangles[len(plain_t):]
    assert np.array_equal(vertices[:len(plain_v)], plain_v)  # the bowl unchanged, the bar added
    t0, _ = B.wiper
    p = vertices[extra]
    on_face = np.all(np.abs(np.angle(np.exp(1j * (np.arctan2(p[..., 1], p[..., 0]) - t0)))) < 1e-9, axis=1)
    assert (~on_face).sum() == 2  # the underside
    r_in, r_out = B.radius - B.track_width, B.radius
    rise = [WIPER_REACH * B.pitch - H] * 2  # [m] at both edges, under the next turn
    want = B.track_width * sum(rise) / 2
    face = p[on_face]
    area = 0.5 * np.linalg.norm(np.cross(face[:, 1] - face[:, 0], face[:, 2] - face[:, 0]), axis=1).sum()
    assert area == pytest.approx(want, rel=1e-9, abs=AREA)
    assert face[..., 2].max() == pytest.approx(float(B.floor_z(t0, r_in)) + WIPER_REACH * B.pitch,
                                               rel=0, abs=LENGTH)
    assert float(B.floor_z(t0, r_in)) + WIPER_REACH * B.pitch < B.top
    assert (face[..., 2].max() - face[..., 2].min()) < B.pitch  # below the next turn
    # (near the helix's end no turn lies above: the face stops at the wall's top)
    late = bowl_from({**PARAMS, "wiper_at": 0.9})
    assert late.wiper_top(r_out) == pytest.approx(late.top, rel=0, abs=LENGTH)


def helix_cubes(b):
    """The polar angles of the fill cubes round the helix (their centres on its centre line),
    unwrapped from the track's start, in order."""
    centres = np.array([(0.5 * (x0 + x1), 0.5 * (y0 + y1)) for x0, x1, y0, y1, *_ in
                        fill_boxes(b, SIZE, 5e-4)])
    on = np.abs(np.hypot(*centres.T) - b.r_mid) < LENGTH
    theta = np.unwrap(np.arctan2(centres[on, 1], centres[on, 0]))
    return theta + 2 * math.pi * np.ceil((b.theta_start - theta[0]) / (2 * math.pi))


def test_no_fill_cube_under_the_wiper_nor_a_side_either_side():
    """No cube's centre within the bar's stretch widened by a cube's side either side; the cubes
    the wiper takes away are exactly those."""
    dtheta = 0.6 * B.track_width / B.r_mid
    t0, t1 = B.wiper
    theta, plain = helix_cubes(B), helix_cubes(replace(B, wiper_height=0.0))
    assert len(theta) > 20
    assert not np.any((theta >= t0 - dtheta) & (theta <= t1 + dtheta))
    gone = (plain >= t0 - dtheta) & (plain <= t1 + dtheta)
    assert gone.sum() > 0 and len(theta) == len(plain) - gone.sum()


@pytest.mark.parametrize("change, words", [
    ({"wiper_height": THICK * (1 - 1e-9)}, "lower than a part lying flat"),
    ({"wiper_at": -1e-9}, r"must be in \[0, 1\)"),
    ({"wiper_at": 1.0}, r"must be in \[0, 1\)"),
    ({"wiper_at": 1 - SIZE / B.length * (1 - 1e-6)}, "runs past the helix's end"),
    ({"wiper_height": WIPER_REACH * B.pitch}, "would not exist"),
])
def test_the_wipers_refusals_at_their_boundaries(change, words):
    with pytest.raises(ParameterError, match=words):
        check_bowl({**PARAMS, **change})


@pytest.mark.parametrize("change", [
    {"wiper_height": THICK},
    {"wiper_at": 0.0},
    {"wiper_at": 1 - SIZE / B.length * (1 + 1e-9)},
    {"wiper_at": 1 - SIZE / B.length},  # the bar ends at the helix's end (to rounding)
    {"wiper_height": WIPER_REACH * B.pitch * (1 - 1e-9)},
])
def test_just_inside_the_wipers_boundaries_is_accepted(change):
    check_bowl({**PARAMS, **change})
    assert bowl_from({**PARAMS, **change}).wiper[1] <= THETA_END + 1e-12


@pytest.mark.parametrize("at", [0.2, 0.9])
def test_a_wiper_exactly_as_high_as_its_face_rises_is_refused_a_hair_lower_accepted(at):
    """The face rises WIPER_REACH of a pitch above the floor under the next turn (wiper_at 0.2),
    near the end (0.9: 0.15 of a turn below it) to the wall's top, wall_height above the end's
    outer floor edge, lowest over the inner edge, w tan(cross_tilt) above the outer one. A
    wiper whose underside is as high as that has no face: refused; a hair lower accepted."""
    b = bowl_from({**PARAMS, "wiper_at": at})
    t0, _ = b.wiper
    w, tilt = b.track_width, math.tan(math.radians(3.0))
    want = WIPER_REACH * b.pitch if at == 0.2 else 0.15 * b.pitch + 1e-3 - w * tilt
    # (the face's rise from the bowl's own surfaces, to the bit: the boundary itself)
    room = min(float(b.wiper_top(r) - b.floor_z(t0, r)) for r in (b.radius - w, b.radius))
    assert room == pytest.approx(want, rel=0, abs=LENGTH)
    with pytest.raises(ParameterError, match="would not exist"):
        check_bowl({**PARAMS, "wiper_at": at, "wiper_height": room})
    check_bowl({**PARAMS, "wiper_at": at, "wiper_height": math.nextafter(room, 0.0)})


def face_rows(b):
    """The wiper's face (its triangles at the face's polar angle, added after the bowl's): the
    distinct heights of its corners on the track's inner edge and on the wall, and its area."""
    plain_t = bowl_mesh(replace(b, wiper_height=0.0))[1]
    vertices, triangles = bowl_mesh(b)
    t0, _ = b.wiper
    p = vertices[triangles[len(plain_t):]]
    on_face = np.all(np.abs(np.angle(np.exp(1j * (np.arctan2(p[..., 1], p[..., 0]) - t0)))) < 1e-9, axis=1)
    face = p[on_face]
    area = 0.5 * np.linalg.norm(np.cross(face[:, 1] - face[:, 0], face[:, 2] - face[:, 0]), axis=1).sum()
    corners = face.reshape(-1, 3)
    r = np.hypot(corners[:, 0], corners[:, 1])
    assert np.all((np.abs(r - b.radius + b.track_width) < LENGTH) | (np.abs(r - b.radius) < LENGTH))
    levels = [np.unique(np.round(corners[np.abs(r - edge) < LENGTH, 2], 12))
              for edge in (b.radius - b.track_width, b.radius)]
    return levels, area, len(face)


# A 5 cm bowl, 2.5 turns: its 10 deg helix's face rises 0.9 pitch = 24.3 mm less the underside's
# height, its 3 deg helix's 7.2 mm; 1.5 turns of the 10 deg helix with the wiper at 0.72: the wall's
# top 0.42 pitch + 1 mm above the outer floor edge, the inner edge w tan(3 deg) = 63 um higher.
BIG = {**PARAMS, "bowl_diameter": 0.05, "turns": 2.5, "chute_length": 0.012}
PITCH_10 = 2 * math.pi * (0.025 - 0.6e-3) * math.tan(math.radians(10.0))
PITCH_3 = 2 * math.pi * (0.025 - 0.6e-3) * math.tan(math.radians(3.0))
RISE_TOP = 0.28 * 1.5 * PITCH_10 + 1e-3  # [m] the capped face's rise over the outer edge


@pytest.mark.parametrize("change, rises, rows", [
    # exactly two rows ten widths high (the face on the bowl's -y side: y = -25 mm)
    ({"helix_angle": 10.0, "wiper_at": 0.2, "wiper_height": WIPER_REACH * PITCH_10 - 24e-3},
     (24e-3, 24e-3), 2),
    # a hair over two rows' worth: three
    ({"helix_angle": 10.0, "wiper_at": 0.2, "wiper_height": WIPER_REACH * PITCH_10 - 24.001e-3},
     (24.001e-3, 24.001e-3), 3),
    # one row (on the +y side: y = +25 mm)
    ({"helix_angle": 3.0, "wiper_at": 0.4, "wiper_height": H}, (WIPER_REACH * PITCH_3 - H,) * 2, 1),
    # capped by the wall's top: the outer edge a hair over ten widths, the inner a hair under
    ({"helix_angle": 10.0, "turns": 1.5, "wiper_at": 0.72, "wiper_height": RISE_TOP - 12.03e-3},
     (12.03e-3 - 1.2e-3 * math.tan(math.radians(3.0)), 12.03e-3), 2),
])
def test_the_wipers_face_is_in_the_fewest_rows_ten_track_widths_high(change, rises, rows):
    """The face from the underside (wiper_height over the floor) up to its top, at the track's
    inner edge and at the wall, in n equal rows: n = ceil(the higher rise / (10 w)), so that no
    row is more than ten times as high as the track is wide (a sliver LIGGGHTS refuses) and
    none is added (each costs time at every step). Its area: the trapezoid's."""
    p = {**BIG, **change}
    check_bowl(p)
    b = bowl_from(p)
    t0, _ = b.wiper
    w = b.track_width
    levels, area, count = face_rows(b)
    for edge, z, rise in zip((b.radius - w, b.radius), levels, rises):
        under = float(b.floor_z(t0, edge)) + b.wiper_height
        assert z == pytest.approx(np.linspace(under, under + rise, rows + 1), rel=0, abs=LENGTH), edge
        assert np.diff(z).max() <= 10 * w + LENGTH
    assert count == 2 * rows
    # (to the corners' rounding to 1e-12 m along the face's outline, 50 mm at most)
    assert area == pytest.approx(w * sum(rises) / 2, rel=0, abs=5e-14)
