"""Messages speak the user's words, never Python's: a number read from a file or computed by
numpy (a numpy scalar) shows as its number (0.05, not np.float64(0.05)), text without
Python's quotes, lists and tables as the TOML files write them."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from helpers import DT, write_trial
from vibrofeed.errors import InputError, TrialFileError, UsageError, said

PYTHON = ("np.", "numpy", "array(")


def speaks_plainly(message: str) -> None:
    assert not any(word in message for word in PYTHON), message
    assert not re.search(r"(?<!\w)'[^'\s]+'", message), message  # Python's quotes
    assert "\n" not in message


def test_said_shows_values_as_the_user_writes_them():
    assert [said(v) for v in (np.float64(0.05), np.int64(3), np.float32(0.5), np.bool_(True), False,
                              5e-05, 1.0, "x", b"complete", np.str_("failed"))] == \
        ["0.05", "3", "0.5", "true", "false", "5e-05", "1.0", "x", "complete", "failed"]
    assert said([1, "a", np.float64(0.25)]) == '[1, "a", 0.25]'
    assert said({"low": 1e-5, "log": True}) == "{ low = 1e-05, log = true }"
    assert said(np.array([1.5, 2.0])) == "[1.5, 2.0]"
    assert said(np.array(0.5)) == "0.5"


@pytest.mark.parametrize("t, words", [
    (5 * DT, f"time is not increasing at data row 11 ({9 * DT:g} -> {5 * DT:g} s)"),
    (10.3 * DT, "time is not uniformly sampled: step"),
])
def test_a_trial_files_times_are_numbers_in_its_message(tmp_path, t, words):
    from vibrofeed.validation.replay.trials import read_trial

    def mutate(cols):
        cols["t"] = cols["t"].copy()
        cols["t"][10] = t

    path = write_trial(tmp_path / "bad.csv", mutate=mutate)
    with pytest.raises(TrialFileError) as err:
        read_trial(path)
    message = str(err.value).replace(str(path), "FILE")
    assert words in message
    speaks_plainly(message)


def test_numpy_values_through_the_library_checks():
    from vibrofeed.engine.runner import check_ranks, check_target_error
    from vibrofeed.parameters import ParameterError, _check_relations

    with pytest.raises(UsageError) as err:
        check_ranks(np.int64(0))
    assert str(err.value) == "the number of ranks must be a positive integer, got 0"
    with pytest.raises(UsageError) as err:
        check_target_error("three percent", None)
    assert str(err.value) == "target error must be a number, got three percent"
    with pytest.raises(UsageError) as err:
        check_target_error(np.float64(1.5), None)
    speaks_plainly(str(err.value))
    # a sweep's or a study's values may come from numpy (a design, a screen's Sobol points)
    values = {"amp_n": np.float64(0.05), "freq": np.float64(100.0), "part_size": np.float64(3e-4),
              "track_width": np.float64(2e-3), "n_parts": np.float64(0), "inlet_rate": np.float64(1e7)}
    for drop in (("part_size",), ("amp_n",)):
        with pytest.raises(ParameterError) as err:
            _check_relations({k: v for k, v in values.items() if k not in drop})
        speaks_plainly(str(err.value))


def test_an_analysis_option_given_as_a_numpy_number():
    from vibrofeed.postproc.flights import Flights

    with pytest.raises(InputError) as err:
        Flights(None, contact_tolerance=np.float64(-1e-6))
    assert str(err.value) == "contact_tolerance must be a gap of 0 m or more, got -1e-06"
    with pytest.raises(InputError) as err:
        Flights(None, contact_tolerance=np.float64(math.nan))
    assert str(err.value).endswith("got nan")


def test_no_option_is_read_by_pythons_own_int_or_float():
    """argparse's int and float say "invalid int value: 'abc'" (and float takes nan and inf):
    every numeric option is read by vibrofeed.cli.numbers, whose refusals name the option and
    the number as the user typed it."""
    import argparse

    from vibrofeed.cli import build_parser

    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    raw = [f"{name} {'/'.join(action.option_strings) or action.dest}"
           for name, sub in commands.choices.items() for action in sub._actions
           if action.type in (int, float)]
    assert raw == []
    assert len(commands.choices) == 17  # every command was built, not only one
