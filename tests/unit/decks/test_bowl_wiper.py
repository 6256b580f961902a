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
    {"wiper_height": WIPER_REACH * B.pitch * (1 - 1e-9)},
])
def test_just_inside_the_wipers_boundaries_is_accepted(change):
    check_bowl({**PARAMS, **change})
    assert bowl_from({**PARAMS, **change}).wiper[1] <= THETA_END + 1e-12
