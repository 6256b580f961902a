"""A feeder line's slot trap sorts boxes by how they lie, by construction: one box placed on
section 2 just upstream of the slot, against the reference wall (the floor tilted 3 degrees
down towards it), in a given pose (LIGGGHTS commands after the deck: the pre-fill removed,
the deck's own box inserted with ``insert/pack ... orientation constant`` in a region a
fraction of a micrometre across around where its centre of mass goes), then a short
sub-hopping run (Gamma_n 0.8) that conveys it over the slot.

Boxes 0.4 x 0.3 x 0.1 mm (L x W x T), a slot 0.13 mm wide at its default place, along the
wall (T < 0.13 mm < W/2: a flat box's centre lies beyond it), 0.63 mm long (0.3 to 0.75 of
a 1.4 mm section 2):

(a) a box lying flat along the track (W across) bridges it and leaves over the outlet edge;
(b) one lying crosswise (L across) bridges it too;
(c) one on its long side (T across, W up) tips into it and falls through: a reject of
    section 2 that the analysis attributes to the slot;
(d) one standing on its end (L up, T across) falls through as (c).

Each run's mass balance is exact at every frame (inserted = on track + exited + rejected).
"""

import math

import numpy as np
import pytest

from helpers import deck_values, one_body_balanced, place_one_body
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import Feeder, section_from
from vibrofeed.feeders.records import Part
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.postproc.line import TOOLING, tooling
from vibrofeed.results.reader import Result

L_, W_, T_ = 4e-4, 3e-4, 1e-4
SLOT = 1.3e-4
TILT = 3.0  # deg, section 2's floor down towards the reference wall
LINE = {"n_parts": 1, "shape": 3, "part_size": L_, "part_width": W_, "part_thickness": T_,
        "restitution": 0.06, "track_length": 3e-3, "track_width": 1e-3, "gate_width": 6e-4, "gate_at": 0.6,
        "fill_from": 0.05,
        "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30, "sections": 2,
        "s2_length": 1.4e-3, "s2_width": 6e-4, "s2_step": 4e-5, "s2_cross_tilt": TILT,
        "s2_amp_n": 2e-5, "s2_amp_t": 6e-5, "s2_phase": -30, "s2_slot_from": 0.3,
        "s2_slot_to": 0.75, "s2_slot_width": SLOT, "t_end": 0.12, "t_settle": 0.002, "output_dt": 0.005}
PRIMES = (15485863, 32452843, 49979687)
GAP = 2e-6  # between the placed box and the wall, and the floor; and its front and the slot
# (stand, facing) of vibrofeed.poses: 0 flat, 1 on its side, 2 on its end; the longer (0) or
# shorter (1) of the other two along the track
POSES = {"flat": (0, 0), "crosswise": (0, 1), "side": (1, 0), "end": (2, 0)}


def placement(stand, facing):
    """(centre of mass, quaternion w x y z) of a box in the pose, turned with the floor's cross
    tilt, GAP from the reference wall and above the floor at t = 0, its front GAP short of the
    slot."""
    section = section_from(deck_values(LINE))
    rows = box_template(Box.of(Part.from_values(LINE)))
    c, s = math.cos(math.radians(TILT)), math.sin(math.radians(TILT))
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ pose_matrix(stand, facing)
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    normal = np.array([0.0, -s, c])  # the floor's (z rises towards +y)
    lo = -section.width / 2
    floor = -section.step + LINE["s2_amp_n"] * math.sin(math.radians(LINE["s2_phase"]))  # at y = -w/2
    x = section.slot_x[0] - GAP - (placed[:, 0] + r).max()
    y = lo + GAP - (placed[:, 1] - r).min()
    # lowest sphere GAP above the plane through (., lo, floor) with that normal
    above = (placed @ normal - r).min()
    z = (floor * c + GAP - above + s * (y - lo)) / c
    return np.array([x, y, z]), matrix_quaternion(R)


def run(path, pose):
    at, q = placement(*POSES[pose])
    commands = place_one_body(at, q, PRIMES[0])
    run_deck(Deck.find("bulk_feeder"), deck_values(LINE), path, before_run=commands)
    with Result(path) as r:
        mb, out, rej = r.mass_balance, r.outlet, r.rejects
        ids, x = r.read("id"), r.read("position")
    section = section_from(deck_values(LINE))
    x = np.where((ids >= 0)[..., None], x, np.nan)  # (frames, 1, 3): the one part
    stations = Feeder.from_values(deck_values(LINE)).stations
    by = [TOOLING[k] for k in tooling(rej["position"][:, 0], rej["section"], stations, L_)]
    return {"mb": mb, "out": out["id"].tolist(), "rejects": rej["id"].tolist(), "by": by,
            "reject_x": rej["position"][:, 0].tolist(), "x": x[:, 0], "slot": section.slot_x,
            "from_wall": x[:, 0, 1] + section.width / 2}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    folder = tmp_path_factory.mktemp("slot")
    return {pose: run(folder / f"{pose}.h5", pose) for pose in POSES}


@pytest.mark.parametrize("pose", ["flat", "crosswise"])
def test_a_box_lying_flat_bridges_the_slot(runs, pose):
    found = runs[pose]
    one_body_balanced(found["mb"])
    assert len(found["out"]) == 1 and not found["rejects"]  # over the slot and out
    assert found["mb"]["exited"][-1] == 1
    # it crossed the slot riding the wall: its centre no farther from it than half its width
    # across (and a little), so it lay across the slot's whole width
    a, b = found["slot"]
    over = (found["x"][:, 0] >= a) & (found["x"][:, 0] <= b)
    across = W_ if pose == "flat" else L_
    assert over.sum() >= 2 and (found["from_wall"][over] < across / 2 + 2e-5).all()


@pytest.mark.parametrize("pose", ["side", "end"])
def test_a_box_on_its_side_or_end_falls_through_the_slot(runs, pose):
    found = runs[pose]
    one_body_balanced(found["mb"])
    assert not found["out"] and len(found["rejects"]) == 1
    assert found["by"] == ["slot"]  # attributed to the slot: it fell within its stretch
    a, b = found["slot"]
    assert a <= found["reject_x"][0] <= b
    assert found["mb"]["rejected"][-1] == 1
