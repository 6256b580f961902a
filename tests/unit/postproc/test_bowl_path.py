"""Where a part is along a bowl's track (postproc.path): the helix's arc length of its centre
in the bowl's frame, the recorded rotation and lift undone; NaN off the track; and the
bowl's dilute limit, the single-part model under the drive the helix sees."""

import math

import numpy as np
import pytest

from helpers import parts
from vibrofeed.bowl import THETA_END, bowl_from, track_drive
from vibrofeed.postproc.feedrate import dilute_limit
from vibrofeed.postproc.path import along, path_end
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import ResultWriter

BOWL = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
        "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 3.0, "lip_height": 0.0,
        "chute_length": 8e-3, "freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -20.0,
        "mu": 0.5, "restitution": 0.3, "shape": 0, "part_size": 3e-4, "density": 2330.0}
LENGTH = 1e-9  # [m]
ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"


def write_bowl(path, angles, lifts, points):
    """A rotating result: at frame k the parts are the bowl-frame ``points`` turned by
    angles[k] about z and lifted by lifts[k], as parts riding the bowl are."""
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                     variables=variables, derived={"dt_used": 1e-6}, engine_version=ENGINE,
                     seed=1, run_id="x" * 64, rotating=True)
    for k, (a, z) in enumerate(zip(angles, lifts)):
        c, s = math.cos(a), math.sin(a)
        lab = np.column_stack([c * points[:, 0] - s * points[:, 1], s * points[:, 0] + c * points[:, 1],
                               points[:, 2] + z])
        w.write_frame(k, k * 1e-3, parts(np.arange(1, len(points) + 1), lab, radius=1.5e-4),
                      [0, 0, z], [0, 0, 0], surface_rotation=([0, 0, a], [0, 0, 0]))
    w.finish("complete")


def test_a_part_is_where_the_helix_puts_it_whatever_the_bowl_turned(tmp_path):
    b = bowl_from(BOWL)
    thetas = np.array([b.theta_start + 0.3, -8.0, -2.0, THETA_END - 0.01])  # 1.5 turns to -pi/2
    on_helix = b.helix_point(thetas) + [0, 0, 1.5e-4]  # resting on the floor
    chute = np.array([[3e-3, -b.r_mid, b.end_z + 3e-3 * math.tan(math.radians(3)) + 1.5e-4]])
    pile = np.array([[0.0, 0.0, 1e-3], [5e-3, 0.0, 6e-4]])  # inside the track's inner edge
    points = np.vstack([on_helix, chute, pile])
    angles = [0.0, 4e-3, -4e-3]  # [rad]: well beyond a drive's angle, to see it undone
    lifts = [0.0, 3e-5, -3e-5]
    write_bowl(tmp_path / "b.h5", angles, lifts, points)
    want = np.r_[b.arc_length(thetas), b.length + 3e-3 / math.cos(math.radians(3)), np.nan, np.nan]
    with Result(tmp_path / "b.h5") as r:
        s, moved = along(r, np.arange(3))
        assert path_end(r) == pytest.approx(b.length + b.chute_length, rel=1e-12, abs=0)
    for k in range(3):
        assert np.allclose(s[k], want, rtol=0, atol=LENGTH, equal_nan=True)
    assert np.array_equal(moved, s, equal_nan=True)
    # not undoing the rotation would misplace them by r * angle: 38 um at 4 mrad
    assert b.r_mid * 4e-3 > 1e4 * LENGTH


def test_a_bowls_dilute_limit_is_the_model_under_the_drive_the_helix_sees():
    from vibrofeed.models.deck import transport

    got, note = dilute_limit(BOWL)
    d = track_drive(5e-5, 3e-5, -20.0, 100.0, 3.0, bowl_from(BOWL).r_mid)
    want = transport({**BOWL, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                      "incline": d.incline}).velocity
    assert got == pytest.approx(want, rel=1e-12, abs=0) and note == ""
    flat = transport(BOWL).velocity  # the bowl's own numbers, read as a level linear track
    assert abs(got - flat) > 0.02 * abs(want)  # the projection and the climb matter
