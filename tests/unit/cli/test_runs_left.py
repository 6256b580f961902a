"""A command that ends on an error while runs are waited for in other threads (a sweep's
ledger on a full disk, a bug in a study's objective) stops those runs before it returns,
as Ctrl-C does: a daemon thread left in a run would be cut off mid-call by the
interpreter's end, its run's scratch folder kept and its file's status never written."""

from __future__ import annotations

import pytest

from helpers import run_in_flight
from vibrofeed import cli, interrupt
from vibrofeed.cli import decks as decks_cli
from vibrofeed.errors import RunError


@pytest.fixture
def fresh(monkeypatch):
    monkeypatch.setattr(interrupt, "_stoppers", {})
    monkeypatch.setattr(interrupt, "_stopping", None)
    monkeypatch.setattr(interrupt, "install", lambda: None)  # the suite's signal handlers stay


def command_with_a_run_in_flight(failure: BaseException, record: list):
    """A command's ``run`` that leaves one run going in another thread, then fails."""

    def run(args):
        run_in_flight(record)
        raise failure

    return run


@pytest.mark.parametrize("failure, code", [(RunError("the ledger could not be written"), 1),
                                           (OSError(28, "No space left on device"), 1)])
def test_a_failed_command_stops_its_runs_and_waits_for_them(fresh, monkeypatch, failure, code):
    record: list = []
    monkeypatch.setattr(decks_cli, "run", command_with_a_run_in_flight(failure, record))
    assert cli.main(["decks"]) == code
    assert record == ["stopped: the command ended on an error", "recorded its end"]
    with pytest.raises(KeyboardInterrupt):  # and no run starts after
        interrupt.check()


def test_a_bug_keeps_its_traceback_and_still_stops_the_runs(fresh, monkeypatch):
    record: list = []
    monkeypatch.setattr(decks_cli, "run", command_with_a_run_in_flight(ZeroDivisionError("bug"), record))
    with pytest.raises(ZeroDivisionError):
        cli.main(["decks"])
    assert record == ["stopped: the command ended on an error", "recorded its end"]


def test_a_command_that_left_no_run_stops_nothing(fresh, monkeypatch):
    monkeypatch.setattr(decks_cli, "run", lambda args: 0)
    assert cli.main(["decks"]) == 0
    assert interrupt._stopping is None  # later runs of this process may start
    assert interrupt.stop_left("why") is False


def test_after_ctrl_c_the_runs_are_not_waited_for_twice(fresh, monkeypatch):
    """stop_all had its wait (30 s at most) for a run that would not end: none more."""
    waits: list = []
    monkeypatch.setattr(interrupt, "stop_all", lambda exc, timeout=30.0, why=None: waits.append(why))

    def interrupted(args):
        interrupt.register(lambda why: None)  # a run that never unregisters
        interrupt._stopping = KeyboardInterrupt()  # as the real stop_all leaves it
        raise KeyboardInterrupt()

    monkeypatch.setattr(decks_cli, "run", interrupted)
    assert cli.main(["decks"]) == 130
    assert waits == [None]
