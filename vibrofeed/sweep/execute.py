"""Running a sweep: its jobs through the isolated runner, and the summary's row of each one.

Every job is one :func:`~vibrofeed.engine.runner.run_deck` (a worker process
of its own, or its own ``mpirun`` for ``ranks_per_run`` > 1, started without
the launcher variables of any enclosing MPI job), so a job that fails (bad
parameters, a LIGGGHTS ERROR, a crash, a kill) becomes a ``failed`` row and
the others go on. Its analysis (:mod:`.metrics`) runs where the job ran, and
an analysis that raises is that job's failure too (the result stays; a rerun
with ``--retry-failed`` analyses it again without running it).

The jobs go through the executor validation shares
(:mod:`vibrofeed.engine.batch`), longest expected first: without MPI,
``workers`` jobs at once, each waited for by a thread (the threads only wait
for their worker processes and analyse); under ``mpirun``, across groups of
``ranks_per_run`` ranks, rank 0 dispatching. Only one process writes the
summary: this one, or rank 0, a journal line per finished job (:class:`.summary.Ledger`).
"""

from __future__ import annotations

import json
import os
import shlex
import sys
import time
from pathlib import Path

from ..decks import Deck
from ..engine import batch
from ..engine.runner import check_at_once, run_deck
from ..errors import RunError, UsageError, VibrofeedError
from . import folder as F
from . import summary as S
from .metrics import metrics
from .plan import Job, dispatch_order, find_deck, plan
from .progress import SweepProgress
from .spec import SweepSpec, load


def _number(text: str):
    """A resolved parameter value as the summary stores it: a number when it is one."""
    try:
        x = float(text)
    except (TypeError, ValueError):
        return text
    return int(x) if x.is_integer() and "." not in text and "e" not in text.lower() else x


def base_row(job: Job, parameters: list[str]) -> dict:
    row = {"job": job.index, "replicate": job.replicate, "seed": job.seed}
    row.update({name: _number(job.values[name]) for name in parameters if name != "seed"})
    row.update({"status": S.FAILED, "error": "", "file": "", "run_id": job.run_id, "wall_s": None})
    return row


def _one_line(text: str) -> str:
    return " ".join(str(text).split())


def run_job(job: Job, folder: Path, deck: Deck, ranks: int, parameters: list[str],
            command: str = "", warn=None) -> tuple[dict, bool]:
    """(summary row, computed here) of one job; never raises for the job's own failure."""
    row = base_row(job, parameters)
    started = time.monotonic()

    def on_event(event: dict) -> None:
        if event.get("event") == "warning" and warn is not None:
            warn(job, event.get("message", ""))

    try:
        result = run_deck(deck, job.params, folder / job.file, ranks=ranks, reuse=True,
                          on_event=on_event, command=f"{command} (job {job.index})".strip(),
                          target_error=job.target_error)
    except VibrofeedError as exc:
        partial = getattr(exc, "partial", None)
        row.update(error=_one_line(exc), wall_s=time.monotonic() - started,
                   file=str(Path(partial[0]).relative_to(folder)) if partial else "")
        return row, True
    except Exception as exc:  # a bug in one job's set-up must not end the sweep: it is its row
        row.update(error=_one_line(f"{type(exc).__name__}: {exc}"), wall_s=time.monotonic() - started)
        return row, True
    row.update(file=job.file, wall_s=result.wall if result.reused else time.monotonic() - started)
    try:
        row.update(metrics(folder / job.file))
    except Exception as exc:  # the run is kept; --retry-failed analyses it again
        row.update(error=_one_line(f"analysis failed: {type(exc).__name__}: {exc}"))
        return row, not result.reused
    row.update(status=S.DONE)
    return row, not result.reused


class Recorder:
    """Records each finished job in the summary's ledger (one journal line: O(1) per
    job, the snapshot rewritten now and then) and tells the progress."""

    def __init__(self, folder: Path, rows: list[dict], parameters: list[str], meta: dict,
                 progress: SweepProgress | None = None):
        self.ledger = S.Ledger(folder, parameters, meta, rows=rows)  # drops rows no longer true
        self.progress = progress

    @property
    def rows(self) -> dict[int, dict]:
        return self.ledger.rows

    def add(self, job: Job, row: dict, computed: bool) -> None:
        self.ledger.add(row)
        if self.progress is not None:
            self.progress.finished(job, row, computed)

    def close(self) -> None:
        """The last snapshot: summary.csv then lists every finished job."""
        self.ledger.close()


def run_local(todo: list[Job], workers: int, run_one, recorder: Recorder,
              progress: SweepProgress) -> None:
    """``workers`` jobs at a time, longest expected first (the executor's local pool)."""
    batch.run_local(dispatch_order(todo), workers, run_one, progress.started,
                    lambda job, answer: recorder.add(job, *answer))


def run_mpi(comm, todo: list[Job], setup: dict, run_one, recorder: Recorder,
            progress: SweepProgress) -> None:
    """Rank 0 of an ``mpirun``: the jobs, longest expected first, across the groups of
    ``ranks_per_run`` ranks (the executor's MPI dispatch; the other ranks run :func:`serve`)."""
    batch.dispatch(comm, dispatch_order(todo), setup, run_one, progress.started,
                   lambda job, answer: recorder.add(job, *answer))


def serve(comm) -> int:
    """The life of an ``mpirun`` rank other than 0: lead a group of ranks running the jobs
    rank 0 hands out, or hold a slot of one (:func:`vibrofeed.engine.batch.serve`)."""
    return batch.serve(comm, _group_leader)


def _group_leader(setup: dict):
    """The job function of a group's leader, from the setup rank 0 sends (:func:`run_mpi`)."""
    deck, folder = Deck(setup["deck"]), Path(setup["folder"])

    def warn(job, message):
        print(f"vibrofeed: warning: job {job.index}: {message}", file=sys.stderr, flush=True)

    return lambda job: run_job(job, folder, deck, setup["ranks"], setup["parameters"], setup["command"],
                               warn)


def describe(jobs: list[Job], spec: SweepSpec, states: dict[int, str]) -> str:
    """The job table of ``--dry-run``."""
    varied = spec.varied
    head = ["job", "rep", "seed"] + varied + ["cost", "state"]
    top = max((j.cost for j in jobs), default=1.0) or 1.0
    rows = [[str(j.index), str(j.replicate), str(j.seed if j.seed is not None else "")]
            + [str(j.setting.get(name, "")) for name in varied]
            + [f"{j.cost / top:.3g}", states.get(j.index, "to run")] for j in jobs]
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in [head] + rows)


def time_estimate(todo: list, at_once: int) -> str:
    """What the sweep's runs still to do are estimated to take (each as a lone run would,
    :func:`~vibrofeed.engine.runner.estimated_seconds`, ``at_once`` at a time), in words for
    its head line; empty when none can be estimated."""
    from ..engine.runner import estimated_seconds
    from ..values import duration

    seconds = [e[0] for job in todo if (e := estimated_seconds(job.values)) is not None]
    if not seconds:
        return ""
    # the longest run bounds the wall time from below however the rest are shared out
    total = max(sum(seconds) / max(at_once, 1), max(seconds))
    some = "" if len(seconds) == len(todo) else f" ({len(todo) - len(seconds)} not estimated)"
    return f"about {duration(total)} to run{some} (one core per run, each run's parts counted)"


def sweep(spec_path, output=None, workers: int = 1, retry_failed: bool = False,
          dry_run: bool = False, quiet: bool = False, comm=None, out=None) -> int:
    """``vibrofeed sweep``: returns the exit status (or raises a VibrofeedError).

    ``comm``: the MPI communicator when started by ``mpirun`` with more than
    one rank (this is rank 0), else None."""
    out = out or sys.stdout
    spec = load(spec_path)
    deck = find_deck(spec)
    jobs = plan(spec, deck)
    folder = Path(output if output is not None else Path("results") / Path(spec_path).stem).absolute()
    ours = F.check_folder(folder, spec)
    parameters = [p for p in spec.parameters if p != "seed"]
    groups = 1 if comm is None else comm.Get_size() // spec.ranks_per_run
    if comm is not None and groups < 1:
        raise UsageError(f"{spec.where('ranks_per_run')}: ranks_per_run = {spec.ranks_per_run} "
                         f"needs at least that many ranks; mpirun started {comm.Get_size()}")
    if comm is not None and workers > 1:
        raise UsageError("-j: under mpirun the groups of ranks_per_run ranks are the workers; drop -j")
    if comm is None:
        check_at_once(workers, spec.ranks_per_run)
    lock = None
    if not dry_run:  # from here on this sweep owns the folder: no other one reads or writes it
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "jobs").mkdir(exist_ok=True)
        lock = F.lock(folder)
        F.clear_leftovers(folder)
    try:
        return _run(spec, deck, jobs, folder, ours, parameters, groups, workers, retry_failed,
                    dry_run, quiet, comm, out, spec_path)
    finally:
        if lock is not None:
            os.close(lock)


def _run(spec, deck, jobs, folder, ours, parameters, groups, workers, retry_failed, dry_run, quiet,
         comm, out, spec_path) -> int:
    rows = S.read(folder)[0] if ours else []
    kept, todo = F.resume(jobs, rows, retry_failed, lambda j: F.result_is_true(folder, j))
    states = {row["job"]: row["status"] for row in kept}
    n_done = sum(s == S.DONE for s in states.values())
    n_failed = len(states) - n_done
    settings = len(jobs) // spec.replicates
    idle = 0 if comm is None else comm.Get_size() - groups * spec.ranks_per_run
    where = "local" if comm is None else f"{comm.Get_size()} MPI ranks" + (
        f" of which {idle} idle: not a multiple of ranks_per_run" if idle else "")
    head = (f"sweep {spec.source}: {len(jobs)} jobs ({settings} settings x {spec.replicates} "
            f"replicates) of deck {deck.name} -> {folder}; {n_done} done, {n_failed} failed kept, "
            f"{len(todo)} to run ({'workers: ' + str(workers) if comm is None else where}, "
            f"{spec.ranks_per_run} rank{'s' * (spec.ranks_per_run > 1)} per run)")
    estimate = time_estimate(todo, groups if comm is not None else workers)
    if estimate:
        head += f"; {estimate}"
    if dry_run:
        print(head, file=out)
        print(describe(jobs, spec, states), file=out)
        return 0

    F.write_manifest(folder, spec, jobs, str(deck.path))
    if not quiet:
        print(head, file=sys.stderr)
    label = lambda job: f"job {job.index} ({job.label(spec.varied)})"  # noqa: E731
    progress = SweepProgress(todo, groups if comm is not None else workers, n_done, n_failed,
                             enabled=not quiet, label=label)
    meta = {"fingerprint": spec.fingerprint, "deck": deck.name, "source": str(spec.source),
            "n_jobs": len(jobs), "replicates": spec.replicates, "varied": json.dumps(spec.varied),
            "axes": json.dumps([axis.keys for axis in spec.axes]),
            "units": json.dumps({n: deck.tunables[n].unit for n in spec.parameters}),
            "spec": spec.text}
    recorder = Recorder(folder, kept, parameters, meta, progress)
    command = shlex.join(["vibrofeed", "sweep", str(spec_path), "-o", str(folder)])

    def warn(job, message):
        print(f"vibrofeed: warning: {label(job)}: {message}", file=sys.stderr)

    def run_one(job: Job):
        return run_job(job, folder, deck, spec.ranks_per_run, parameters, command, warn)

    try:
        if comm is None:
            run_local(todo, workers, run_one, recorder, progress)
        else:
            setup = {"deck": str(deck.path), "folder": str(folder), "ranks": spec.ranks_per_run,
                     "parameters": parameters, "command": command}
            run_mpi(comm, todo, setup, run_one, recorder, progress)
    finally:
        progress.close()
    # Only after a whole run: a sweep ended by an error leaves its journal to the next
    # run or reader (a snapshot then could raise another error in place of that one).
    recorder.close()
    rows = list(recorder.rows.values())
    failed = sum(r["status"] != S.DONE for r in rows)
    # a done job whose analysis measured no feed rate is no rate of zero: counted apart
    unmeasured = sum(r["status"] == S.DONE and bool(r.get("feedrate_reason")) for r in rows)
    print(f"sweep: {len(rows)} of {len(jobs)} jobs finished, {len(rows) - failed} done"
          + (f" ({unmeasured} without a measured feed rate: see vibrofeed sweep-report)"
             if unmeasured else "")
          + f", {failed} failed -> {folder / S.CSV_NAME}", file=out)
    if failed:
        raise RunError(f"{failed} of {len(jobs)} jobs failed (their errors are in "
                       f"{folder / S.CSV_NAME}); rerun with --retry-failed to run them again")
    return 0

