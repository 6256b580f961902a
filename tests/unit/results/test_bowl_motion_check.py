"""`vibrofeed check` of a bowl's recorded motion: the angle and lift must be what riggle and
viblin make of the drive (their step sums), the rates the movers' own; a file that departs
by a millionth of the amplitude, or lacks the drive's parameters, fails."""

import math

import numpy as np

from helpers import parts
from vibrofeed.results.check import check_file
from vibrofeed.results.writer import ResultWriter

DRIVE = {"freq": 100.0, "amp_t": 5e-5, "amp_n": 3e-5, "phase": -30.0, "bowl_diameter": 0.02,
         "track_width": 1.2e-3}
DT = 5.7e-7  # [s]
EVERY = 6491  # steps per frame: 0.37 periods, every phase sampled
ENGINE = "LIGGGHTS (Version LIGGGHTS-PUBLIC 3.8.0, synthetic)"


def motion(steps):
    """The drive's closed form, summed here step by step (not the checker's formula)."""
    w = 2 * math.pi * DRIVE["freq"]
    phi = math.radians(DRIVE["phase"])
    theta_amp = DRIVE["amp_t"] / (DRIVE["bowl_diameter"] / 2 - DRIVE["track_width"] / 2)
    j = np.arange(1, steps.max() + 1)
    angle = np.r_[0.0, np.cumsum(theta_amp * w * DT * np.cos(w * j * DT))][steps]
    lift = DRIVE["amp_n"] * math.sin(phi) + np.r_[0.0, np.cumsum(DRIVE["amp_n"] * w * DT
                                                                 * np.cos(w * j * DT + phi))][steps]
    t = steps * DT
    return angle, theta_amp * w * np.cos(w * t), lift, DRIVE["amp_n"] * w * np.cos(w * t + phi)


def write(path, drive=DRIVE, tamper=None):
    steps = np.arange(12) * EVERY
    angle, rate, lift, vz = motion(steps)
    if tamper:
        tamper(angle, rate, lift, vz)
    variables = {k: (repr(v), "", k, repr(v)) for k, v in drive.items()}
    w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                     variables=variables, derived={"dt_used": DT}, engine_version=ENGINE,
                     seed=1, run_id="y" * 64, rotating=True)
    for k, s in enumerate(steps):
        w.write_frame(int(s), float(s * DT), parts([1], [[0.0, -9.4e-3, 1e-3 + lift[k]]], radius=1.5e-4),
                      [0, 0, lift[k]], [0, 0, vz[k]], surface_rotation=([0, 0, angle[k]], [0, 0, rate[k]]))
    w.finish("complete")
    return check_file(path)


def errors(report):
    return [str(p) for p in report.problems if p.level == "error"]


def test_the_drives_motion_checks_out(tmp_path):
    assert errors(write(tmp_path / "ok.h5")) == []


def test_a_turn_off_by_a_millionth_of_the_amplitude_fails_naming_the_angle(tmp_path):
    theta_amp = DRIVE["amp_t"] / 9.4e-3

    def off(angle, rate, lift, vz):
        angle[7] += 2e-6 * theta_amp

    bad = errors(write(tmp_path / "bad.h5", tamper=off))
    assert len(bad) == 1 and "angle" in bad[0] and "frame 7" in bad[0]


def test_a_lift_or_a_rate_off_fails_too(tmp_path):
    def lift_off(angle, rate, lift, vz):
        lift[3] += 2e-6 * DRIVE["amp_n"]

    def rate_sign(angle, rate, lift, vz):
        rate[:] = -rate

    assert any("position" in e for e in errors(write(tmp_path / "lift.h5", tamper=lift_off)))
    assert any("angular_velocity" in e for e in errors(write(tmp_path / "rate.h5", tamper=rate_sign)))


def test_without_the_drives_parameters_the_motion_cannot_be_verified(tmp_path):
    partial = {k: v for k, v in DRIVE.items() if k != "track_width"}
    bad = errors(write(tmp_path / "partial.h5", drive=partial))
    assert any("track_width" in e and "cannot be verified" in e for e in bad)
