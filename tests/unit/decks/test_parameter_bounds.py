"""Every parameter bound, at its edge and just past it (through ``resolve`` for the
single-part deck's parameters, on the rule itself for the bulk feeder's).

The limits are written out here independently of ``vibrofeed.parameters.RULES``
(README, "Decks", states them for users): a rule that drifts (a bound moved, an
open end closed) fails here, and a new rule without a row below fails too.
"""

from __future__ import annotations

import math
import re

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from helpers import DECKS
from vibrofeed.decks import Deck
from vibrofeed.parameters import MAX_FRAMES, MAX_SURFACE_SPEED, RULES, ParameterError, resolve

INF = math.inf

# name -> (lower, lower included, upper, upper included, allowed integers or None)
BOUNDS = {
    "freq": (0, False, INF, False, None),
    "amp_t": (0, True, 0.01, True, None),
    "amp_n": (0, True, 0.01, True, None),
    "phase": (-INF, False, INF, False, None),
    "incline": (-90, True, 90, True, None),
    "radius": (0, False, 1, True, None),
    "density": (0, False, 1e5, True, None),
    "youngs": (5e6, False, INF, False, None),
    "poisson": (-1, False, 0.5, True, None),
    "restitution": (0.05, False, 1, True, None),
    "mu": (0, True, INF, False, None),
    "rolling": (0, True, 1, True, (0, 1)),
    "tangential_damping": (0, True, 1, True, (0, 1)),
    "limit_force": (0, True, 1, True, (0, 1)),
    "waveform": (0, True, 4, True, (0, 1, 2, 3, 4)),
    "duty": (0, False, 1, False, None),
    "normal_force": (0, True, INF, False, None),
    "t_end": (0, False, INF, False, None),
    "output_dt": (0, False, INF, False, None),
    "dt": (0, True, INF, False, None),
    "seed": (1, True, INF, False, "integers"),
    # micro-scale surface forces (decks/include/surface_forces.liggghts)
    "hamaker": (0, True, 1e-17, True, None),
    "roughness": (0, True, 1e-4, True, None),
    "air_viscosity": (0, True, 1e-3, True, None),
    "face_radius": (0, True, 1, True, None),
    "dt_unchecked": (0, True, 1, True, (0, 1)),
}

# The bulk feeder's own parameters (decks/bulk_feeder.liggghts); their relations
# (_check_bulk_feeder) bind at most edges, so these bounds are checked on the rule itself.
BULK = {
    "skin": (0, True, INF, False, None),
    "shape": (0, True, 4, True, (0, 1, 2, 3, 4)),
    "part_size": (0, False, 1, True, None),
    "part_thickness": (0, False, 1, True, None),
    "part_width": (0, False, 1, True, None),
    "bump_height": (0, True, INF, False, None),
    "bump_diameter": (0, True, INF, False, None),
    "bump_at": (-1, True, 1, True, None),
    "clump_spacing": (0.5, True, 1, True, None),
    "part_unit": (0, False, INF, False, None),  # (prepare takes 0.001 or 1: vibrofeed.stl_part)
    "clump_method": (0, True, 2, True, (0, 1, 2)),
    "clump_spheres": (1, True, INF, False, "integers"),
    "clump_resolution": (4, True, INF, False, "integers"),
    "clump_overlap": (0, True, 1, False, None),
    "size_spread": (0, True, 1, False, None),
    "n_parts": (0, True, INF, False, "integers"),
    "fill_from": (0, True, 1, True, None),
    "fill_to": (0, True, 1, True, None),
    "inlet_rate": (0, True, INF, False, None),
    "inlet_batch": (1, True, INF, False, "integers"),
    "track_length": (0, False, INF, False, None),
    "track_width": (0, False, INF, False, None),
    "wall_height": (0, False, INF, False, None),
    "gate_width": (0, True, INF, False, None),
    "gate_at": (0, True, 1, False, None),
    "cross_tilt": (0, True, 45, True, None),
    "youngs_track": (5e6, False, INF, False, "or zero"),  # 0: the track takes the parts' value
    "poisson_track": (-1, False, 0.5, True, None),
    "restitution_pp": (0.05, False, 1, True, None),
    "mu_pp": (0, True, INF, False, None),
    "rolling_friction": (0, True, INF, False, None),
    "surface_energy": (0, True, INF, False, None),
    "surface_energy_pp": (0, True, INF, False, None),
    "t_settle": (0, True, INF, False, None),
    # the pull-off test of the same contact (decks/pulloff.liggghts)
    "pair": (0, True, 1, True, (0, 1)),
    "pull_speed": (0, False, INF, False, None),
    "overlap0": (0, False, INF, False, None),
    # a feeder line's section 2 (vibrofeed.line)
    "sections": (1, True, 9, True, tuple(range(1, 10))),  # (the deck declares fewer: refused by resolve)
    "s2_length": (0, False, INF, False, None),
    "s2_width": (0, False, INF, False, None),
    "s2_wall_height": (0, False, INF, False, None),
    "s2_step": (0, False, INF, False, None),
    "s2_cross_tilt": (0, True, 45, True, None),
    "s2_freq": (0, False, INF, False, None),
    "s2_amp_t": (0, True, 0.01, True, None),
    "s2_amp_n": (0, True, 0.01, True, None),
    "s2_phase": (-INF, False, INF, False, None),
    "s2_amp_c": (0, True, 0.01, True, None),
    "s2_phase_c": (-INF, False, INF, False, None),
    "amp_c": (0, True, 0.01, True, None),
    "phase_c": (-INF, False, INF, False, None),
    "s2_gate_width": (0, True, INF, False, None),
    "s2_gate_at": (0, True, 1, False, None),
    "s2_drop_from": (0, True, 1, True, None),
    "s2_drop_to": (0, True, 1, True, None),
    "s2_drop_width": (0, True, INF, False, None),
    "s2_wiper_height": (0, True, INF, False, None),
    "s2_wiper_at": (0, True, 1, False, None),
    "s2_wiper_skew": (0, True, 75, True, None),
    # the bowl feeder (vibrofeed.bowl)
    "n_track": (0, True, INF, False, "integers"),
    "bowl_diameter": (0, False, 0.5, True, None),
    "cone_angle": (0, True, 45, True, None),
    "helix_angle": (0, False, 45, False, None),
    "turns": (0, False, INF, False, None),
    "lip_height": (0, True, INF, False, None),
    "chute_length": (0, False, INF, False, None),
    "wiper_height": (0, True, INF, False, None),
    "wiper_at": (0, True, 1, False, None),
}
ALL = {**BOUNDS, **BULK}

DECK = Deck(DECKS / "single_part.liggghts")
FAST = settings(max_examples=25, deadline=None)


def context(name: str, x: float) -> dict[str, str]:
    """Other parameters chosen so that no relation between parameters binds at ``x``."""
    if name == "freq":
        return {"amp_t": "0", "amp_n": "0"}
    if name in ("amp_t", "amp_n", "amp_c"):
        return {"freq": "1"}  # 2 pi * 1 Hz * 0.01 m is far below the surface-speed limit
    if name in ("t_end", "output_dt"):
        other = "output_dt" if name == "t_end" else "t_end"
        return {other: repr(x) if x > 0 else "1", "dt": "0"}  # one frame
    if name == "dt":
        span = repr(max(x, 1e-3))  # (the contact's limits on dt: test_no_false_success.py)
        return {"t_end": span, "output_dt": span, "dt_unchecked": "1"}
    return {}


def accepted(name: str, x: float) -> bool:
    if name in BULK:
        return RULES[name](float(x)) is None
    given_ = {**context(name, x), name: repr(float(x))}
    try:
        resolve(DECK, given_)
    except ParameterError as err:
        assert name in str(err), f"the message must name {name}: {err}"
        return False
    return True


def inside(name: str, x: float) -> bool:
    lo, lo_in, hi, hi_in, ints = ALL[name]
    ok = (x > lo or (lo_in and x == lo)) and (x < hi or (hi_in and x == hi))
    if ints == "or zero":
        ok = ok or x == 0
    elif ints == "integers":
        ok = ok and x == int(x)
    elif ints is not None:
        ok = x in ints
    return ok


def test_every_rule_has_a_stated_bound():
    assert set(ALL) == set(RULES) and not set(BOUNDS) & set(BULK)
    assert set(BOUNDS) <= set(DECK.tunables)


EDGES = [(name, edge, included) for name, (lo, lo_in, hi, hi_in, _) in ALL.items()
         for edge, included in ((lo, lo_in), (hi, hi_in)) if math.isfinite(edge)]


@pytest.mark.parametrize("name, edge, included", EDGES, ids=lambda v: str(v))
def test_each_edge_and_just_past_it(name, edge, included):
    lo = ALL[name][0]
    outward = -INF if edge == lo else INF
    past = math.nextafter(edge, outward)
    assert accepted(name, edge) is included, f"{name}={edge!r}"
    if ALL[name][4] == "or zero" and edge == lo:
        assert accepted(name, 0.0) and not accepted(name, 5e-324) and not accepted(name, -5e-324)
        assert accepted(name, math.nextafter(edge, INF))
        return
    assert not accepted(name, past), f"{name}={past!r} is past the edge"
    if ALL[name][4] is None:
        just_in = math.nextafter(edge, -outward)
        assert accepted(name, just_in), f"{name}={just_in!r} is inside"
    else:  # integer parameters: one past the edge, and a fraction inside
        assert not accepted(name, edge - 1 if edge == lo else edge + 1)


@pytest.mark.parametrize("name", sorted(ALL))
@FAST
@given(x=st.floats(allow_nan=False, allow_infinity=False, min_value=-1e12, max_value=1e12)
       | st.integers(-10, 10).map(float) | st.sampled_from([0.05, 0.5, 5e6, 90.0, -90.0, 0.01]))
@example(x=0.0)
@example(x=-1.0)
@example(x=1.0)
def test_accepted_exactly_inside_the_bounds(name, x):
    if name == "dt" and x > 1e6:
        return  # the run itself would be longer than any float t_end we choose here
    assert accepted(name, x) is inside(name, x), f"{name}={x!r}"


def test_integer_choices_refuse_fractions():
    for name in ("rolling", "waveform", "seed", "limit_force", "tangential_damping", "shape",
                 "n_parts"):
        assert not accepted(name, 0.5)
        assert not accepted(name, 1.5)


def test_non_finite_values_are_refused_for_every_rule():
    for name in BOUNDS:  # the single-part deck's; resolve checks finiteness before any rule
        for bad in ("inf", "-inf", "nan"):
            with pytest.raises(ParameterError, match="not finite"):
                resolve(DECK, {name: bad})


# -- relations between parameters --------------------------------------------------------------
def test_surface_speed_limit_at_and_past_its_edge():
    for amp in ("amp_n", "amp_t"):
        other = "amp_t" if amp == "amp_n" else "amp_n"
        freq = MAX_SURFACE_SPEED / (2 * math.pi * 0.005)  # 0.005 m at this freq: the limit
        resolve(DECK, {amp: "0.005", other: "0", "freq": repr(math.nextafter(freq, 0))})
        with pytest.raises(ParameterError, match=f"{amp}=0.005 m .* m/s peak"):
            resolve(DECK, {amp: "0.005", other: "0", "freq": repr(freq * (1 + 1e-9))})


def test_frame_limit_at_and_past_its_edge():
    assert MAX_FRAMES == 10 ** 6  # README: more than 10^6 frames are refused
    resolve(DECK, {"t_end": "1", "output_dt": "1e-6"})
    with pytest.raises(ParameterError, match="would write 1e\\+06 frames"):
        resolve(DECK, {"t_end": "1.0000005", "output_dt": "1e-6"})
    resolve(DECK, {"t_end": "1", "output_dt": repr(1 / MAX_FRAMES)})
    with pytest.raises(ParameterError, match="frames"):
        resolve(DECK, {"t_end": "1", "output_dt": repr(math.nextafter(1 / MAX_FRAMES, 0) * 0.999)})


def test_output_interval_and_run_length_against_the_timestep():
    resolve(DECK, {"dt": "1e-6", "output_dt": "1e-6", "t_end": "1e-6"})  # equal: allowed
    with pytest.raises(ParameterError, match="output_dt=.* shorter than the timestep"):
        resolve(DECK, {"dt": "1e-6", "output_dt": "9.99e-7", "t_end": "0.1"})
    with pytest.raises(ParameterError, match="longer than the run"):
        resolve(DECK, {"dt": "1e-6", "output_dt": "1e-6", "t_end": "9.99e-7"})
    resolve(DECK, {"t_end": "0.2", "output_dt": "0.2"})  # one frame: allowed
    with pytest.raises(ParameterError, match="longer than the run"):
        resolve(DECK, {"t_end": "0.2", "output_dt": repr(math.nextafter(0.2, 1))})


def test_t_end_shorter_than_the_timestep():
    # output_dt <= t_end < dt cannot hold together with output_dt >= dt, so the
    # t_end check is reached only when output_dt is not given a value here.
    from vibrofeed.parameters import _check_relations

    with pytest.raises(ParameterError, match="t_end=.* shorter than the timestep"):
        _check_relations({"dt": 1e-3, "t_end": 1e-4})
    _check_relations({"dt": 1e-3, "t_end": 1e-3})


def test_surface_speed_limit_is_two_metres_per_second():
    # 2 pi * 63 Hz * 5 mm = 1.98 m/s is allowed; 2 pi * 64 Hz * 5 mm = 2.01 m/s is not
    resolve(DECK, {"amp_n": "0.005", "amp_t": "0", "freq": "63"})
    with pytest.raises(ParameterError, match="2.01 m/s peak \\(limit 2 m/s"):
        resolve(DECK, {"amp_n": "0.005", "amp_t": "0", "freq": "64"})


def test_relations_without_a_fixed_timestep():
    from vibrofeed.parameters import _check_relations

    _check_relations({"t_end": 1e-3, "output_dt": 1e-4})  # no dt given: automatic, no limit
    _check_relations({"t_end": 1e-3, "output_dt": 1e-4, "dt": 0.0})


def test_messages_name_the_unit_but_not_a_dimensionless_one():
    with pytest.raises(ParameterError) as err:
        resolve(DECK, {"density": "0"})
    assert str(err.value) == "parameter density=0 kg/m^3 must be > 0"
    with pytest.raises(ParameterError) as err:
        resolve(DECK, {"duty": "1"})
    assert str(err.value) == "parameter duty=1 must be in (0, 1)"


def test_a_numeric_tunable_without_a_rule_must_still_be_a_number(tmp_path):
    deck = tmp_path / "tiny.liggghts"
    deck.write_text("variable label index abc # [-] a word\n"
                    "variable gain index 2.5 # [-] a factor no rule limits\n")
    tiny = Deck(deck)
    assert resolve(tiny, {"gain": "-7"})["gain"] == "-7"  # no rule: any number
    with pytest.raises(ParameterError, match="gain=x is not a number"):
        resolve(tiny, {"gain": "x"})
    assert resolve(tiny, {"label": "xyz"})["label"] == "xyz"  # a word stays a word


# -- the bulk feeder's relations ---------------------------------------------------------------
# Unit-scale numbers, exact in binary, so that each edge is hit exactly.
BULK_OK = dict(shape=0, part_size=0.1, part_thickness=0.05, size_spread=0.0, n_parts=10,
               inlet_rate=0.0, fill_from=0.0, fill_to=0.5, track_length=1.0, track_width=0.5,
               wall_height=0.4, gate_width=0.0, gate_at=0.75)


def bulk_problem(**changes) -> str | None:
    from vibrofeed.parameters import _check_relations

    try:
        _check_relations({**BULK_OK, **changes})
    except ParameterError as err:
        return str(err)
    return None


def up(x):
    return math.nextafter(x, INF)


def down(x):
    return math.nextafter(x, -INF)


def test_bulk_relations_at_and_past_their_edges():
    assert bulk_problem() is None
    from vibrofeed.parameters import _check_relations

    for missing in ("part_size", "track_width"):  # not the bulk feeder: nothing to relate
        _check_relations({k: v for k, v in BULK_OK.items() if k != missing} | {"n_parts": 0})
    # fed at all
    assert "no part would ever be fed" in bulk_problem(n_parts=0, inlet_rate=0.0)
    assert bulk_problem(n_parts=0, inlet_rate=5.0) is None
    # a chip or disc is thinner than its edge; spheres ignore the thickness
    for shape in (1, 2):
        assert bulk_problem(shape=shape, part_thickness=0.1) is None
        assert "exceeds part_size" in bulk_problem(shape=shape, part_thickness=up(0.1))
        assert "applies to spheres only" in bulk_problem(shape=shape, size_spread=0.25)
    assert bulk_problem(part_thickness=0.2) is None
    # the track is at least a part wide (spheres: the largest of the spread), and wider than
    # the blocks the parts are inserted into whole, 5 % of a part in from each wall, need
    assert bulk_problem(track_width=up(0.135), size_spread=0.25, n_parts=1) is None
    assert "leaves no room to insert a part" in bulk_problem(track_width=0.135, size_spread=0.25, n_parts=1)
    edge = 2 * 0.05 + 0.1 * 0.1  # a sphere's diameter and 5 % of it from each wall
    assert "the inlet (inlet_rate) places each part whole" in bulk_problem(track_width=edge, n_parts=0,
                                                                            inlet_rate=5.0)
    assert bulk_problem(track_width=up(edge), n_parts=0, inlet_rate=5.0) is None
    # the inlet drops no more than its block holds: 2.95 x (width - 0.1) x 2.9 part sizes at
    # the packing of a settled fill, each part in it for a fall through its 2.9 part sizes
    block = 0.295 * (0.5 - 0.01) * 0.29
    holds = 0.6 * block / (math.pi / 6 * 0.1 ** 3)
    most = holds / math.sqrt(2 * 0.29 / 9.81)
    assert bulk_problem(n_parts=0, inlet_rate=most * (1 - 1e-12)) is None
    assert bulk_problem(n_parts=0, inlet_rate=most * (1 + 1e-12)).startswith(
        f"inlet_rate={most:g} /s is more than the inlet can drop: its block above the track's "
        f"start holds at most {holds:.0f} parts of part_size=0.1 m on track_width=0.5 m")
    assert bulk_problem(n_parts=0, inlet_rate=1.0, inlet_batch=math.floor(holds)) is None
    assert bulk_problem(n_parts=0, inlet_rate=1.0, inlet_batch=math.floor(holds) + 1).startswith(
        f"inlet_batch={math.floor(holds) + 1} parts do not fit in the inlet's block")
    assert bulk_problem(track_width=0.11, n_parts=0, inlet_rate=0.0) \
        == "n_parts=0 and inlet_rate=0: no part would ever be fed; set n_parts (pre-fill) or inlet_rate"
    assert "narrower than a part (0.125 m across)" in bulk_problem(
        track_width=down(0.125), size_spread=0.25, n_parts=1)
    assert "narrower than a part (0.1 m across)" in bulk_problem(shape=1, track_width=down(0.1),
                                                                 n_parts=1)
    # the gate: a part wide, narrower than the track, its taper before the outlet, no fill in it
    assert bulk_problem(gate_width=0.125, size_spread=0.25) is None
    assert "gate_width=0.125 m is narrower" not in (bulk_problem(gate_width=0.125,
                                                                 size_spread=0.25) or "")
    assert "is narrower than a part" in bulk_problem(gate_width=down(0.125), size_spread=0.25)
    assert "must be narrower than track_width" in bulk_problem(gate_width=0.5)
    assert bulk_problem(gate_width=down(0.5), gate_at=0.75) is None
    assert bulk_problem(gate_width=0.25, gate_at=0.875) is None          # taper ends at the edge
    assert ("gate_at=0.8751: the gate's 45 degree taper (0.125 m long) runs past "
            "the outlet edge") in bulk_problem(gate_width=0.25, gate_at=0.8751)
    assert bulk_problem(gate_width=0.25, fill_to=0.75) is None           # fill up to the gate
    assert "reaches into the gate" in bulk_problem(gate_width=0.25, fill_to=up(0.75))
    assert bulk_problem(fill_to=0.9) is None                             # no gate: anywhere
    # the fill's extent
    assert "must be below fill_to" in bulk_problem(fill_from=0.5)
    assert bulk_problem(fill_from=down(0.5), n_parts=0, inlet_rate=1.0) is None
    # walls above a part's centre
    assert "no higher than a part's centre (0.05 m)" in bulk_problem(wall_height=0.05, n_parts=0,
                                                                     inlet_rate=1.0)
    assert bulk_problem(wall_height=up(0.05), n_parts=0, inlet_rate=1.0) is None
    assert "(0.025 m)" in bulk_problem(shape=1, wall_height=0.025, n_parts=0, inlet_rate=1.0)


@pytest.mark.parametrize("shape, volume", [
    (0, math.pi / 6 * 0.1 ** 3),          # sphere of diameter part_size
    (1, 0.1 ** 2 * 0.05),                 # square chip part_size x part_size x thickness
    (2, math.pi / 4 * 0.1 ** 2 * 0.05),   # disc of diameter part_size
])
def test_bulk_pre_fill_stays_below_the_walls(shape, volume):
    # n parts packed at 60 % over the fill area (0.5 x 1.0 x 0.5 m) pile n V / 0.15 m high
    n_max = math.floor(0.4 * 0.6 * 0.5 * 1.0 * 0.5 / volume)
    assert bulk_problem(shape=shape, n_parts=n_max) is None
    assert "above the walls" in bulk_problem(shape=shape, n_parts=n_max + 1)
    assert bulk_problem(shape=shape, n_parts=n_max + 1, fill_from=0.0, fill_to=1.0) is None
    # twice the track length, twice the parts
    n_long = math.floor(0.4 * 0.6 * 0.5 * 2.0 * 0.5 / volume)
    assert n_long >= 2 * n_max and bulk_problem(shape=shape, n_parts=n_long, track_length=2.0) is None
    assert "above the walls" in bulk_problem(shape=shape, n_parts=n_long + 1, track_length=2.0)
    # the same span elsewhere on the track holds the same pile
    assert bulk_problem(shape=shape, n_parts=n_max, fill_from=0.25, fill_to=0.75) is None
    assert "above the walls" in bulk_problem(shape=shape, n_parts=n_max + 1, fill_from=0.25,
                                             fill_to=0.75)


@pytest.mark.parametrize("given, named", [
    ({"inlet_rate": "1e7", "n_parts": "0"}, "inlet_rate=1e+07 /s is more than the inlet can drop"),
    ({"inlet_rate": "30", "inlet_batch": "1000", "n_parts": "0"}, "inlet_batch=1000 parts do not fit"),
])
def test_an_inlet_beyond_its_block_is_refused_before_the_engine(given, named):
    """LIGGGHTS tried each step to insert what could not fit: a run a thousand times slower
    than the same run fed at 30 /s, or 'Unable to calculate region volume'."""
    with pytest.raises(ParameterError, match="^" + re.escape(named)):
        resolve(Deck.find(DECKS / "bulk_feeder.liggghts"), given)
    assert resolve(Deck.find(DECKS / "bulk_feeder.liggghts"), {"inlet_rate": "1000", "n_parts": "0"})


def test_a_cross_stroke_counts_in_the_surface_speed_limit():
    bulk = Deck(DECKS / "bulk_feeder.liggghts")
    freq = MAX_SURFACE_SPEED / (2 * math.pi * 0.005)  # 0.005 m at this freq: the limit
    with pytest.raises(ParameterError, match=r"^s2_amp_c=0.005 m at s2_freq=.* m/s peak"):
        resolve(bulk, {"sections": "2", "s2_amp_c": "0.005", "s2_freq": repr(freq * (1 + 1e-9))})
