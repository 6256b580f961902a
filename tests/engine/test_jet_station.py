"""An orienting station (a camera and an air jet) on a feeder line does what it says, by
construction: chips placed on section 2 before the jet's sensing point (LIGGGHTS commands after
the deck, as tests/engine/test_line_tooling.py places them), alternately face up and face down
(a template of the deck's chip turned 180 degrees about x, inserted in its own orientation),
two part sizes apart, conveyed sub-hopping (Gamma_n 0.8) in a channel 1.5 parts wide past the
jet: the face-down ones are sensed, fired at and blown over the wall (rejects of section 2,
attributed to the jet by feedrate's tooling), the face-up ones pass and leave over the outlet
edge; the mass balance is exact. Region mode (everything in the block) on one rank; the ideal
mode (the sensed part only) on two ranks. A headway: of three chips face up, the one less than
the headway behind the first is blown off, the one farther behind passes (with no headway the
test fails: nothing is fired at).
"""

import math

import numpy as np
import pytest

from helpers import deck_values
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import Feeder
from vibrofeed.geometry import chip_template
from vibrofeed.orientation import STATES
from vibrofeed.postproc.line import TOOLING, tooling
from vibrofeed.results.reader import Result

SIZE, THICK, DENSITY = 3e-4, 1.5e-4, 2330.0
LINE = {"n_parts": 1, "track_length": 2e-3, "track_width": 2e-3, "gate_width": 4.5e-4, "gate_at": 0.5,
        "fill_from": 0.05, "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30, "shape": 1,
        "restitution": 0.06, "sections": 2, "s2_length": 3e-3, "s2_width": 4.5e-4, "s2_amp_n": 2e-5,
        "s2_amp_t": 6e-5, "s2_phase": -30, "s2_step": 5e-5, "s2_wall_height": 6e-4, "output_dt": 0.005,
        "t_end": 0.25,
        # the jet: senses at 0.9 mm past the joint; its block 0.4 mm long from 0.1 mm before
        # to 0.3 mm after; fires 5 ms after sensing, for 20 ms, 1.5e-6 N (5 weights) at 45 deg
        "s2_jet_at": 0.3, "s2_jet_offset": 1e-4, "s2_jet_length": 4e-4, "s2_jet_delay": 0.005,
        "s2_jet_duration": 0.02, "s2_jet_force": 1.5e-6, "s2_jet_angle": 45,
        "s2_jet_keep": "up,any-direction"}
PRIMES = (15485863, 32452843, 49979687, 67867967, 86028121, 104395301, 122949823, 141650939,
          160481183, 179424673, 198491317, 217645177)


def chips(placed, params):
    """Commands placing chips at (x past the joint, face down) on section 2's floor."""
    mass = SIZE ** 2 * THICK * DENSITY
    i_in, i_out = mass / 12 * (SIZE ** 2 + THICK ** 2), mass / 6 * SIZE ** 2
    joint, h = params["track_length"], 1e-5
    floor = -params["s2_step"] + params["s2_amp_n"] * math.sin(math.radians(params["s2_phase"]))
    commands, counts = ["delete_atoms region fill mol yes"], []
    for k, (x, down) in enumerate(placed):
        rows = chip_template(SIZE, THICK)
        if down:  # turned 180 degrees about x: the marked face (+z) down
            rows = rows * np.array([1.0, -1.0, -1.0, 1.0])
        z = floor + THICK / 2 + 2e-6
        spheres = " ".join(f"{v!r}" for v in rows.ravel().tolist())
        commands += [
            f"fix vf_chip{k} all particletemplate/multisphere {PRIMES[3 * k]} atom_type 1 density "
            f"constant {DENSITY!r} nspheres {len(rows)} ntry 200000 spheres {spheres} type {k + 2} "
            f"mass {mass!r} inertia_tensor {i_in!r} 0 0 {i_in!r} 0 {i_out!r} use_density",
            f"fix vf_dist{k} all particledistribution/discrete {PRIMES[3 * k + 1]} 1 vf_chip{k} 1.0",
            f"region vf_here{k} block {joint + x - h!r} {joint + x + h!r} {-h!r} {h!r} {z - h!r} "
            f"{z + h!r} units box volume_limit 1e-20",
            f"fix vf_put{k} all insert/pack seed {PRIMES[3 * k + 2]} distributiontemplate vf_dist{k} "
            "insert_every once overlapcheck yes all_in no orientation template vel constant 0 0 0 "
            f"region vf_here{k} particles_in_region 1 ntry_mc 10000"]
        counts.append(f"f_vf_put{k}[1]")
    return commands + ["variable n_inserted delete", f"variable n_inserted equal {'+'.join(counts)}"]


# chips placed at (x of the centre past the joint [m], face down): two part sizes apart
PLACED = [(0.2e-3, False), (0.8e-3, True), (1.4e-3, False)]


def run(path, params, ranks=1, placed=PLACED):
    run_deck(Deck.find("bulk_feeder"), deck_values(params), path, before_run=chips(placed, params),
             ranks=ranks)
    with Result(path) as r:
        return {"ids": r.read("id"), "x": r.read("position"), "time": r.time,
                "outlet": r.outlet, "rejects": r.rejects, "firings": r.jet_firings,
                "balance": r.mass_balance, "parameters": r.parameters}


def first_x(found, n=3):
    """Each part's id by the order placed (its x at the first frame that has them all: they are
    inserted in the first step): ``n`` of them."""
    k = int(np.argmax((found["ids"] >= 0).sum(axis=1) == n))
    ids, x = found["ids"][k], found["x"][k, :, 0]
    present = ids >= 0
    return [int(i) for i in ids[present][np.argsort(x[present])]]


def check(found):
    order = first_x(found)  # ascending x: PLACED's order
    down = {pid for pid, (_, d) in zip(order, PLACED) if d}
    up = set(order) - down
    f, rj, out = found["firings"], found["rejects"], found["outlet"]
    assert set(f["id"].tolist()) == down  # fired at the face-down ones, once each
    assert len(f["id"]) == len(down)
    assert all(STATES[s] == "down" for s in f["state"])
    assert np.allclose(f["end"] - f["start"], LINE["s2_jet_duration"], rtol=0, atol=1e-9)  # s
    assert set(rj["id"].tolist()) == down and set(rj["section"].tolist()) == {2}
    assert set(out["id"].tolist()) == up
    feeder = Feeder.from_values(found["parameters"])
    kinds = [TOOLING[k] for k in tooling(rj["position"][:, 0], rj["section"], feeder.stations, SIZE)]
    assert kinds == ["jet"] * len(down)
    b = found["balance"]
    assert b["lost"].max() == 0 and b["inserted"][-1] == len(PLACED)
    assert b["rejected"][-1] == len(down) and b["exited"][-1] == len(up)
    return f, rj


def test_the_jet_blows_the_face_down_chip_off_and_lets_the_face_up_ones_pass(tmp_path):
    f, rj = check(run(tmp_path / "region.h5", LINE))
    print("firings", {k: v.tolist() for k, v in f.items()})
    print("rejects x", rj["position"][:, 0].tolist(), "t", rj["time"].tolist())


@pytest.mark.parametrize("ranks", [2])
def test_the_ideal_jet_on_two_ranks(tmp_path, ranks):
    f, rj = check(run(tmp_path / "ideal.h5", {**LINE, "s2_jet_mode": "ideal"}, ranks))
    print("firings", {k: v.tolist() for k, v in f.items()})


# three chips face up before a camera at 1.5 mm past the joint: the first 0.3 mm before it, the
# second 0.35 mm behind the first (0.05 mm of clear gap), the third 1 mm behind the first;
# conveyed at about 20 mm/s they cross the camera some 17 and 50 ms after the first
CLOSE = [(0.2e-3, False), (0.85e-3, False), (1.2e-3, False)]


def test_a_headway_blows_off_a_chip_too_close_behind_the_last_one_passed_whatever_its_state(tmp_path):
    # every chip face up, in the state the jet keeps: only the headway (30 ms) fires, at the
    # second; the third, more than 30 ms after the first, passes
    params = {**LINE, "s2_jet_mode": "ideal", "s2_jet_headway": 0.03, "s2_jet_at": 0.5}
    found = run(tmp_path / "headway.h5", params, placed=CLOSE)
    third, second, first = first_x(found, len(CLOSE))  # (ascending x)
    f, rj, out = found["firings"], found["rejects"], found["outlet"]
    assert f["id"].tolist() == [second] and STATES[int(f["state"][0])] == "up"
    assert rj["id"].tolist() == [second] and sorted(out["id"].tolist()) == sorted([first, third])
    # the third left more than the headway after the first
    leave = dict(zip(out["id"].tolist(), out["time"].tolist()))
    assert leave[third] - leave[first] > 0.03
    b = found["balance"]
    assert b["lost"].max() == 0 and b["rejected"][-1] == 1 and b["exited"][-1] == 2
