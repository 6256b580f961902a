"""The documented environment variables: one set to a value that means nothing is refused in
one line naming it, before the command does anything; set to nothing, it is unset."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from vibrofeed import environment


def command(env: dict, *args):
    full = {k: v for k, v in os.environ.items() if not k.startswith("VIBROFEED_")}
    return subprocess.run([sys.executable, "-m", "vibrofeed.cli", *args], capture_output=True, text=True,
                          env={**full, **env})


@pytest.mark.parametrize("name, value, why", [
    ("VIBROFEED_MAX_RANKS", "abc", "must be a whole number of MPI ranks, at least 1"),
    ("VIBROFEED_MAX_RANKS", "-1", "must be a whole number of MPI ranks, at least 1"),
    ("VIBROFEED_MAX_RANKS", "0", "must be a whole number of MPI ranks, at least 1"),
    ("VIBROFEED_STALL_SECONDS", "nan", "must be a number of seconds > 0"),
    ("VIBROFEED_STALL_SECONDS", "-5", "must be a number of seconds > 0"),
    ("VIBROFEED_LONG_RUN_HOURS", "soon", "must be a number of hours > 0"),
    ("VIBROFEED_LONG_RUN_HOURS", "0", "must be a number of hours > 0"),
    ("VIBROFEED_LONG_RUN_HOURS", "inf", "must be a number of hours > 0"),
    ("VIBROFEED_DEBUG", "maybe", "must be 1 (show tracebacks) or 0 (do not)"),
    ("VIBROFEED_ABORT_SHIM", "{tmp}/no_shim.so", "names no file: it does not exist"),
    ("VIBROFEED_ABORT_SHIM", "{tmp}", "is not a file"),
    ("VIBROFEED_DECKS", "{tmp}/no_decks", "names no folder: it does not exist"),
    ("VIBROFEED_DECKS", "{tmp}/file", "is not a folder"),
    ("VIBROFEED_LIGGGHTS_LIB", "{tmp}/libnone.so", "names no file: it does not exist"),
    ("VIBROFEED_TRIALS_DIR", "{tmp}/no_trials", "names no folder: it does not exist"),
])
def test_a_variable_that_means_nothing_stops_the_command_in_one_line(tmp_path, name, value, why):
    (tmp_path / "file").write_text("")
    value = value.format(tmp=tmp_path)
    proc = command({name: value}, "decks")
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr == (f"vibrofeed: error: environment variable {name}={value} {why}; "
                           "correct it or unset it\n")


@pytest.mark.parametrize("value, on", [("1", True), ("true", True), ("YES", True), ("on", True),
                                       ("0", False), ("false", False), ("no", False), ("off", False),
                                       ("", False)])
def test_debug_is_on_only_when_it_says_so(monkeypatch, value, on):
    monkeypatch.setenv("VIBROFEED_DEBUG", value)
    assert environment.debug() is on


def test_debug_zero_keeps_a_user_error_to_one_line():
    proc = command({"VIBROFEED_DEBUG": "0"}, "run", "no_such_deck")
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    proc = command({"VIBROFEED_DEBUG": "1"}, "run", "no_such_deck")
    assert "Traceback" in proc.stderr


def test_variables_set_to_what_exists_are_taken(tmp_path, monkeypatch):
    shim = tmp_path / "shim.so"
    shim.write_bytes(b"\x7fELF")
    monkeypatch.setenv("VIBROFEED_ABORT_SHIM", str(shim))
    monkeypatch.setenv("VIBROFEED_DECKS", str(tmp_path))
    monkeypatch.setenv("VIBROFEED_LIGGGHTS_LIB", "libliggghts.so.3")  # a name: the loader searches
    monkeypatch.setenv("VIBROFEED_STALL_SECONDS", "2.5")
    monkeypatch.setenv("VIBROFEED_LONG_RUN_HOURS", "0.25")
    environment.check()
    assert environment.long_run_hours() == 0.25
    from vibrofeed.decks import decks_dir
    from vibrofeed.engine.runner import abort_shim

    assert abort_shim() == shim and decks_dir() == tmp_path
    assert environment.liggghts_lib() == "libliggghts.so.3" and environment.stall_seconds() == 2.5


def test_a_variable_set_to_nothing_is_unset(monkeypatch):
    for name in environment.READERS:
        monkeypatch.setenv(name, "")
    environment.check()
    assert [read() for read in environment.READERS.values()] == [False] + [None] * 7


def test_every_variable_the_sources_read_is_read_here():
    # no VIBROFEED_* variable is read past this module's checks, in the package or the validation
    import re
    from pathlib import Path

    root = Path(environment.__file__).parent
    files = [*root.rglob("*.py"), *root.parent.joinpath("validation").rglob("*.py")]
    assert len(files) > 50
    named = {name for path in files if path.name != "environment.py"
             for name in re.findall(r"environ(?:\.get\(|\[)\s*[\"'](VIBROFEED_\w+)", path.read_text())}
    assert named == set(), f"read outside vibrofeed.environment: {sorted(named)}"
    text = Path(environment.__file__).read_text()
    read = set(re.findall(r"_(?:get|existing)\(\"(VIBROFEED_\w+)", text))
    assert read == set(environment.READERS)
