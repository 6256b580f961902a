"""The demo's cases: the line and the track it replaces resolve as deck parameters (checked
as any run's are), share the supply, and the line is sized as its comments say; the bowl's
case is a valid bowl whose dies the single-part model says climb, sliding, as its comments
say."""

import math

import pytest

from helpers import DECKS
from vibrofeed.cli.demo import CASES, SUPPLY
from vibrofeed.decks import Deck
from vibrofeed.feeders import Feeder
from vibrofeed.parameters import resolve


def described_case(case: str, name: str, toml: str):
    """(deck, resolved values, checked Feeder) of the demo case whose description is
    feeders/``toml`` and whose result is ``name``."""
    from vibrofeed.decks import feeders_dir

    assert CASES[case] == (name, toml, {})
    described = Deck.find(feeders_dir() / toml)
    values = resolve(described, {})
    feeder = Feeder.from_values(values)
    feeder.check()
    return described, values, feeder


@pytest.mark.parametrize("case", ["line", "track"])
def test_each_case_is_a_valid_run_of_the_bulk_feeder(case):
    name, deck, given = CASES[case]
    assert deck == "bulk_feeder"
    values = resolve(Deck(DECKS / "bulk_feeder.liggghts"), given)
    assert {k: values[k] for k in SUPPLY} == SUPPLY  # the same supply for both
    assert name.endswith(("line", "feeder"))


def test_the_line_steps_down_at_every_instant_and_is_fed_not_drained():
    _, _, given = CASES["line"]
    p = {k: float(v) for k, v in resolve(Deck(DECKS / "bulk_feeder.liggghts"), given).items()
         if k in given or k in ("freq", "s2_freq", "amp_n", "phase", "part_size", "gate_width",
                               "sections")}
    joint = Feeder.from_values(p).joints[0]
    dz, dx = joint.motion
    low, high = joint.steps
    assert low > dz and high < p["part_size"]  # a small step down, below the floors' motion
    assert dx < p["part_size"] / 2
    # a sub-hopping single-file section (Gamma_n < 1): hopping spheres convey at scattered speeds
    assert p["s2_amp_n"] * (2 * math.pi * p["s2_freq"]) ** 2 / 9.81 < 1
    assert p["n_parts"] == 0 and p["inlet_rate"] > 0


def test_the_bowl_case_is_a_bowl_whose_dies_climb_sliding_within_5_g():
    import warnings

    from vibrofeed.bowl import bowl_from, track_drive
    from vibrofeed.models.deck import transport

    name, deck, given = CASES["bowl"]
    assert (name, deck) == ("bowl_feeder", "bowl_feeder")
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no warning: the model says the dies climb
        values = resolve(Deck(DECKS / "bowl_feeder.liggghts"), given)
    p = {}
    for k, v in values.items():
        try:
            p[k] = float(v)
        except ValueError:  # (the deck's file names)
            pass
    assert p["shape"] == 1  # dies
    w = 2 * math.pi * p["freq"]
    b = bowl_from(p)
    d = track_drive(p["amp_t"], p["amp_n"], p["phase"], p["freq"], b.helix_angle, b.r_mid)
    # within 5 g at the track; the lift below 1 g (sliding, no hop): the comments' drive
    assert max(p["amp_t"], p["amp_n"]) * w ** 2 / 9.81 < 5
    assert d.amp_n * w ** 2 / 9.81 < 1
    speed = transport({**p, "amp_t": d.amp_t, "amp_n": d.amp_n, "phase": d.phase,
                       "incline": d.incline}).velocity
    assert speed == pytest.approx(0.048, rel=0.02, abs=0)  # [m/s] the comment's 48 mm/s


def test_the_bowl_line_case_speeds_the_dies_up_at_its_joint_as_its_description_says():
    """feeders/bowl_line.toml: the chute's lone die more than three times slower than one alone on
    the exit section, by the single-part models (the chute's: vibrofeed.bowl.chute_mean_speed);
    the joint sound (Feeder.check)."""
    from vibrofeed.bowl import chute_mean_speed
    from vibrofeed.models.deck import transport

    described, values, feeder = described_case("bowl-line", "bowl_line", "bowl_line.toml")
    assert [e.kind for e in feeder.elements] == ["bowl", "linear"]
    p = {k: float(v) for k, v in values.items()
         if k in described.variables and described.variables[k].is_numeric}
    chute, note = chute_mean_speed(p)
    assert chute is not None and chute > 0, note
    exit_line = transport(feeder.section_values(3)).velocity
    assert exit_line > 3 * chute  # the speed step that spaces the queue (continuity)
    # sliding, not hopping: the normal stroke below 1 g
    drive = feeder.elements[1].drive
    assert drive.amp_n * (2 * math.pi * drive.freq) ** 2 < 9.81


def jet_pushes_off(values, part, section) -> bool:
    """Whether a section's jet pushes a part across the tilted floor against friction with a
    margin: its force along the floor beyond 1.5 times the weight's share down the tilt and the
    friction of what it still presses on the floor."""
    L, W, T = part.size, part.width, part.thickness
    weight = float(values["density"]) * L * W * T * 9.81
    jet = section.jet
    mu, tilt, angle = float(values["mu"]), math.radians(section.cross_tilt), math.radians(jet.angle)
    along = jet.force * math.cos(angle)
    resist = weight * math.sin(tilt) + mu * max(weight * math.cos(tilt) - jet.force * math.sin(angle), 0.0)
    return along > 1.5 * resist


def gamma_n(section) -> float:
    """The normal stroke's peak acceleration over g (above 1 the parts hop)."""
    return section.drive.amp_n * (2 * math.pi * section.drive.freq) ** 2 / 9.81


def test_the_orient_case_drops_crosswise_boxes_off_a_ledge_and_blows_off_the_wrong_ones():
    """feeders/orient_ledge.toml, the demo's: its rules as docs/orientation.md states them, each a
    closed form of the part's dimensions: no gate; the ledge keeps a lengthwise box and drops a
    crosswise one by its centre of mass, which leans (T/2) tan(tilt) towards the wall
    (W/2 <= width < L/2 - (T/2) tan(tilt)); the jet keeps the part's correct state and pushes a
    part off; the bulk section hops, the ledge's slides; the bulk floor's stroke runs down its
    tilt; the line is drawn from a store (its rejects removed, its inlet fed) and checks as a
    whole (joints, with the cross stroke's sway)."""
    from vibrofeed.orientation import parse_correct

    _, values, feeder = described_case("orient", "orient_ledge", "orient_ledge.toml")
    part = feeder.part
    L, W, T = part.size, part.width, part.thickness
    one, two = feeder.elements
    assert one.gate is None and two.gate is None
    lean = T / 2 * math.tan(math.radians(two.cross_tilt))
    assert W / 2 <= two.side_drop.width < L / 2 - lean
    assert two.width >= one.width  # (the ledge narrows the floor, not the joint)
    assert two.jet.keeps_correct and two.jet.keep == part.correct == parse_correct("up, lengthwise")
    assert two.side_drop.start < two.jet.at < two.side_drop.end  # the jet blows over the open side
    lo, hi = two.jet_span(part.size)  # its whole block, so that what it blows falls off
    assert two.x0 + two.side_drop.start * two.length <= lo < hi <= two.x0 + two.side_drop.end * two.length
    assert jet_pushes_off(values, part, two)
    assert gamma_n(one) > 1 > gamma_n(two)
    # the bulk floor moves down its tilt, towards the wall, as it rises: the cross stroke runs
    # against the normal one (phase_c = phase + 180) and outweighs the vertical stroke's share up
    # the tilt, amp_n sin(tilt) against amp_c cos(tilt)
    drive, tilt = one.drive, math.radians(one.cross_tilt)
    assert math.cos(math.radians(drive.phase_c - drive.phase)) == pytest.approx(-1, abs=1e-12)
    assert drive.amp_c * math.cos(tilt) > drive.amp_n * math.sin(tilt)
    assert float(values["recirculate"]) == 0 and float(values["inlet_rate"]) > 0  # a store


def test_the_gated_orientation_line_files_boxes_lengthwise_as_its_comments_say():
    """feeders/orient_line.toml (the line of the jet-delay sweep and the gate's optimiser study):
    the gate passes a box only lengthwise (W <= width < L), the side drop drops a crosswise box
    and keeps a lengthwise one (W/2 <= width < L/2), the jet keeps the part's correct state and
    pushes a part off, the bulk section hops, the second slides; the rejects return to the
    inlet, which is fed."""
    from vibrofeed.decks import feeders_dir
    from vibrofeed.orientation import parse_correct

    values = resolve(Deck.find(feeders_dir() / "orient_line.toml"), {})
    feeder = Feeder.from_values(values)
    feeder.check()
    part = feeder.part
    L, W = part.size, part.width
    one, two = feeder.elements
    assert W <= one.gate.width < L
    assert W / 2 <= two.side_drop.width < L / 2
    assert two.jet.keeps_correct and two.jet.keep == part.correct == parse_correct("up, lengthwise")
    assert jet_pushes_off(values, part, two)
    assert gamma_n(one) > 1 > gamma_n(two)
    assert float(values["recirculate"]) == 1 and float(values["inlet_rate"]) > 0  # fed, not drained
