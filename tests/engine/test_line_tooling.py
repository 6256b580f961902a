"""A feeder line's wiper does what it says, by construction: parts placed on section 2 just
upstream of the wiper (LIGGGHTS commands after the deck: the pre-fill removed, a sphere made
with create_atoms, chips inserted each in a small box with the orientation of a template of our
own), a short sub-hopping run (Gamma_n 0.8 on both sections: nothing hops over the bar) in a
channel 1.5 parts wide, and what passes under the bar is checked frame by frame against its
clearance above the floor:

(a) a chip stacked on another, at a wiper 1.5 chip thicknesses high: the bottom one passes and
    exits, the top one never passes the wiper higher than its clearance: it is held back and
    knocked off the stack (here it crosses the face 30 ms after the bottom one, lying flat);
(b) a single sphere lying on the floor passes a wiper 1.5 sphere diameters high and exits;
(c) a chip standing on its edge at the same wiper as (a) is held back, while a chip lying flat
    at the same place passes and exits.

Not built: a sphere stacked on a sphere. On this vibrating floor the top sphere rolls off the
bottom one within ~20 ms by itself, with or without a wiper (placed against the wiper's face,
the run without a wiper also never shows it past the face on top), so no test of it could tell a
working wiper from a missing one. Flat chips stack stably; without a wiper the stack in (a) and
the chip on edge in (c) pass the bar's place taller than its clearance.
What a wiper cannot do here: throw a part off the line. Its bar sweeps along the track (-x) and
the section is walled on both sides, so a part it knocks down lands on the floor behind it and
then passes under it as any part lying on the floor does; only an open side (a side drop)
removes a part from the line.
"""

import math

import numpy as np
import pytest

from helpers import deck_values
from vibrofeed.decks import Deck
from vibrofeed.engine.runner import run_deck
from vibrofeed.feeders.feeder import section_from
from vibrofeed.geometry import chip_template
from vibrofeed.results.reader import Result
from vibrofeed.rotations import quaternion_matrices

SIZE, THICK, DENSITY = 3e-4, 1.5e-4, 2330.0
# Section 1 is only there to be a line (its pre-fill is removed before the run); section 2 is a
# channel 1.5 parts wide whose wiper's face lies 0.8 mm past the joint, 0.9 mm before the outlet.
LINE = {"n_parts": 1, "track_length": 3e-3, "track_width": 2e-3, "gate_width": 4.5e-4, "gate_at": 0.5,
        "fill_from": 0.05, "fill_to": 0.45, "amp_n": 2e-5, "amp_t": 6e-5, "phase": -30,
        "sections": 2, "s2_length": 2e-3, "s2_width": 4.5e-4, "s2_amp_n": 2e-5, "s2_amp_t": 6e-5,
        "s2_phase": -30, "s2_step": 5e-5, "s2_wiper_at": 0.4, "output_dt": 0.005}
SPHERES = {**LINE, "s2_wiper_height": 1.5 * SIZE, "t_end": 0.2}
CHIPS = {**LINE, "shape": 1, "restitution": 0.06, "s2_wiper_height": 1.5 * THICK, "t_end": 0.12}
PRIMES = (15485863, 32452843, 49979687, 67867967, 86028121, 104395301)
GAP = 1e-5  # between a part and the wiper's face, and above the floor, when placed
# A part under the bar may press into it by its contact's overlap: a few um at most.
OVERLAP = 0.02 * THICK


def wiper_face(params):
    return section_from(deck_values(params)).wiper_x[0]


def floor_at_start(params):
    """Section 2's floor at t = 0 (its sine starts at s2_amp_n sin(s2_phase))."""
    return -params["s2_step"] + params["s2_amp_n"] * math.sin(math.radians(params["s2_phase"]))


def run(path, params, commands):
    run_deck(Deck.find("bulk_feeder"), deck_values(params), path, before_run=commands)
    return path


def sphere(path):
    """A sphere on the floor against the reference wall, its front GAP from the wiper's face."""
    p, r = SPHERES, SIZE / 2
    x, y, z = wiper_face(p) - r - GAP, -p["s2_width"] / 2 + r + 1e-6, floor_at_start(p) + r + 1e-6
    return run(path, p, ["delete_atoms region fill", f"create_atoms 1 single {x!r} {y!r} {z!r} units box",
                         f"set type 1 diameter {SIZE!r} density {DENSITY!r}",
                         "variable n_inserted delete", "variable n_inserted equal 1"])


def chips(path, placed):
    """Chips ``placed`` as (lying flat or standing on an edge along the track, their face in the
    x-z plane; height of the bottom above the floor), each with its front GAP from the wiper's
    face: inserted from a template of the deck's chip (the same spheres, mass and inertia),
    turned 90 degrees about x for an edge, in its own orientation (insert/pack ... orientation
    template), each in a box 20 um across (its own fix: insert/pack places one part per box)."""
    p, h = CHIPS, 1e-5
    mass = SIZE ** 2 * THICK * DENSITY
    i_in, i_out = mass / 12 * (SIZE ** 2 + THICK ** 2), mass / 6 * SIZE ** 2
    x = wiper_face(p) - SIZE / 2 - GAP
    commands, counts = ["delete_atoms region fill mol yes"], []
    for k, (on_edge, bottom) in enumerate(placed):
        rows, inertia = chip_template(SIZE, THICK), (i_in, 0, 0, i_in, 0, i_out)
        if on_edge:
            rows = rows[:, [0, 2, 1, 3]]  # (x, y, 0) -> (x, 0, y): the face's normal along y
            inertia = (i_in, 0, 0, i_out, 0, i_in)
        z = floor_at_start(p) + bottom + (SIZE if on_edge else THICK) / 2 + 2e-6
        spheres_ = " ".join(f"{v!r}" for v in rows.ravel().tolist())
        # each template needs its own multisphere type (the deck's chip is type 1); LIGGGHTS'
        # seeds are primes above 10000
        commands += [
            f"fix vf_chip{k} all particletemplate/multisphere {PRIMES[3 * k]} atom_type 1 density "
            f"constant {DENSITY!r} nspheres {len(rows)} ntry 200000 spheres {spheres_} type {k + 2} "
            f"mass {mass!r} inertia_tensor {' '.join(repr(float(v)) for v in inertia)} use_density",
            f"fix vf_dist{k} all particledistribution/discrete {PRIMES[3 * k + 1]} 1 vf_chip{k} 1.0",
            # a box this small needs a lower volume_limit than the region's default
            f"region vf_here{k} block {x - h!r} {x + h!r} {-h!r} {h!r} {z - h!r} {z + h!r} units box "
            "volume_limit 1e-20",
            f"fix vf_put{k} all insert/pack seed {PRIMES[3 * k + 2]} distributiontemplate vf_dist{k} "
            "insert_every once overlapcheck yes all_in no orientation template vel constant 0 0 0 "
            f"region vf_here{k} particles_in_region 1 ntry_mc 10000"]
        counts.append(f"f_vf_put{k}[1]")
    commands += ["variable n_inserted delete", f"variable n_inserted equal {'+'.join(counts)}"]
    return run(path, p, commands)


def tracks(path, params):
    """Per part id: (time, x of its centre from the wiper's face, height of its top above the
    floor) [s, m, m], the face and the floor moving with section 2; and the result's outlet and
    reject ids."""
    face, step = wiper_face(params), params["s2_step"]
    with Result(path) as r:
        ids, x = r.read("id"), r.read("position")
        shift, _ = r.section_surface(2)
        radius, q = r.read("radius"), r.read("orientation")
        template = r.body_template
        t = r.time
        out, rejects = set(r.outlet["id"].tolist()), set(r.rejects["id"].tolist())
    floor = -step + shift[:, 2]
    top = x[..., 2] + radius  # a sphere
    if template is not None and params.get("shape") == 1:  # a chip: its highest sphere
        rot = quaternion_matrices(q.reshape(-1, 4)).reshape(*q.shape[:2], 3, 3)
        top = x[..., 2] + (np.einsum("fpij,sj->fpsi", rot, template[:, :3])[..., 2]
                           + template[:, 3]).max(axis=-1)
    found = {}
    for pid in np.unique(ids[ids >= 0]):
        f, s = np.nonzero(ids == pid)
        found[int(pid)] = (t[f], x[f, s, 0] - face - shift[f, 0], top[f, s] - floor[f])
    return found, out, rejects


def never_taller_past_the_face(found, params):
    """No part is past the wiper's face (before the outlet edge) with its top above the
    wiper's underside: nothing passes the wiper taller than its clearance."""
    clearance = params["s2_wiper_height"]
    before_edge = params["s2_length"] * (1 - params["s2_wiper_at"])
    for pid, (_, x, top) in found.items():
        under = (x >= 0) & (x <= before_edge)
        assert (top[under] <= clearance + OVERLAP).all(), \
            f"part {pid} passed the wiper {1e6 * (top[under].max() - clearance):.0f} um too tall"


@pytest.fixture(scope="module")
def chip_runs(tmp_path_factory):
    """Runs of chips placed as (on edge, bottom's height above the floor)."""
    folder = tmp_path_factory.mktemp("tooling")
    placed = {"stack": [(False, 0.0), (False, THICK + 2e-6)], "edge": [(True, 0.0)],
              "flat": [(False, 0.0)]}
    return {name: tracks(chips(folder / f"{name}.h5", chips_), CHIPS) for name, chips_ in placed.items()}


def test_a_stacked_chip_does_not_pass_the_wiper(chip_runs):
    found, out, rejects = chip_runs["stack"]
    (bottom, below), (top, above) = sorted(found.items(), key=lambda item: item[1][2][0])
    # as placed: the top one's top two thicknesses high, its front at the face
    assert above[2][0] > 2 * THICK - OVERLAP and above[1][0] > -SIZE / 2 - 2 * GAP
    never_taller_past_the_face(found, CHIPS)
    assert bottom in out and not rejects  # walls on both sides: nothing falls off
    # held back: the top one crosses the face (if at all) apart from the bottom one, which is
    # then most of a part size further along (two chips cannot lie side by side in a channel
    # 1.5 parts wide); carried along on it, they would cross together
    assert (below[1] >= SIZE).any()  # the bottom one cleared the bar (a part size long)
    crossing = above[0][above[1] >= 0]
    if len(crossing):
        assert np.interp(crossing[0], *below[:2]) - above[1][above[1] >= 0][0] > 0.75 * SIZE


def test_a_single_sphere_on_the_floor_passes_the_wiper(tmp_path):
    found, out, rejects = tracks(sphere(tmp_path / "sphere.h5"), SPHERES)
    ((pid, (_, x, top)),) = found.items()
    assert top.max() < SPHERES["s2_wiper_height"]  # lying on the floor throughout
    assert (x > SIZE).any() and pid in out and not rejects


def test_a_chip_on_edge_is_held_back_while_a_flat_one_passes(chip_runs):
    clearance = CHIPS["s2_wiper_height"]
    ((flat, (t_f, x_f, top_f)),) = chip_runs["flat"][0].items()
    assert top_f.max() < clearance  # lying flat throughout: its top ~ a thickness high
    assert flat in chip_runs["flat"][1] and not chip_runs["flat"][2]
    exit_time = t_f[-1]  # its last frame on the line
    found, out, rejects = chip_runs["edge"]
    ((edge, (t_e, x_e, top_e)),) = found.items()
    assert top_e[0] > SIZE - OVERLAP  # as placed: standing, a chip's edge (2 thicknesses) high
    never_taller_past_the_face(found, CHIPS)
    # held back: still before the face when the flat chip from the same place has left
    assert (x_e[t_e <= exit_time] < 0).all()
    assert edge not in out and not rejects
