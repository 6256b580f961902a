"""An option or a parameter given twice with two values is refused: argparse and a dict keep the
last one without a word, and which one was meant is not for vibrofeed to guess."""

from __future__ import annotations

import pytest

from vibrofeed.cli import main
from vibrofeed.parameters import ParameterError, parse_assignments


def test_a_parameter_given_twice_with_two_values_is_refused_naming_both():
    with pytest.raises(ParameterError) as err:
        parse_assignments(["freq=50", "amp_n=1e-4", "freq=60"])
    assert str(err.value) == "parameter freq given twice, as -p freq=50 and -p freq=60; give it once"


def test_a_parameter_repeated_with_its_value_is_one_request():
    assert parse_assignments(["freq=50", "freq = 50"]) == {"freq": "50"}


@pytest.mark.parametrize("argv, words", [
    (["singulation", "r.h5", "--gap", "1e-3", "--gap", "2e-3"],
     "singulation: --gap given twice, as --gap 0.001 and --gap 0.002; give it once"),
    (["render", "r.h5", "-o", "a.png", "--output", "b.png"],
     "render: -o given twice, as -o a.png and --output b.png; give it once"),
    (["render", "r.h5", "--size", "640x480", "--size", "800x600"],
     "render: --size given twice, as --size 640x480 and --size 800x600; give it once"),
    (["run", "single_part", "-n", "1", "-n", "2"], "run: -n given twice, as -n 1 and -n 2; give it once"),
    (["feedrate", "r.h5", "--start", "0.5", "--start", "1"],
     "feedrate: --start given twice, as --start 0.5 and --start 1; give it once"),
])
def test_an_option_given_twice_with_two_values_is_one_line(capsys, argv, words):
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1
    assert err.startswith(f"vibrofeed: error: {words} (see vibrofeed ")


def test_an_option_repeated_with_its_value_runs(tmp_path, capsys):
    # the same value twice is one request: the command goes on (here to its own refusal)
    assert main(["feedrate", str(tmp_path / "none.h5"), "--batches", "10", "--batches", "10"]) != 0
    assert "given twice" not in capsys.readouterr().err
