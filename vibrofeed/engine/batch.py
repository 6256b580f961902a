"""Many runs at once, each isolated: the executor that validation and sweeps share.

Every run goes through :func:`~vibrofeed.engine.runner.run_deck` in a worker
process of its own, so one run that fails (bad parameters, a LIGGGHTS ERROR,
a crash, a kill) is recorded as that run's outcome and never stops the
others. Threads are enough here: each thread only waits for its worker.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

from ..decks import Deck
from ..errors import VibrofeedError
from .runner import RunResult, run_deck


@dataclass
class RunRequest:
    """One run: ``run_deck(deck, params, output, ranks=..., ...)``."""

    deck: Deck
    params: Mapping[str, str]
    output: Path
    label: str = ""
    ranks: int = 1
    reuse: bool = False
    before_run: list[str] = field(default_factory=list)
    schedule: list[dict] | None = None


@dataclass
class RunOutcome:
    request: RunRequest
    result: RunResult | None = None
    error: VibrofeedError | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


def run_many(requests: Sequence[RunRequest], jobs: int = 1,
             on_state: Callable[[RunRequest, str], None] | None = None) -> list[RunOutcome]:
    """Run ``requests``, ``jobs`` at a time; outcomes in the order of the requests.

    ``on_state(request, state)`` is told ``running``, then ``done``,
    ``reused`` or ``failed``. Errors of the vibrofeed tree become the run's
    outcome; anything else (a bug) is raised once every run has finished.
    """
    notify = on_state or (lambda request, state: None)

    def one(request: RunRequest) -> RunOutcome:
        notify(request, "running")
        try:
            result = run_deck(request.deck, request.params, request.output, ranks=request.ranks,
                              reuse=request.reuse, before_run=request.before_run,
                              schedule=request.schedule)
        except VibrofeedError as exc:
            notify(request, "failed")
            return RunOutcome(request, error=exc)
        notify(request, "reused" if result.reused else "done")
        return RunOutcome(request, result=result)

    with ThreadPoolExecutor(max(1, int(jobs))) as pool:
        futures = [pool.submit(one, r) for r in requests]
    return [f.result() for f in futures]
