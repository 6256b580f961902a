"""The bowl's mesh is one LIGGGHTS accepts, whatever the bowl: mesh/surface refuses a
triangle whose smallest angle is below its curvature setting (0.256 deg by default; a 6 deg
helix's first mesh left a 0.17 deg sliver of wall beside the chute's slot)."""

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from vibrofeed.bowl import Bowl, bowl_mesh

LIGGGHTS_CURVATURE = 0.256  # [deg]


def smallest_angles(vertices, triangles) -> np.ndarray:
    p = vertices[triangles]
    out = []
    for i in range(3):
        u = p[:, (i + 1) % 3] - p[:, i]
        v = p[:, (i + 2) % 3] - p[:, i]
        cos = (u * v).sum(axis=1) / (np.linalg.norm(u, axis=1) * np.linalg.norm(v, axis=1))
        out.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return np.min(out, axis=0)


@settings(max_examples=40, deadline=None)
@given(st.floats(1.0, 44.0), st.floats(0.25, 4.0), st.floats(0.0, 10.0), st.floats(0.0, 10.0),
       st.sampled_from([0.0, 2e-4]), st.floats(0.006, 0.05))
def test_every_face_is_wider_than_liggghts_curvature(helix, turns, cone, tilt, lip, diameter):
    b = Bowl(radius=diameter / 2, track_width=1.2e-3, helix_angle=helix, turns=turns, wall_height=1e-3,
             cone_angle=cone, cross_tilt=tilt, lip_height=lip, chute_length=diameter)
    vertices, triangles = bowl_mesh(b)
    assert smallest_angles(vertices, triangles).min() > 2 * LIGGGHTS_CURVATURE


def test_the_sliver_beside_the_slot_is_gone():
    b = Bowl(radius=0.01, track_width=1.2e-3, helix_angle=6.0, turns=1.5, wall_height=1e-3,
             cone_angle=3.0, chute_length=8e-3)
    assert smallest_angles(*bowl_mesh(b)).min() >= 1.0  # [deg]


@settings(max_examples=40, deadline=None)
@given(st.floats(1.0, 20.0), st.floats(0.25, 3.0), st.floats(0.0, 10.0), st.floats(0.0, 10.0),
       st.floats(0.0, 0.9), st.floats(0.05, 1.0), st.floats(3e-4, 1.125e-3))
def test_with_a_side_drop_every_face_is_wider_than_liggghts_curvature_and_no_edge_is_open_twice(
        helix, turns, cone, tilt, start, length, width):
    """Any side drop check_bowl accepts (300 um parts): the faces' smallest angles, and every
    edge shared by at most two faces (the narrow floor meets the wide one edge to edge)."""
    from hypothesis import assume

    from vibrofeed.bowl import check_bowl
    from vibrofeed.errors import ParameterError

    end = min(start + length, 1.0)
    p = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": helix, "turns": turns,
         "wall_height": 1e-3, "cone_angle": cone, "cross_tilt": tilt, "chute_length": 0.02,
         "part_size": 3e-4, "drop_from": start, "drop_to": end, "drop_width": width}
    try:
        check_bowl(p)
    except ParameterError:
        assume(False)
    b = Bowl(radius=0.01, track_width=1.2e-3, helix_angle=helix, turns=turns, wall_height=1e-3,
             cone_angle=cone, cross_tilt=tilt, chute_length=0.02, drop_from=start, drop_to=end,
             drop_width=width)
    vertices, triangles = bowl_mesh(b)
    assert smallest_angles(vertices, triangles).min() > 2 * LIGGGHTS_CURVATURE
    pairs = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [0, 2]]])
    edges = np.sort(pairs, axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    assert counts.max() <= 2


@settings(max_examples=40, deadline=None)
@given(st.floats(1.0, 44.0), st.floats(0.25, 3.0), st.floats(0.0, 10.0), st.floats(0.0, 10.0),
       st.floats(0.0, 1.0), st.floats(3e-4, 3e-2), st.floats(0.006, 0.05))
@example(44.0, 3.0, 0.0, 0.0, 0.0, 1e-3, 0.05)  # the tallest face: 0.13 m on a 1.2 mm track
def test_with_a_wiper_every_face_is_wider_than_liggghts_curvature(helix, turns, cone, tilt, at, height,
                                                                 diameter):
    """Any wiper check_bowl accepts (300 um spheres), on any bowl: its bar and its face (in rows
    under a tall pitch) keep every face's smallest angle clear of LIGGGHTS' curvature."""
    from hypothesis import assume

    from vibrofeed.bowl import bowl_from, check_bowl
    from vibrofeed.errors import ParameterError

    p = {"bowl_diameter": diameter, "track_width": 1.2e-3, "helix_angle": helix, "turns": turns,
         "wall_height": 1e-3, "cone_angle": cone, "cross_tilt": tilt, "chute_length": diameter,
         "part_size": 3e-4, "wiper_height": height, "wiper_at": at}
    try:
        check_bowl(p)
    except ParameterError:
        assume(False)
    vertices, triangles = bowl_mesh(bowl_from(p))
    assert smallest_angles(vertices, triangles).min() > 2 * LIGGGHTS_CURVATURE
