"""The demo's cases: the line and the track it replaces resolve as deck parameters (checked
as any run's are), share the supply, and the line is sized as its comments say."""

import math

import pytest

from helpers import DECKS
from vibrofeed.cli.demo import CASES, SUPPLY
from vibrofeed.decks import Deck
from vibrofeed.line import joint_motion, joint_steps
from vibrofeed.parameters import resolve


@pytest.mark.parametrize("case", sorted(CASES))
def test_each_case_is_a_valid_run_of_the_bulk_feeder(case):
    name, given = CASES[case]
    values = resolve(Deck(DECKS / "bulk_feeder.liggghts"), given)
    assert {k: values[k] for k in SUPPLY} == SUPPLY  # the same supply for both
    assert name.endswith(("line", "feeder"))


def test_the_line_steps_down_at_every_instant_and_is_fed_not_drained():
    _, given = CASES["line"]
    p = {k: float(v) for k, v in resolve(Deck(DECKS / "bulk_feeder.liggghts"), given).items()
         if k in given or k in ("freq", "s2_freq", "amp_n", "phase", "part_size", "gate_width")}
    dz, dx = joint_motion(p)
    low, high = joint_steps(p)
    assert low > dz and high < p["part_size"]  # a small step down, below the floors' motion
    assert dx < p["part_size"] / 2
    # a sub-hopping single-file section (Gamma_n < 1): hopping spheres convey at scattered speeds
    assert p["s2_amp_n"] * (2 * math.pi * p["s2_freq"]) ** 2 / 9.81 < 1
    assert p["n_parts"] == 0 and p["inlet_rate"] > 0
