"""A sweep across the ranks of an ``mpirun`` (or ``srun``): groups, dynamic dispatch.

The ranks form groups of ``ranks_per_run`` consecutive ranks (ranks beyond
the last whole group stay idle); the lowest rank of a group is its leader.
Rank 0 reads the sweep, plans it, owns the folder and the summary, and hands
out jobs one at a time, longest expected first, to whichever leader is free
(dynamic dispatch: jobs of unequal length keep every group busy); it also
leads group 0, running its job in a thread. A leader runs its job through the
isolated runner with ``ranks_per_run`` ranks (its own ``mpirun``, started
without the enclosing job's launcher variables, so a crash stays inside it),
analyses it and sends the summary row back; the other members of a group
only hold their slot of the allocation.

Open MPI's blocking receive spins a core at 100 % while it waits; every wait
here is ``Iprobe`` then a short sleep instead, so idle ranks cost nothing and
the cores go to the runs.
"""

from __future__ import annotations

import os
import queue
import sys
import threading
import time
from collections import deque
from pathlib import Path

TAG_SETUP, TAG_JOB, TAG_ROW, TAG_STOP = 11, 12, 13, 14
# Seconds between polls: a leader answers a new job within this; idle members check rarely.
POLL, IDLE_POLL = 0.05, 0.5
# Variables that say this process was started by an MPI launcher (Open MPI, MPICH/Hydra, PMIx/srun).
LAUNCHER_VARIABLES = ("OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "PMI_RANK")

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
    """Rank 0 ends without dispatching (an error, --dry-run): the other ranks may exit."""
    global _released
    if _released:
        return
    _released = True
    for rank in range(1, comm.Get_size()):
        comm.send(("exit", None), dest=rank, tag=TAG_SETUP)


def serve(comm) -> int:
    """The life of a rank other than 0: lead a group, or hold a slot, until told to stop."""
    from mpi4py import MPI

    from ..decks import Deck
    from .execute import run_job

    _wait(comm, 0, TAG_SETUP, IDLE_POLL)
    kind, setup = comm.recv(source=0, tag=TAG_SETUP)
    if kind == "exit":
        return 0
    rank, per_run = comm.Get_rank(), setup["ranks"]
    leader = rank % per_run == 0 and rank < (comm.Get_size() // per_run) * per_run
    deck = Deck(setup["deck"])
    folder = Path(setup["folder"])

    def warn(job, message):
        print(f"vibrofeed: warning: job {job.index}: {message}", file=sys.stderr, flush=True)

    while True:
        status = _wait(comm, 0, MPI.ANY_TAG, POLL if leader else IDLE_POLL)
        message = comm.recv(source=0, tag=status.Get_tag())
        if status.Get_tag() == TAG_STOP:
            return 0
        job = message
        row, computed = run_job(job, folder, deck, per_run, setup["parameters"], setup["command"], warn)
        comm.send((job.index, row, computed), dest=0, tag=TAG_ROW)


def dispatch(comm, todo, per_run: int, setup: dict, run_one, recorder, progress) -> None:
    """Rank 0: hand out ``todo`` (longest expected first) to the group leaders and itself."""
    global _released
    from mpi4py import MPI

    from .plan import dispatch_order

    size = comm.Get_size()
    for rank in range(1, size):
        comm.send(("setup", setup), dest=rank, tag=TAG_SETUP)
    _released = True
    waiting = deque(dispatch_order(todo))
    free = deque(range(per_run, (size // per_run) * per_run, per_run))  # the other leaders
    busy: dict[int, object] = {}
    mine: queue.Queue = queue.Queue()
    local = None
    status = MPI.Status()

    def work(job):
        try:
            mine.put((job, *run_one(job)))
        except BaseException as exc:  # noqa: BLE001 (re-raised below)
            mine.put((job, exc, False))

    try:
        while waiting or busy or local is not None:
            if local is None and waiting:
                local = waiting.popleft()
                progress.started(local)
                threading.Thread(target=work, args=(local,), daemon=True).start()
            while free and waiting:
                job, rank = waiting.popleft(), free.popleft()
                comm.send(job, dest=rank, tag=TAG_JOB)
                busy[rank] = job
                progress.started(job)
            heard = False
            while comm.Iprobe(source=MPI.ANY_SOURCE, tag=TAG_ROW, status=status):
                rank = status.Get_source()
                _, row, computed = comm.recv(source=rank, tag=TAG_ROW)
                recorder.add(busy.pop(rank), row, computed)
                free.append(rank)
                heard = True
            try:
                job, row, computed = mine.get_nowait()
            except queue.Empty:
                pass
            else:
                local, heard = None, True
                if isinstance(row, BaseException):
                    raise row
                recorder.add(job, row, computed)
            if not heard:
                time.sleep(POLL)
    finally:
        for rank in range(1, size):
            comm.send(None, dest=rank, tag=TAG_STOP)
