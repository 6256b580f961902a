"""Run parameters are checked against physical limits before anything starts."""

import pytest

from helpers import DECKS
from vibrofeed.decks import Deck
from vibrofeed.parameters import ParameterError, parse_assignments, resolve


@pytest.fixture(scope="module")
def deck():
    return Deck(DECKS / "single_part.liggghts")


def test_defaults_are_the_deck_defaults(deck):
    values = resolve(deck, {})
    assert values["freq"] == deck.variables["freq"].default
    assert set(values) == set(deck.tunables)
    assert "driver" not in values  # reserved, set by vibrofeed


def test_override_replaces_default(deck):
    assert resolve(deck, {"freq": "60"})["freq"] == "60"


@pytest.mark.parametrize("name, value, fragment", [
    ("freq", "0", "must be > 0"),
    ("freq", "-3", "must be > 0"),
    ("radius", "0", "must be > 0"),
    ("amp_n", "-1e-4", "must be in [0, 0.01]"),
    ("amp_t", "-1e-4", "must be in [0, 0.01]"),
    ("restitution", "0.05", "(0.05, 1]"),
    ("restitution", "1.2", "(0.05, 1]"),
    ("poisson", "0.6", "(-1, 0.5]"),
    ("youngs", "1e6", "5e+06"),
    ("incline", "91", "[-90, 90]"),
    ("rolling", "2", "one of 0, 1"),
    ("seed", "1.5", "integer"),
    ("mu", "-0.1", ">= 0"),
    ("t_end", "0", "> 0"),
    ("freq", "abc", "not a number"),
    ("freq", "nan", "not finite"),
])
def test_non_physical_values_are_refused(deck, name, value, fragment):
    with pytest.raises(ParameterError) as err:
        resolve(deck, {name: value})
    assert name in str(err.value) and fragment in str(err.value)


@pytest.mark.parametrize("name, value", [
    ("restitution", "1"), ("restitution", "0.06"), ("poisson", "0.5"), ("amp_n", "0"),
    ("incline", "-30"), ("rolling", "1"), ("phase", "-270"), ("mu", "0"),
])
def test_limit_values_that_are_physical_pass(deck, name, value):
    assert resolve(deck, {name: value})[name] == value


def test_unknown_parameter_lists_valid_ones_and_suggests(deck):
    with pytest.raises(ParameterError) as err:
        resolve(deck, {"fre": "50"})
    text = str(err.value)
    assert "unknown parameter 'fre'" in text and "did you mean 'freq'" in text
    for name in deck.tunables:
        assert name in text


def test_reserved_parameter_is_refused(deck):
    with pytest.raises(ParameterError, match="set by vibrofeed"):
        resolve(deck, {"driver": "0"})


def test_output_interval_shorter_than_timestep(deck):
    with pytest.raises(ParameterError, match="shorter than the timestep"):
        resolve(deck, {"dt": "1e-4", "output_dt": "1e-5"})


def test_output_interval_longer_than_run(deck):
    with pytest.raises(ParameterError, match="longer than the run"):
        resolve(deck, {"t_end": "0.01", "output_dt": "0.02"})


def test_too_many_frames_is_refused(deck):
    # 0.01 s at 1 ns would be 1e7 frames and, with the automatic timestep, 1e7 steps
    with pytest.raises(ParameterError, match="would write 1e\\+07 frames"):
        resolve(deck, {"t_end": "0.01", "output_dt": "1e-9"})
    resolve(deck, {"t_end": "0.01", "output_dt": "1e-8"})  # 1e6 frames: allowed


def test_parse_assignments():
    assert parse_assignments(["a=1", " b = x "]) == {"a": "1", "b": "x"}
    for bad in (["a"], ["=1"], ["a="]):
        with pytest.raises(ParameterError, match="name=value"):
            parse_assignments(bad)
