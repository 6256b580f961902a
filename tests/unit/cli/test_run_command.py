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


@pytest.mark.parametrize("said", [0, 1, 2])
def test_the_warm_up_starts_with_the_worker_and_is_joined_when_the_run_fails(tmp_path, monkeypatch,
                                                                             said):
    """The imports for the check and summary start once the worker has spoken (not beside its
    start), once, and a run that fails is left only after they end."""
    started, joined = [], []

    class Recorded(threading.Thread):
        def start(self):
            started.append(self)
            super().start()

        def join(self, timeout=None):
            joined.append(self)
            super().join(timeout)

    def fail(*_a, on_event, **_k):
        for _ in range(said):
            on_event({"event": "deck"})
            assert len(started) == 1 and not joined
        assert len(started) == min(said, 1)
        raise RunError("the engine worker exited with status 1 during the deck phase")

    monkeypatch.setattr(run_cli.threading, "Thread", Recorded)
    monkeypatch.setattr(runner, "run_deck", fail)
    args = argparse.Namespace(deck="single_part", param=[], output=str(tmp_path / "r.h5"),
                              quiet=True, ranks=1, reuse=False, target_error=None)
    with pytest.raises(RunError):
        run_cli.run(args)
    assert joined == started and len(started) == min(said, 1)
