"""The bowl's dilute-limit check (validation.crosscheck.bowl_speeds): each part's speed along
the helix over whole periods, against the model at the part's own radius."""

import math

import numpy as np
import pytest

from helpers import parts
from vibrofeed.bowl import bowl_from, track_drive
from vibrofeed.errors import CaseError
from vibrofeed.models.deck import transport
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter
from vibrofeed.validation.crosscheck import bowl_speeds, min_distance

ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"
BOWL = {"bowl_diameter": 0.02, "track_width": 1.2e-3, "helix_angle": 3.0, "turns": 1.5,
        "wall_height": 1e-3, "cone_angle": 3.0, "cross_tilt": 0.0, "lip_height": 0.0,
        "chute_length": 8e-3, "freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -30.0,
        "mu": 0.5, "restitution": 0.06, "shape": 1, "part_size": 3e-4, "part_thickness": 1.5e-4,
        "density": 2330.0}


def bowl_writer(path) -> ResultWriter:
    """A rotating bowl result of BOWL's parameters, to write frames into."""
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    return ResultWriter(path, deck_name="bowl_feeder", deck_path="b.liggghts", deck_text="#\n",
                        variables=variables, derived={"dt_used": 1e-6}, engine_version=ENGINE, seed=1,
                        run_id="b" * 64, recording=Recording(rotating=True))


def test_speeds_along_the_helix_and_the_model_at_each_parts_radius(tmp_path):
    b = bowl_from(BOWL)
    radii = np.array([b.radius - 1.0e-3, b.radius - 0.3e-3])  # inner and outer side of the track
    rates = np.array([1.2, 2.0])  # [rad/s] about the axis
    theta0 = np.array([-9.0, -5.0])
    frames = np.arange(0, 0.2 + 1e-12, 0.0025)  # 4 frames per period
    w = bowl_writer(tmp_path / "b.h5")
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


def test_speeds_end_where_each_part_reaches_the_chute(tmp_path):
    """The chute is not measured (its drive is not the helix's): a part is measured up to its
    last whole-period frame on the helix, and counts only if that spans at least half the
    window; a part that starts on the chute, or leaves the helix early, does not count."""
    b = bowl_from(BOWL)
    cos_a, sin_a = math.cos(math.radians(3.0)), math.sin(math.radians(3.0))
    THETA_END = -math.pi / 2
    inner, outer = b.radius - 1.0e-3, b.radius - 0.3e-3

    def helix_then_chute(t, rate, r, t_switch, chute_speed):
        if t <= t_switch:
            return b.helix_point(THETA_END - rate * (t_switch - t), r)
        return b.helix_point(THETA_END, r) + chute_speed * (t - t_switch) * np.array([cos_a, 0, sin_a])

    frames = np.arange(0, 0.2 + 1e-12, 0.0025)  # 4 frames per period
    w = bowl_writer(tmp_path / "b.h5")
    for k, t in enumerate(frames):
        pos = np.array([
            helix_then_chute(t, 1.6, inner, 0.175, 4e-3),  # on the helix until 0.175 s: counts
            helix_then_chute(t, 2.4, outer, 0.135, 4e-3),  # leaves it after 0.035 s of 0.1: not
            helix_then_chute(t, 0.0, b.r_mid, -0.3, 1e-2),  # on the chute throughout: not
        ]) + [0, 0, 7.5e-5]
        w.write_frame(k, float(t), parts([1, 2, 3], pos, radius=1.8e-4), [0, 0, 0], [0, 0, 0],
                      surface_rotation=([0, 0, 0], [0, 0, 0]))
    w.finish("complete")
    with Result(tmp_path / "b.h5") as r:
        model, dem, _ = bowl_speeds(r, 0.1)
    assert dem == pytest.approx(1.6 * b.r_mid / cos_a, rel=1e-9, abs=0)
    d = track_drive(5e-5, 3e-5, -30.0, 100.0, 3.0, b.r_mid, inner)
    want = transport({**BOWL, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                      "incline": d.incline}).velocity
    assert model == pytest.approx(want, rel=1e-12, abs=0)


def test_speeds_refuse_when_no_part_stays_on_the_helix(tmp_path):
    b = bowl_from(BOWL)
    frames = np.arange(0, 0.2 + 1e-12, 0.0025)
    w = bowl_writer(tmp_path / "b.h5")
    a = math.radians(3.0)
    for k, t in enumerate(frames):
        pos = b.helix_point(-math.pi / 2) + (2e-3 + 1e-2 * t) * np.array([math.cos(a), 0, math.sin(a)])
        w.write_frame(k, float(t), parts([1], pos[None] + [0, 0, 7.5e-5], radius=1.8e-4), [0, 0, 0],
                      [0, 0, 0], surface_rotation=([0, 0, 0], [0, 0, 0]))
    w.finish("complete")
    with Result(tmp_path / "b.h5") as r, pytest.raises(CaseError, match="helix"):
        bowl_speeds(r, 0.1)


def test_chute_speeds_bin_each_parts_whole_period_speed_along_the_chute(tmp_path):
    """By hand, frames a quarter period apart (whole periods: every 4th): part 1 runs along the
    chute from x = 0.5 mm at 10 mm/s, part 2 from x = 4.2 mm at 4 mm/s, part 3 climbs the
    helix (not the chute: left out), part 4 runs past the last part size before the outlet
    (its intervals there left out). Bins of 1 mm: each holds the intervals whose mid-point
    lies in it, at its part's speed."""
    from helpers import write_bulk_result
    from vibrofeed.validation.crosscheck import chute_speeds

    b = bowl_from(BOWL)
    a = math.radians(BOWL["helix_angle"])
    up = np.array([math.cos(a), 0.0, math.sin(a)])
    end = b.chute_length - BOWL["part_size"]  # [m] the last x measured

    def chute(x):
        return b.helix_point(-math.pi / 2) + x * up + [0, 0, 1e-4]

    frames = []
    times = np.arange(0, 0.2 + 1e-12, 0.0025)
    for k, t in enumerate(times):
        pos = np.array([chute(5e-4 + 0.01 * t), chute(4.2e-3 + 0.004 * t),
                        b.helix_point(b.theta_start + 1.0 + 2.0 * t) + [0, 0, 1e-4],
                        chute(6.5e-3 + 0.01 * t)])
        frames.append((k, float(t), parts(np.arange(1, 5), pos, radius=1.8e-4)))
    variables = {k: (repr(v), "", k, repr(v)) for k, v in BOWL.items()}
    path = write_bulk_result(tmp_path / "c.h5", frames, variables=variables,
                             outlet={"outlet_x": b.outlet_x, "catch_z": -5e-4, "method": "synthetic"})
    with Result(path) as r:
        bins = chute_speeds(r, 0.0, 1e-3)
    # the intervals by hand: 20 whole periods of 10 ms; part k's mid-points x0 + v (j + 0.5) T
    want = {}
    for x0, v in ((5e-4, 0.01), (4.2e-3, 0.004), (6.5e-3, 0.01)):
        for j in range(20):
            x_a, x_b = x0 + v * j * 0.01, x0 + v * (j + 1) * 0.01
            if x_b <= end:
                lo = math.floor((x_a + x_b) / 2 / 1e-3) * 1e-3
                want.setdefault(round(lo, 9), []).append(v)
    assert [round(lo, 9) for lo, _, _, _ in bins] == sorted(want)
    for lo, hi, n, speed in bins:
        assert n == len(want[round(lo, 9)])
        assert speed == pytest.approx(np.mean(want[round(lo, 9)]), rel=1e-9, abs=0)
        assert hi <= end + 1e-15
