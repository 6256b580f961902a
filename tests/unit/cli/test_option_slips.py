"""The analysis commands' options take SI units as the run's parameters do: a value that is
almost surely in other units (a gap in um typed as metres, a mass in grams) is one warning line
naming the option, and the command goes on."""

from __future__ import annotations

import pytest

from vibrofeed.cli import main
from vibrofeed.plausibility import option_advice


@pytest.mark.parametrize("argv, lines", [
    (["singulation", "{missing}", "--gap-distance", "300"],
     ["--gap-distance 300 m is longer than a feeder's gaps and parts: a length in mm or µm? "
      "(--gap-distance is in metres)"]),
    (["singulation", "{missing}", "--tolerance", "5", "--gap", "20"],
     ["--gap 20 s is longer than a feeder's parts arrive apart: a time in ms? (--gap is in seconds)",
      "--tolerance 5 m is longer than a feeder's gaps and parts: a length in mm or µm? "
      "(--tolerance is in metres)"]),
    (["replay", "{missing}", "--mass", "9", "--mu-s", "72", "--mu-k", "0.5", "--normal-force", "1"],
     ["--mass 9 kg is heavier than a part a finger grasps: a mass in g? (--mass is in kg)",
      "--mu-s 72 exceeds the friction of solids (0.05 to 1.5)"]),
])
def test_a_unit_slip_in_an_option_is_named_before_the_work(tmp_path, capsys, argv, lines):
    main([a.format(missing=tmp_path / "none") for a in argv])  # (then refused: no such file)
    err = capsys.readouterr().err.splitlines()
    assert err[:-1] == [f"vibrofeed: warning: {line}" for line in lines]
    assert err[-1].startswith("vibrofeed: error: ")


@pytest.mark.parametrize("option, value, unit", [
    ("--gap-distance", 1e-4, "m"), ("--gap-distance", 0.1, "m"), ("--tolerance", 3e-6, "m"),
    ("--gap", 0.005, "s"), ("--gap", 10.0, "s"), ("--mass", 0.009, "kg"), ("--mass", 1.0, "kg"),
    ("--mu-s", 0.72, "-"), ("--mu-s", 2.0, "-"), ("--gap", None, "s"),
])
def test_plausible_values_and_the_limits_say_nothing(option, value, unit):
    assert option_advice(option, value, unit) is None


@pytest.mark.parametrize("option, value, unit", [
    ("--gap-distance", 0.1001, "m"), ("--gap", 10.01, "s"), ("--mass", 1.001, "kg"), ("--mu-k", 2.001, "-"),
])
def test_just_past_a_limit_is_named(option, value, unit):
    assert option_advice(option, value, unit).startswith(f"{option} {value:g}")
