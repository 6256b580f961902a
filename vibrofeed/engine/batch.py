"""Many runs at once, each isolated: the executor that validation and sweeps share.

Every run goes through :func:`~vibrofeed.engine.runner.run_deck` in a worker
process of its own (or its own ``mpirun`` for several ranks), so one run that
fails (bad parameters, a LIGGGHTS ERROR, a crash, a kill) is recorded as that
run's outcome and never stops the others. Two ways to spread the runs:

* :func:`run_local`: ``workers`` at a time on this machine, each waited for by
  a daemon thread (the threads only wait for their worker processes; an
  interrupted batch exits at once and its runs' workers get SIGTERM as their
  parent dies). :func:`run_many` runs :class:`RunRequest` objects this way.
* Under ``mpirun`` (or ``srun``), :func:`dispatch` on rank 0 and :func:`serve`
  on the others: the ranks form groups of ``per_run`` consecutive ranks (ranks
  beyond the last whole group stay idle); the lowest rank of a group is its
  leader. Rank 0 hands out the items one at a time, in the order given, to
  whichever leader is free (dynamic dispatch: items of unequal length keep
  every group busy) and also leads group 0, running its item in a thread. A
  leader runs its item and sends the answer back; the other members of a group
  only hold their slot of the allocation.

Both take the items lazily, one as a slot frees: ``items`` may be a generator that
decides the next run from the answers so far (the optimiser asks its sampler so), and
may yield :data:`WAIT` when it has nothing to start until a running item finishes.

Open MPI's blocking receive spins a core at 100 % while it waits; every wait
here is ``Iprobe`` then a short sleep instead, so idle ranks cost nothing and
the cores go to the runs.
"""

from __future__ import annotations

import os
import queue
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from ..decks import Deck
from ..errors import VibrofeedError
from .runner import RunResult, run_deck

TAG_SETUP, TAG_JOB, TAG_ROW, TAG_STOP = 11, 12, 13, 14
# Seconds between polls: a leader answers a new item within this; idle members check rarely.
POLL, IDLE_POLL = 0.05, 0.5
# Variables that say this process was started by an MPI launcher (Open MPI, MPICH/Hydra, PMIx/srun).
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK")


# What an item source yields when it has nothing to start until a running item finishes.
WAIT = object()


class _Source:
    """Items pulled one at a time from an iterable (a list, or a generator that may yield WAIT)."""

    def __init__(self, items: Iterable):
        self._items = iter(items)
        self.ended = False

    def take(self):
        """The next item; None when there is none now (WAIT) or ever (``ended``)."""
        if self.ended:
            return None
        try:
            item = next(self._items)
        except StopIteration:
            self.ended = True
            return None
        return None if item is WAIT else item

    def stalled(self) -> RuntimeError:
        return RuntimeError("the item source waits (WAIT) with no item running: it would wait forever")


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


def _nothing(*args) -> None:
    return None


# ----------------------------------------------------------------- on this machine
def run_local(items: Iterable, workers: int, work: Callable, started: Callable = _nothing,
              finished: Callable = _nothing) -> None:
    """``work(item)`` for ``items`` in their order, ``workers`` at a time, each in a
    daemon thread. ``started(item)`` is called as an item starts and
    ``finished(item, answer)`` with what ``work`` returned as it ends, both in the
    calling thread. An exception ``work`` raises is raised here; the runs still in
    the others' threads are stopped by the command line as it ends on the error
    (:func:`vibrofeed.interrupt.stop_left`), as after Ctrl-C."""
    source = _Source(items)
    done: queue.Queue = queue.Queue()
    running = 0

    def one(item) -> None:
        try:
            done.put((item, work(item), None))
        except BaseException as exc:  # noqa: BLE001 (re-raised in the calling thread)
            done.put((item, None, exc))

    while True:
        while running < max(1, int(workers)):
            item = source.take()
            if item is None:
                break
            started(item)
            threading.Thread(target=one, args=(item,), daemon=True).start()
            running += 1
        if not running:
            if source.ended:
                return
            raise source.stalled()
        item, answer, exc = done.get()
        running -= 1
        if exc is not None:
            raise exc
        finished(item, answer)


def run_many(requests: Sequence[RunRequest], jobs: int = 1,
             on_state: Callable[[RunRequest, str], None] | None = None) -> list[RunOutcome]:
    """Run ``requests``, ``jobs`` at a time (:func:`run_local`); outcomes in the order of
    the requests.

    ``on_state(request, state)`` is told ``running``, then ``done``,
    ``reused`` or ``failed``. Errors of the vibrofeed tree become the run's
    outcome; anything else (a bug) is raised once every run has finished.
    """
    notify = on_state or _nothing

    def one(index: int):
        request = requests[index]
        notify(request, "running")
        try:
            result = run_deck(request.deck, request.params, request.output, ranks=request.ranks,
                              reuse=request.reuse, before_run=request.before_run,
                              schedule=request.schedule)
        except VibrofeedError as exc:
            notify(request, "failed")
            return RunOutcome(request, error=exc)
        except BaseException as exc:  # noqa: BLE001 (raised after the others)
            return exc
        notify(request, "reused" if result.reused else "done")
        return RunOutcome(request, result=result)

    answers: dict[int, RunOutcome | BaseException] = {}
    run_local(range(len(requests)), jobs, one, finished=answers.__setitem__)
    for index in range(len(requests)):
        if isinstance(answers[index], BaseException):
            raise answers[index]
    return [answers[index] for index in range(len(requests))]


# ----------------------------------------------------------------- across MPI ranks
_released = False


def world():
    """MPI.COMM_WORLD when this process is one of several MPI ranks, else None.
    mpi4py (and MPI_Init) is loaded only when a launcher started us."""
    if not any(name in os.environ for name in LAUNCHER_VARIABLES):
        return None
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    return comm if comm.Get_size() > 1 else None


def _wait(comm, source: int, tag: int, interval: float):
    """Status of the next message from ``source`` with ``tag``, polling (no spinning)."""
    from mpi4py import MPI

    status = MPI.Status()
    while not comm.Iprobe(source=source, tag=tag, status=status):
        time.sleep(interval)
    return status


def release(comm) -> None:
    """Rank 0 ends without dispatching (an error, a dry run): the other ranks may exit."""
    global _released
    if _released:
        return
    _released = True
    for rank in range(1, comm.Get_size()):
        comm.send(("exit", None), dest=rank, tag=TAG_SETUP)


def serve(comm, worker: Callable[[dict], Callable]) -> int:
    """The life of a rank other than 0: lead a group, or hold a slot, until told to stop.
    ``worker(setup)`` makes the function a leader runs each item with, from the
    ``setup`` rank 0 sent (which holds ``ranks``: the ranks per group)."""
    from mpi4py import MPI

    _wait(comm, 0, TAG_SETUP, IDLE_POLL)
    kind, setup = comm.recv(source=0, tag=TAG_SETUP)
    if kind == "exit":
        return 0
    rank, per_run = comm.Get_rank(), setup["ranks"]
    leader = rank % per_run == 0 and rank < (comm.Get_size() // per_run) * per_run
    work = worker(setup)
    while True:
        status = _wait(comm, 0, MPI.ANY_TAG, POLL if leader else IDLE_POLL)
        item = comm.recv(source=0, tag=status.Get_tag())
        if status.Get_tag() == TAG_STOP:
            return 0
        comm.send(work(item), dest=0, tag=TAG_ROW)


def dispatch(comm, items: Iterable, setup: dict, work: Callable, started: Callable = _nothing,
             finished: Callable = _nothing) -> None:
    """Rank 0: hand out ``items`` (in their order) to the group leaders and itself.
    ``setup`` goes to every rank (:func:`serve`); ``work``, ``started`` and
    ``finished`` as for :func:`run_local`, ``work`` being rank 0's own."""
    global _released
    from mpi4py import MPI

    size, per_run = comm.Get_size(), setup["ranks"]
    for rank in range(1, size):
        comm.send(("setup", setup), dest=rank, tag=TAG_SETUP)
    _released = True
    source = _Source(items)
    free = deque(range(per_run, (size // per_run) * per_run, per_run))  # the other leaders
    busy: dict[int, object] = {}
    mine: queue.Queue = queue.Queue()
    local = None
    status = MPI.Status()

    def one(item):
        try:
            mine.put((item, work(item), None))
        except BaseException as exc:  # noqa: BLE001 (re-raised below)
            mine.put((item, None, exc))

    try:
        while True:
            if local is None:
                local = source.take()
                if local is not None:
                    started(local)
                    threading.Thread(target=one, args=(local,), daemon=True).start()
            while free:
                item = source.take()
                if item is None:
                    break
                rank = free.popleft()
                comm.send(item, dest=rank, tag=TAG_JOB)
                busy[rank] = item
                started(item)
            if local is None and not busy:
                if source.ended:
                    break
                raise source.stalled()
            heard = False
            while comm.Iprobe(source=MPI.ANY_SOURCE, tag=TAG_ROW, status=status):
                rank = status.Get_source()
                answer = comm.recv(source=rank, tag=TAG_ROW)
                finished(busy.pop(rank), answer)
                free.append(rank)
                heard = True
            try:
                item, answer, exc = mine.get_nowait()
            except queue.Empty:
                pass
            else:
                local, heard = None, True
                if exc is not None:
                    raise exc
                finished(item, answer)
            if not heard:
                time.sleep(POLL)
    finally:
        for rank in range(1, size):
            comm.send(None, dest=rank, tag=TAG_STOP)
