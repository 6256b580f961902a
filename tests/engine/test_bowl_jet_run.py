"""An air jet on a bowl's helix, through the driver, by construction: one box placed on the
helix's centre line 0.8 mm before the camera, lengthwise along it, face down or face up
(LIGGGHTS commands after the deck: the pile's one part removed, the deck's own box inserted
turned as asked), conveyed up the helix to the camera, which senses it by its path
coordinate.

The bowl: 20 mm across, half a turn of a 3 degree helix on a 1.2 mm track, at 75 Hz (2e-4 m of
torsion at the centre line, 4e-5 m of lift 60 degrees behind: about 40 mm/s up the helix). The
camera at 0.6 of the helix (17.7 mm of path, the polar angle -162 degrees), keeping "up" in any
direction (ideal mode: only the sensed box), 1.2e-5 N (about three weights) for 10 ms, 20 degrees
up from the floor and across towards the axis: over the track's open inner edge (no wall there),
back into the bowl.

(a) a box face down is sensed once, in state down, fired at, blown off the helix and is back in
    the bowl at the end (off the track: no path coordinate, inside its inner edge, below its
    floor), on 1 and 2 ranks;
(b) a box face up crosses the camera unfired and is still on the helix past it at the end.

Each run's mass balance is exact at every frame (inserted = on track + exited)."""

import math

import numpy as np
import pytest

from helpers import BOX_PARTS, place_one_body
from vibrofeed.bowl import path_coordinate
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders import Feeder
from vibrofeed.orientation import STATES
from vibrofeed.parameters import resolve
from vibrofeed.parts import Box, box_template
from vibrofeed.poses import matrix_quaternion, pose_matrix
from vibrofeed.results.reader import Result

BOWL = BOX_PARTS + """[supply]
n_parts = 1
n_track = 0
[run]
t_end = 0.08
t_settle = 0.002
output_dt = 0.0025

[[element]]
kind = "bowl"
diameter = 0.02
width = 1.2e-3
turns = 0.5
helix_angle = 3
chute_length = 6e-3
drive = { freq = 75, amp_t = 2e-4, amp_n = 4e-5, phase = -60 }
jet = { force = 1.2e-5, at = 0.6, keep = "up, any-direction", duration = 0.01, angle = 20, mode = "ideal" }
"""
SEED = 15485863
GAP = 2e-5  # between the placed box and the floor
BEFORE = 0.8e-3  # m of path before the camera


def run(folder, face_down: bool, ranks: int = 1):
    (folder / "bowl.toml").write_text(BOWL)
    deck = Deck.find(folder / "bowl.toml")
    feeder = Feeder.from_values(resolve(deck, {}))  # (the deck's defaults with the description's)
    bowl = feeder.elements[0]
    b = bowl.bowl
    s0 = bowl.sensing - BEFORE
    theta = float(b.theta_at(s0))
    heading = pose_matrix(0, 0)
    turn = np.array([[-math.sin(theta), -math.cos(theta), 0.0],  # body x along the path there
                     [math.cos(theta), -math.sin(theta), 0.0], [0.0, 0.0, 1.0]])
    R = turn @ heading
    if face_down:
        R = R @ np.diag([1.0, -1.0, -1.0])  # turned over about its long axis
    rows = box_template(Box.of(feeder.part))
    placed, r = rows[:, :3] @ R.T, rows[:, 3]
    floor = float(b.floor_z(theta, b.r_mid)) + 4e-5 * math.sin(math.radians(-60))  # lifted at t = 0
    at = b.helix_point(theta)
    at[2] = floor + GAP - (placed[:, 2] - r).min()
    out = folder / f"{'down' if face_down else 'up'}{ranks}.h5"
    # the pile's one part removed (wherever it settled), the box placed
    commands = place_one_body(at, matrix_quaternion(R), SEED)
    commands[0:1] = ["region vf_all block INF INF INF INF INF INF units box",
                     "delete_atoms region vf_all mol yes"]
    run_deck(deck, {}, out, ranks=ranks, before_run=commands)
    with Result(out) as res:
        ids, x = res.read("id")[:, 0], res.read("position")[:, 0, :]
        found = {"mb": res.mass_balance, "fired": res.jet_firings, "x": x[ids >= 0]}
    found["path"] = path_coordinate(b, found["x"])
    found["sensing"], found["bowl"] = bowl.sensing, b
    # the helix's floor under the camera at its wall, the lowest of its edges there
    found["floor"] = float(b.floor_z(float(b.theta_at(bowl.sensing)), b.radius))
    return found


def balanced(mb):
    # the one part inserted from the first step on (frame 0 is before it), none lost, exact
    assert (mb["inserted"][1:] == 1).all() and (mb["lost"] == 0).all()
    assert (mb["inserted"] == mb["on_track"] + mb["exited"]).all()


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("bowl_jet")


@pytest.mark.parametrize("ranks", [1, 2])
def test_a_box_face_down_on_the_helix_is_sensed_and_blown_back_into_the_bowl(folder, ranks):
    found = run(folder, face_down=True, ranks=ranks)
    balanced(found["mb"])
    fired = found["fired"]
    assert len(fired["id"]) == 1 and STATES[int(fired["state"][0])] == "down"  # sensed once, face down
    assert int(fired["section"][0]) == 1  # the helix
    path = found["path"]
    assert np.nanmax(path) >= found["sensing"] and np.nanmin(path) < found["sensing"]
    # at the end off the helix (no path coordinate), inside its inner edge, below its floor
    # at the camera (0.93 mm up): fallen back into the bowl
    b, end = found["bowl"], found["x"][-1]
    assert np.isnan(path[-1])
    assert math.hypot(end[0], end[1]) < b.radius - b.track_width
    assert end[2] < found["floor"]
    assert found["mb"]["exited"][-1] == 0


def test_a_box_face_up_on_the_helix_passes_the_camera_unfired(folder):
    found = run(folder, face_down=False)
    balanced(found["mb"])
    assert len(found["fired"]["id"]) == 0
    assert found["path"][-1] > found["sensing"] + 1e-4  # past the camera, still on the helix
