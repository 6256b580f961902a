"""The command line: help for every command, one-line errors, nothing half-written."""

import json
import os
import sys

import pytest

from helpers import parts, vibrofeed, write_result
from vibrofeed.cli import COMMANDS


def test_top_level_help_lists_every_command():
    out = vibrofeed("--help", check=True).stdout
    for c in COMMANDS:
        assert c in out


@pytest.mark.parametrize("command", COMMANDS)
def test_every_command_has_help(command):
    proc = vibrofeed(command, "--help")
    assert proc.returncode == 0 and "usage: vibrofeed " + command in proc.stdout


def test_decks_and_params():
    assert "single_part" in vibrofeed("decks", check=True).stdout
    out = vibrofeed("params", "single_part", check=True).stdout
    assert "freq" in out and "Hz" in out and "driver" not in out
    rows = json.loads(vibrofeed("params", "single_part", "--json", check=True).stdout)
    assert {"name": "freq", "default": "50", "unit": "Hz", "description": "vibration frequency"} in rows


@pytest.mark.parametrize("args, fragment", [
    (["-p", "fre=1"], "unknown parameter fre"),
    (["-p", "freq=0"], "freq=0 Hz must be > 0"),
    (["-p", "restitution=0.02"], "restitution=0.02"),
    (["-p", "amp_n=-1"], "amp_n=-1 m must be in [0, 0.01]"),
    (["-p", "output_dt=1e-6", "-p", "dt=1e-5"], "shorter than the timestep"),
    (["-p", "amp_n=1e3"], "amp_n=1e3 m must be in [0, 0.01]"),
    (["-p", "amp_t=5e-3", "-p", "freq=100"], "3.14 m/s peak"),
    (["-p", "output_dt=0.5", "-p", "t_end=0.2"], "longer than the run"),
    (["-p", "output_dt=1e-7", "-p", "t_end=1"], "would write 1e+07 frames"),
    (["-p", "duty=1"], "duty=1 must be in (0, 1)"),
    (["-p", "density=0"], "density=0 kg/m^3 must be > 0"),
    (["-p", "seed=0"], "seed=0 must be >= 1"),
    (["-p", "waveform=5"], "waveform=5 must be one of 0, 1, 2, 3, 4"),
    (["-p", "incline=-90.5"], "incline=-90.5 deg must be in [-90, 90]"),
    (["-p", "poisson=-1"], "poisson=-1 must be in (-1, 0.5]"),
    (["-p", "freq"], "is not of the form name=value"),
    (["-n", "0"], "must be at least 1"),
    (["-n", "-1"], "must be at least 1"),
    (["-n", "abc"], "must be a whole number of MPI ranks"),
    (["-n", "100000"], "100000 ranks is more than this machine can run"),
])
def test_bad_run_input_is_one_line_and_writes_nothing(tmp_path, args, fragment):
    out = tmp_path / "r.h5"
    proc = vibrofeed("run", "single_part", "-o", out, *args)
    assert proc.returncode == 2
    assert proc.stderr.startswith("vibrofeed: error: ") and fragment in proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("name, value", [("incline", "-90"), ("incline", "90"), ("poisson", "-0.99"),
                                         ("poisson", "0.5"), ("duty", "0.99"), ("seed", "1"),
                                         ("amp_n", "0.01"), ("waveform", "4"), ("output_dt", "0.2")])
def test_values_at_the_edge_of_their_bounds_are_accepted(name, value):
    from vibrofeed.decks import Deck
    from vibrofeed.parameters import resolve

    extra = {"freq": "10"} if name.startswith("amp") else {}
    assert resolve(Deck.find("single_part"), {name: value, **extra})[name] == value


def test_mpirun_missing_is_one_line(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "VIBROFEED_DEBUG"}
    env["PATH"] = str(tmp_path)  # no mpirun (nor anything else) on the PATH
    import subprocess

    proc = subprocess.run([sys.executable, "-m", "vibrofeed.cli", "run", "single_part", "-n", "2",
                           "-o", tmp_path / "r.h5"], capture_output=True, text=True, env=env)
    assert proc.returncode == 1 and "mpirun not found" in proc.stderr
    assert proc.stderr.count("\n") == 1


def test_missing_deck_names_the_available_ones(tmp_path):
    proc = vibrofeed("run", "no_such_deck", "-o", tmp_path / "r.h5")
    assert proc.returncode == 2 and "no deck no_such_deck" in proc.stderr
    assert "single_part" in proc.stderr


def test_unwritable_output(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    proc = vibrofeed("run", "single_part", "-o", blocker / "sub" / "r.h5")
    assert proc.returncode == 2 and f"folder {blocker} is not a folder" in proc.stderr
    proc = vibrofeed("run", "single_part", "-o", tmp_path)
    assert proc.returncode == 2 and "is a folder" in proc.stderr


def test_check_exit_status_and_json(tmp_path):
    good = write_result(tmp_path / "good.h5", [(0, 0.0, parts([1], [[0, 0, 0]]))])
    killed = write_result(tmp_path / "killed.h5", [(0, 0.0, parts([1], [[0, 0, 0]]))], status=None)
    proc = vibrofeed("check", good)
    assert proc.returncode == 0 and proc.stdout.startswith("OK: ")
    proc = vibrofeed("check", good, killed)
    assert proc.returncode == 1 and "INVALID" in proc.stdout and "killed" in proc.stdout
    assert vibrofeed("check", "--allow-incomplete", killed).returncode == 0
    reports = json.loads(vibrofeed("check", "--json", good, killed).stdout)
    assert [r["ok"] for r in reports] == [True, False]
    assert reports[1]["problems"][0]["where"] == "/parameters/run"


def test_check_of_a_missing_file(tmp_path):
    proc = vibrofeed("check", tmp_path / "none.h5")
    assert proc.returncode == 1 and proc.stdout.splitlines()[1:] == ["  error: /: no such file"]
    assert proc.stdout.startswith(f"INVALID: {tmp_path / 'none.h5'}: ")


def test_params_of_an_unknown_deck():
    proc = vibrofeed("params", "no_such_deck")
    assert proc.returncode == 2 and proc.stderr.startswith("vibrofeed: error: no deck")


def test_usage_errors_are_one_line():
    proc = vibrofeed("run")
    assert proc.returncode == 2 and proc.stderr.startswith("vibrofeed: error: run: ")
    assert proc.stderr.count("\n") == 1
    proc = vibrofeed("no_such_command")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1
    assert proc.stderr.startswith("vibrofeed: error: argument COMMAND: ")


def test_validate_list_and_unknown_case():
    out = vibrofeed("validate", "--list", check=True).stdout
    for name in ("hop_flights", "subhop_speed", "vertical_two_level"):
        assert name in out
    listed = json.loads(vibrofeed("validate", "--list", "--json", check=True).stdout)
    assert {"hop_flights", "subhop_speed", "vertical_two_level"} <= {c["case"] for c in listed}
    assert all(c["kind"] and c["title"] for c in listed)
    proc = vibrofeed("validate", "no_such_case")
    assert proc.returncode == 2 and "no validation case no_such_case;" in proc.stderr


def test_validate_runs_at_once_are_held_to_the_rank_limit(tmp_path, monkeypatch):
    """validate -j 3 -n 2 on a 4-rank limit started 6 ranks; now refused before any case runs."""
    monkeypatch.setenv("VIBROFEED_MAX_RANKS", "4")
    proc = vibrofeed("validate", "hop_speed", "-j", "3", "-n", "2", "-o", tmp_path / "v")
    assert proc.returncode == 2
    assert proc.stderr.startswith("vibrofeed: error: -j 3: 3 runs at once of -n 2 ranks each is 6 ranks")
    assert "give -j 2 or less" in proc.stderr and not (tmp_path / "v").exists()
