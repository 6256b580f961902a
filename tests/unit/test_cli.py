"""The command line: help for every command, one-line errors, nothing half-written."""

import json

import pytest

from helpers import parts, vibrofeed, write_result

COMMANDS = ["run", "check", "validate", "decks", "params"]


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
    (["-p", "fre=1"], "unknown parameter 'fre'"),
    (["-p", "freq=0"], "freq=0 Hz must be > 0"),
    (["-p", "restitution=0.02"], "restitution=0.02"),
    (["-p", "amp_n=-1"], "amp_n=-1 m must be >= 0"),
    (["-p", "output_dt=1e-6", "-p", "dt=1e-5"], "shorter than the timestep"),
    (["-n", "0"], "ranks must be a positive integer"),
])
def test_bad_run_input_is_one_line_and_writes_nothing(tmp_path, args, fragment):
    out = tmp_path / "r.h5"
    proc = vibrofeed("run", "single_part", "-o", out, *args)
    assert proc.returncode == 2
    assert proc.stderr.startswith("vibrofeed: error: ") and fragment in proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_missing_deck_names_the_available_ones(tmp_path):
    proc = vibrofeed("run", "no_such_deck", "-o", tmp_path / "r.h5")
    assert proc.returncode == 2 and "no deck 'no_such_deck'" in proc.stderr
    assert "single_part" in proc.stderr


def test_unwritable_output(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    proc = vibrofeed("run", "single_part", "-o", blocker / "sub" / "r.h5")
    assert proc.returncode == 1 and "cannot create folder" in proc.stderr
    proc = vibrofeed("run", "single_part", "-o", tmp_path)
    assert proc.returncode == 1 and "is a directory" in proc.stderr


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


def test_validate_list_and_unknown_case():
    out = vibrofeed("validate", "--list", check=True).stdout
    for name in ("hop_flights", "subhop_speed", "vertical_two_level"):
        assert name in out
    proc = vibrofeed("validate", "no_such_case")
    assert proc.returncode == 2 and "no validation case 'no_such_case'" in proc.stderr
