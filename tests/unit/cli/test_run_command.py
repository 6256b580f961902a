"""`vibrofeed run`'s own thread: the summary's warm-up import is joined on every way out.

A run that fails at once (an engine error in the deck takes about a second) used to leave
the CLI while that daemon thread was still importing scipy; ending the interpreter then can
crash it (SIGSEGV, exit status -11 instead of 1: seen once in CI's engine.run_errors)."""

from __future__ import annotations

import argparse
import threading

import pytest

from vibrofeed.cli import run as run_cli
from vibrofeed.engine import runner
from vibrofeed.errors import RunError


def test_the_warm_up_thread_is_joined_when_the_run_fails(tmp_path, monkeypatch):
    started, joined = [], []

    class Recorded(threading.Thread):
        def start(self):
            started.append(self)
            super().start()

        def join(self, timeout=None):
            joined.append(self)
            super().join(timeout)

    def fail(*_a, **_k):
        assert started, "the run began before the warm-up"
        assert not joined
        raise RunError("the engine worker exited with status 1 during the deck phase")

    monkeypatch.setattr(run_cli.threading, "Thread", Recorded)
    monkeypatch.setattr(runner, "run_deck", fail)
    args = argparse.Namespace(deck="single_part", param=[], output=str(tmp_path / "r.h5"),
                              quiet=True, ranks=1, reuse=False, target_error=None)
    with pytest.raises(RunError):
        run_cli.run(args)
    assert joined == started and len(started) == 1
