"""A bowl in pictures and ParaView: its mesh turned by the recorded angle about z and lifted,
each vertex moving at the lift's rate plus the turn's rate x r."""

import math

import numpy as np

from helpers import parts
from vibrofeed.pictures.scene import read_frame, track_mesh, track_velocity
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"
REST = np.array([[0.01, 0.0, 0.0], [0.0, 0.01, 0.001], [-0.007, -0.007, 0.002]])  # [m]


def test_the_bowl_is_drawn_where_the_drive_turned_and_lifted_it(tmp_path):
    path = tmp_path / "bowl.h5"
    angles, rates, lifts, vz = [0.0, 0.01, -0.02], [1.0, -2.0, 0.5], [0.0, 2e-5, -3e-5], [0.0, 0.01, -0.02]
    w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                     variables={"freq": ("100", "Hz", "f", "100")}, derived={"dt_used": 1e-6},
                     engine_version=ENGINE, seed=1, run_id="z" * 64, recording=Recording(rotating=True),
                     track=(REST, np.array([[0, 1, 2]], dtype=np.int32)))
    for k in range(3):
        w.write_frame(k, k * 1e-3, parts([1], [[0.0, 0.0, 0.005]]), [0, 0, lifts[k]], [0, 0, vz[k]],
                      surface_rotation=([0, 0, angles[k]], [0, 0, rates[k]]))
    w.finish("complete")
    with Result(path) as r:
        for k in range(3):
            frame = read_frame(r, k)
            c, s = math.cos(angles[k]), math.sin(angles[k])
            turned = REST @ np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])  # rows: R @ p
            want = turned + [0, 0, lifts[k]]
            got, _ = track_mesh(r, frame)
            assert np.allclose(got, want, rtol=0, atol=1e-15)  # [m]
            v = track_velocity(r, frame)
            want_v = rates[k] * np.column_stack([-turned[:, 1], turned[:, 0], np.zeros(3)]) + [0, 0, vz[k]]
            assert np.allclose(v, want_v, rtol=0, atol=1e-15)  # [m/s]
