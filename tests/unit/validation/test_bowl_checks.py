"""The bowl's dilute-limit check (validation.crosscheck.bowl_speeds): each part's speed along
the helix over whole periods, against the model at the part's own radius."""

import math

import numpy as np
import pytest

from helpers import parts
from vibrofeed.bowl import bowl_from, track_drive
from vibrofeed.models.deck import transport
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import ResultWriter
from vibrofeed.validation.crosscheck import bowl_speeds, min_distance

ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"
BOWL = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
        "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 0.0, "lip_height": 0.0,
        "chute_length": 8e-3, "freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -30.0,
        "mu": 0.5, "restitution": 0.06, "shape": 1, "part_size": 3e-4, "part_thickness": 1.5e-4,
        "density": 2330.0}


def test_speeds_along_the_helix_and_the_model_at_each_parts_radius(tmp_path):
    b = bowl_from(BOWL)
    radii = np.array([b.radius - 1.0e-3, b.radius - 0.3e-3])  # inner and outer side of the track
    rates = np.array([1.2, 2.0])  # [rad/s] about the axis
    theta0 = np.array([-9.0, -5.0])
    frames = np.arange(0, 0.2 + 1e-12, 0.0025)  # 4 frames per period
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    w = ResultWriter(tmp_path / "b.h5", deck_name="bowl_feeder", deck_path="b.liggghts", deck_text="#\n",
                     variables=variables, derived={"dt_used": 1e-6}, engine_version=ENGINE, seed=1,
                     run_id="b" * 64, rotating=True)
    for k, t in enumerate(frames):
        theta = theta0 + rates * t
        pos = np.array([b.helix_point(th, r) for th, r in zip(theta, radii)]) + [0, 0, 7.5e-5]
        w.write_frame(k, float(t), parts([1, 2], pos, radius=1.8e-4), [0, 0, 0], [0, 0, 0],
                      surface_rotation=([0, 0, 0], [0, 0, 0]))
    w.finish("complete")
    with Result(tmp_path / "b.h5") as r:
        model, dem, centripetal = bowl_speeds(r, 0.1)
        closest = min_distance(r)
    # the path is the centre line's arc length: d/dt = rate r_mid / cos(helix angle), whatever
    # the part's radius
    want = float(np.mean(rates * b.r_mid / math.cos(math.radians(3.0))))
    assert dem == pytest.approx(want, rel=1e-9, abs=0)
    models = []
    for r_ in radii:
        d = track_drive(5e-5, 3e-5, -30.0, 100.0, 3.0, b.r_mid, float(r_))
        models.append(transport({**BOWL, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                                 "incline": d.incline}).velocity)
    assert model == pytest.approx(float(np.mean(models)), rel=1e-12, abs=0)
    assert abs(models[1] - models[0]) > 0.01 * abs(model)  # the radius matters
    omega = 2 * math.pi * 100.0
    assert centripetal == pytest.approx(radii.max() * (5e-5 * omega / b.r_mid) ** 2, rel=1e-12, abs=0)
    assert closest > 1e-3  # [m] far apart
