"""A section's cross stroke lays a box on its side flat and leaves a flat one flat, by
construction: one box placed on section 2 of a line, lengthwise in the middle of its floor (level,
1.4 mm wide: room to fall over either way), on its long side or flat (LIGGGHTS commands after
the deck, as tests/engine/test_slot_trap.py places its boxes), then 0.15 s of a drive that
conveys it gently along the track and shakes it across.

The box is the orientation demo's chip component, 1.0 x 0.5 x 0.35 mm in 36 spheres
(clump_spacing 1), its rounded edges giving it the rocking ratios b/h = (T - d)/W = 0.35 on its
side and (W - d)/T = 0.93 flat (d the spheres' diameter, T/2: docs/orientation.md). On a floor
of friction mu = 0.5 a box rocks under a cross acceleration when b/h < mu and slides first when
b/h > mu (the tipping-or-sliding closed form of vibrofeed.models.rocking). Under a stroke
much stronger than friction the floor slides under the box along the stroke, skewed theta off
the track: the friction's share across is mu sin(theta) of the normal force, and a box on its
side can fall over only where mu sin(theta) > b/h (theta > 44 degrees here). So:

(a) on its side under a cross stroke of 7e-5 m at 100 Hz in phase with the stroke along of
    4e-5 m (theta = 60 degrees, mu sin(theta) = 0.43) it falls over onto a broad face within
    the run and stays there;
(b) lying flat under the same stroke it slides and never tilts beyond 10 degrees;
(c) on its side with no cross stroke (the same section otherwise) it stays on its side: the
    stroke, not the conveying, turns it; and under the same cross stroke with 1.4e-4 m along
    (theta = 27 degrees, mu sin(theta) = 0.22 < 0.35) it stays on its side too;
(d) under the same stroke a quarter period out of phase with the one along (the floor circles)
    it spins about the normal, its long axis sweeping to 80 degrees off the path and back, and
    stays on its side: a cross stroke that orients runs in phase with the stroke along it.

Every run is checked as any result is (``vibrofeed check``: section 2's recorded sway against
its sine).
"""

import math

import numpy as np
import pytest

from helpers import deck_values, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import section_from
from vibrofeed.feeders.records import Part
from vibrofeed.orientation import part_states
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result
from vibrofeed.rotations import quaternion_matrices

L_, W_, T_ = 1e-3, 5e-4, 3.5e-4
AMP_C, PHASE_C = 7e-5, 0.0
LINE = {"n_parts": 1, "shape": 3, "part_size": L_, "part_width": W_, "part_thickness": T_,
        "clump_spacing": 1.0, "youngs": 2e7, "mu": 0.5, "restitution": 0.3,
        "track_length": 3e-3, "track_width": 1.4e-3, "fill_from": 0.05, "fill_to": 0.45,
        "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30, "sections": 2,
        "s2_length": 6e-3, "s2_width": 1.4e-3 + 2 * AMP_C, "s2_step": 5e-5, "s2_amp_t": 4e-5,
        "s2_amp_n": 1e-5, "s2_phase": -30, "s2_amp_c": AMP_C, "s2_phase_c": PHASE_C,
        "t_end": 0.15, "t_settle": 0.002, "output_dt": 0.005}
PRIMES = (15485863, 32452843, 49979687)
GAP = 2e-6  # between the placed box and the floor
POSES = {"side": (1, 0), "flat": (0, 0)}  # (stand, facing) of vibrofeed.poses, lengthwise


def placement(params, stand, facing):
    """(centre of mass, quaternion w x y z) of a box in the pose on section 2's floor where its
    sines put it at t = 0, a quarter of the way along, in the middle across."""
    section = section_from(deck_values(params))
    rows = box_template(Box.of(Part.from_values(params)))
    R = pose_matrix(stand, facing)
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    floor = -section.step + params["s2_amp_n"] * math.sin(math.radians(params["s2_phase"]))
    y = params["s2_amp_c"] * math.sin(math.radians(params["s2_phase_c"]))
    x = params["track_length"] + 0.25 * params["s2_length"]
    return np.array([x, y, floor + GAP - (placed[:, 2] - r).min()]), matrix_quaternion(R)


def run(path, params, pose):
    at, q = placement(params, *POSES[pose])
    commands = place_one_body(at, q, PRIMES[0])
    run_deck(Deck.find("bulk_feeder"), deck_values(params), path, before_run=commands)
    problems = [str(p) for p in check_file(path).problems if p.level == "error"]
    with Result(path) as r:
        ids, q = r.read("id"), r.read("orientation")
        template = r.body_template
    live = ids[:, 0] >= 0
    q = q[live, 0]
    up = quaternion_matrices(q)[:, :, 2]  # the box's thin axis in the frame, at each frame
    tilt = np.degrees(np.arccos(np.clip(np.abs(up @ quaternion_matrices(q[:1])[0][:, 2]), -1, 1)))
    states = part_states(q, template[:, :3])
    return {"problems": problems, "final": states.names()[-1], "states": set(states.names()),
            "angle": np.nan_to_num(states.angle, nan=0.0), "tilt": tilt, "frames": int(live.sum())}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cross")
    still = {**LINE, "s2_amp_c": 0.0, "s2_width": 1.4e-3}
    circling = {**LINE, "s2_phase_c": 90.0}
    shallow = {**LINE, "s2_amp_t": 1.4e-4}
    return {"side": run(folder / "side.h5", LINE, "side"), "flat": run(folder / "flat.h5", LINE, "flat"),
            "side, no stroke": run(folder / "still.h5", still, "side"),
            "side, circling": run(folder / "circling.h5", circling, "side"),
            "side, shallow": run(folder / "shallow.h5", shallow, "side")}


@pytest.mark.parametrize("case", ["side", "flat", "side, no stroke", "side, circling", "side, shallow"])
def test_each_run_passes_check_with_the_part_on_the_track_throughout(runs, case):
    found = runs[case]
    assert found["problems"] == []
    assert found["frames"] >= 25  # (0.15 s at 5 ms: it never left section 2)


def test_a_box_on_its_side_is_laid_flat_by_the_cross_stroke(runs):
    assert runs["side"]["final"] in ("up", "down")


def test_a_flat_box_slides_under_the_same_stroke_and_stays_flat(runs):
    assert runs["flat"]["final"] == "up" and runs["flat"]["tilt"].max() < 10.0


def test_without_the_stroke_the_box_stays_on_its_side(runs):
    assert runs["side, no stroke"]["states"] == {"side"}


def test_a_stroke_skewed_too_little_across_leaves_it_on_its_side(runs):
    # mu sin(theta) = 0.5 x 7 / sqrt(7^2 + 14^2) = 0.22, below b/h = 0.35
    assert 0.5 * LINE["s2_amp_c"] / math.hypot(1.4e-4, LINE["s2_amp_c"]) < 0.35
    assert runs["side, shallow"]["states"] == {"side"}


def test_a_circling_floor_spins_the_box_instead(runs):
    found = runs["side, circling"]
    assert found["states"] == {"side"} and found["angle"].max() > 45.0
    # (the stroke in phase keeps it lengthwise)
    assert runs["side"]["angle"].max() < 45.0


def test_section_one_moves_across_as_its_sine_and_check_holds_it_to_it(tmp_path):
    """Section 1's own cross stroke (``amp_c`` 8e-5 m leading by ``phase_c`` 30 deg, a bulk
    feeder of three spheres): the recorded surface's y is amp_c sin(w t + phi_c), to within the
    movers' Riemann sum's departure amp_c w dt (1 + w dt / 24) (check.sine_drive), x as without
    it; `check` passes the result and fails a copy whose recorded amp_c is not its motion."""
    import shutil

    import h5py

    amp, lead, freq = 8e-5, 30.0, 100.0
    params = {"n_parts": 3, "inlet_rate": 0, "amp_c": amp, "phase_c": lead, "freq": freq,
              "t_end": 0.02, "output_dt": 1e-3}
    path = tmp_path / "c1.h5"
    run_deck(Deck.find("bulk_feeder"), deck_values(params), path)
    assert [p for p in check_file(path).problems if p.level == "error"] == []
    with Result(path) as r:
        pos = r.file["observables/surface/position/value"][()]
        t = r.file["observables/surface/position/time"][()]
        dt = float(r.file["parameters/derived/dt_used"][()])
    w = 2 * math.pi * freq
    bound = amp * w * dt * (1 + w * dt / 24)
    assert np.abs(pos[:, 1] - amp * np.sin(w * t + math.radians(lead))).max() <= bound
    assert np.abs(pos[:, 1]).max() > 0.5 * amp  # it moved across
    bad = tmp_path / "bad.h5"
    shutil.copy(path, bad)
    with h5py.File(bad, "r+") as f:
        kept = f["parameters/variables/amp_c"]
        new = np.array(b"1.6e-4" if kept.dtype.kind in "SO" else 1.6e-4, dtype=kept.dtype)
        attrs = dict(kept.attrs)
        del f["parameters/variables/amp_c"]
        f["parameters/variables/amp_c"] = new
        f["parameters/variables/amp_c"].attrs.update(attrs)
    errors = [str(p) for p in check_file(bad).problems if p.level == "error"]
    assert any("section 1's cross-track position" in e for e in errors), errors
