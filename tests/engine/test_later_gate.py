"""A gate on a later section of a line files boxes lengthwise, by construction: one box placed
on section 2 just before its gate's taper, centred across (the gate is), in a given pose
(LIGGGHTS commands after the deck: the pre-fill removed, the deck's own box inserted turned,
as in test_slot_trap), then a short sub-hopping run (Gamma_n 0.8) that conveys it into the gate.

Boxes 0.4 x 0.3 x 0.1 mm (L x W x T) on a section 0.6 mm wide, gated to 0.35 mm from 30 % of
its length on (W <= 0.35 mm < L: a box passes it only lengthwise):

(a) a box lying flat lengthwise passes the gate and leaves over the outlet edge;
(b) one lying flat crosswise (L across) never lies past the gate's narrowest point wider than
    the gate: held in the taper or turned lengthwise by it, it does not pass crosswise.

The mesh decides it: with the gate's walls missing, (b) would ride on crosswise. Each run's mass
balance is exact at every frame (inserted = on track + exited + rejected).
"""

import numpy as np
import pytest

from helpers import deck_values, one_body_balanced, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import section_from
from vibrofeed.feeders.records import Part
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.reader import Result
from vibrofeed.rotations import quaternion_matrices

L_, W_, T_ = 4e-4, 3e-4, 1e-4
GATE = 3.5e-4
LINE = {"n_parts": 1, "shape": 3, "part_size": L_, "part_width": W_, "part_thickness": T_,
        "restitution": 0.06, "track_length": 3e-3, "track_width": 1e-3, "gate_width": 6e-4, "gate_at": 0.6,
        "fill_from": 0.05, "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30, "sections": 2,
        "s2_length": 1.4e-3, "s2_width": 6e-4, "s2_step": 4e-5, "s2_amp_n": 2e-5, "s2_amp_t": 6e-5,
        "s2_phase": -30, "s2_gate_width": GATE, "s2_gate_at": 0.3, "t_end": 0.15, "t_settle": 0.002,
        "output_dt": 0.005}
GAP = 2e-6  # between the placed box and the floor, and its front and the taper's start
# A box in the narrowed channel may press into its walls by its contacts' overlap: a few um.
OVERLAP = 1e-5
POSES = {"lengthwise": (0, 0), "crosswise": (0, 1)}  # vibrofeed.poses: flat, long or short along x


def placement(facing):
    """(centre of mass, quaternion w x y z) of a flat box, centred across, GAP above the
    floor at t = 0, its front GAP short of the gate's taper."""
    section = section_from(deck_values(LINE))
    rows = box_template(Box.of(Part.from_values(LINE)))
    R = pose_matrix(0, facing)
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    floor = -section.step + LINE["s2_amp_n"] * np.sin(np.radians(LINE["s2_phase"]))
    x = section.gate_x[0] - GAP - (placed[:, 0] + r).max()
    z = floor + GAP - (placed[:, 2] - r).min()
    return np.array([x, 0.0, z]), matrix_quaternion(R)


def run(path, pose):
    at, q = placement(POSES[pose][1])
    run_deck(Deck.find("bulk_feeder"), deck_values(LINE), path, before_run=place_one_body(at, q, 15485863))
    with Result(path) as r:
        mb, out, rejects = r.mass_balance, r.outlet["id"].tolist(), r.rejects["id"].tolist()
        ids, x, quat, template = r.read("id"), r.read("position"), r.read("orientation"), r.body_template
        shift, _ = r.section_surface(2)
    live = ids[:, 0] >= 0  # (frames, 1): the one part
    rot = quaternion_matrices(quat[live, 0])
    ys = np.einsum("fij,sj->fsi", rot, template[:, :3])[..., 1]
    across = (ys + template[:, 3]).max(axis=1) - (ys - template[:, 3]).min(axis=1)
    centre = x[live, 0, 0] - shift[live, 0]  # along section 2, as it moves
    return {"mb": mb, "out": out, "rejects": rejects, "x": centre, "across": across,
            "narrow": section_from(deck_values(LINE)).gate_x[1], "end": section_from(deck_values(LINE)).x1}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("later_gate")
    return {pose: run(folder / f"{pose}.h5", pose) for pose in POSES}


def never_wider_than_the_gate_past_it(found):
    past = (found["x"] >= found["narrow"]) & (found["x"] <= found["end"])
    assert (found["across"][past] <= GATE + OVERLAP).all(), \
        f"{1e6 * (found['across'][past].max() - GATE):.0f} um wider than the gate past it"


def test_a_box_lengthwise_passes_a_later_gate(runs):
    found = runs["lengthwise"]
    one_body_balanced(found["mb"])
    assert found["across"][0] == pytest.approx(W_, abs=OVERLAP)  # as placed: W across
    never_wider_than_the_gate_past_it(found)
    assert (found["x"] > found["narrow"]).any()  # it went through
    assert len(found["out"]) == 1 and not found["rejects"] and found["mb"]["exited"][-1] == 1


def test_a_box_crosswise_does_not_pass_a_later_gate_crosswise(runs):
    found = runs["crosswise"]
    one_body_balanced(found["mb"])
    assert found["across"][0] == pytest.approx(L_, abs=OVERLAP)  # as placed: L across, wider
    never_wider_than_the_gate_past_it(found)
    assert not found["rejects"]  # walled on both sides: nothing falls off
