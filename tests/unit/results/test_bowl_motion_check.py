"""`vibrofeed check` of a bowl's recorded motion: the angle and lift must be what riggle and
viblin make of the drive (their step sums), the rates the movers' own; a file that departs
by a millionth of the amplitude, or lacks the drive's parameters, fails."""

import math

import h5py
import numpy as np
import pytest

from helpers import parts, write_result
from vibrofeed.results import layout as L
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result
from vibrofeed.results.writer import Recording, ResultWriter

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


def write(path, drive=DRIVE, tamper=None, **kw):
    return check_file(write_file(path, drive, tamper, **kw))


def write_file(path, drive=DRIVE, tamper=None, frames=12, derived=None):
    steps = np.arange(frames) * EVERY
    derived = {"dt_used": DT} if derived is None else derived
    angle, rate, lift, vz = motion(steps)
    if tamper:
        tamper(angle, rate, lift, vz)
    variables = {k: (repr(v), "", k, repr(v)) for k, v in drive.items()}
    w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                     variables=variables, derived=derived, engine_version=ENGINE,
                     seed=1, run_id="y" * 64, recording=Recording(rotating=True))
    for k, s in enumerate(steps):
        w.write_frame(int(s), float(s * DT), parts([1], [[0.0, -9.4e-3, 1e-3 + lift[k]]], radius=1.5e-4),
                      [0, 0, lift[k]], [0, 0, vz[k]], surface_rotation=([0, 0, angle[k]], [0, 0, rate[k]]))
    w.finish("complete")
    return path


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


def test_the_bowls_rotation_reads_back_and_a_fixed_surface_reads_none(tmp_path):
    path = write_file(tmp_path / "bowl.h5")
    angle, rate, lift, vz = motion(np.arange(12) * EVERY)
    with Result(path) as r:
        assert r.holds("surface_angle") is True
        np.testing.assert_array_equal(r.read("surface_angle")[:, 2], angle)   # stored float64
        np.testing.assert_array_equal(r.read("surface_angular_velocity", frames=[3, 1])[:, 2], rate[[3, 1]])
        assert not r.read("surface_angle")[:, :2].any()
        np.testing.assert_array_equal(r.read("surface_position")[:, 2], lift)
    flat = write_result(tmp_path / "flat.h5", [(0, 0.0, parts([1], [[0, 0, 1e-4]])),
                                                (1, 1e-3, parts([1], [[0, 0, 1e-4]]))])
    with Result(flat) as r:
        assert r.holds("surface_angle") is False
        assert r.read("surface_angle").tolist() == [[0.0, 0.0, 0.0]] * 2   # zeros, one per frame
        assert r.read("surface_angular_velocity", frames=-1).tolist() == [0.0, 0.0, 0.0]


@pytest.mark.parametrize("missing", ["angle", "angular_velocity"])
def test_a_rotating_surface_records_both_its_angle_and_its_rate(tmp_path, missing):
    path = write_file(tmp_path / "half.h5")
    with h5py.File(path, "r+") as f:
        del f[f"{L.SURFACE}/{missing}"]
    assert f"error: /{L.SURFACE}: a rotating surface records angle, angular_velocity: {missing} missing" \
        in [str(p) for p in check_file(path).problems]


def test_a_bowl_run_that_wrote_no_frame_has_no_motion_to_verify(tmp_path):
    """Not even without a recorded time step (the engine died before telling it)."""
    variables = {k: (repr(v), "", k, repr(v)) for k, v in DRIVE.items()}
    w = ResultWriter(tmp_path / "died.h5", deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts",
                     deck_text="#\n", variables=variables, derived={}, engine_version=ENGINE, seed=1,
                     run_id="c" * 64, recording=Recording(rotating=True))
    w.finish("failed", "the engine died before the first frame")
    report = check_file(tmp_path / "died.h5", allow_incomplete=True)
    assert report.ok and [p.message for p in report.problems] == [
        "run status is 'failed': the engine died before the first frame"]


def test_a_bowl_without_any_time_step_cannot_be_verified(tmp_path):
    """With frames after the first, time / step stands for the unrecorded dt_used; with only
    the frame at step 0 there is no step to compute the drive with."""
    assert errors(write(tmp_path / "no_dt.h5", derived={})) == []
    assert errors(write(tmp_path / "first.h5", frames=1, derived={})) == [
        "error: /observables/surface: no time step recorded (derived/dt_used): the bowl's motion "
        "cannot be verified"]


def test_a_chute_after_the_bowl_is_checked_standing_still_not_against_a_drive(tmp_path):
    """Element 2 of a bowl's exit line is a chute: check asks the feeder which element it is
    (the bowl is element 1) and holds its recorded motion to zero, not to a drive it has none of."""
    chute = {**DRIVE, "helix_angle": 3.0, "turns": 0.5, "wall_height": 1e-3, "chute_length": 8e-3,
             "part_size": 3e-4, "sections": 2.0, "s2_kind": 1.0, "s2_length": 3e-3, "s2_width": 2e-3,
             "s2_wall_height": 1e-3, "s2_step": 5e-5, "s2_slope": 5.0}
    steps = np.arange(12) * EVERY
    angle, rate, lift, vz = motion(steps)

    def written(path, moved):
        variables = {k: (repr(v), "", k, repr(v)) for k, v in chute.items()}
        w = ResultWriter(path, deck_name="bowl_feeder", deck_path="bowl_feeder.liggghts", deck_text="#\n",
                         variables=variables, derived={"dt_used": DT}, engine_version=ENGINE,
                         seed=1, run_id="y" * 64, recording=Recording(sections=2, rotating=True))
        for k, s in enumerate(steps):
            turn = ([0, 0, angle[k]], [0, 0, rate[k]])
            w.write_frame(int(s), float(s * DT), parts([1], [[0.0, -9.4e-3, 1e-3 + lift[k]]], radius=1.5e-4),
                          [0, 0, lift[k]], [0, 0, vz[k]], surface_rotation=turn,
                          section_surfaces=[([moved * k, 0, 0], [0, 0, 0])])
        w.finish("complete")
        return errors(check_file(path))

    assert written(tmp_path / "still.h5", 0.0) == []
    moved = written(tmp_path / "moved.h5", 1e-6)
    assert len(moved) == 1 and "section 2's position (a chute, which does not move)" in moved[0]
