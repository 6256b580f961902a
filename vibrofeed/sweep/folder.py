"""A sweep's output folder: which sweep it belongs to, and what a rerun has left to do.

::

    DIR/sweep.json      the sweep file's fingerprint and content, and the jobs (the manifest)
    DIR/summary.h5      one row per finished job (summary.py): a snapshot, summary.csv the same
                        as text, and summary.journal.jsonl the rows finished since
    DIR/jobs/job-K.h5   job K's result (job-K.log its LIGGGHTS log)
    DIR/.lock           held while a sweep runs here

A folder belongs to one sweep file content (its fingerprint): running another
one into it is refused rather than mixing two designs in one summary. A rerun
keeps a ``done`` row only when the job's result opens as a complete vibrofeed
result whose run id is the job's (the deck, its includes, the parameters and
the vibrofeed version: an edited deck is another run), keeps ``failed`` rows
unless ``--retry-failed``, and runs everything else, through the runner's
``reuse`` so that a result that completed just before a kill is analysed, not
computed again.
"""

from __future__ import annotations

import json
import os
from datetime import UTC, datetime
from pathlib import Path

from .. import __version__
from ..errors import UsageError
from .plan import Job
from .spec import SweepSpec, describe_change
from .summary import CSV_NAME, DONE, FAILED, H5_NAME, JOURNAL_NAME, replace_atomically

SPEC_NAME = "sweep.json"
LOCK_NAME = ".lock"


def recorded(folder: Path) -> dict | None:
    """The sweep.json of ``folder``, or None."""
    path = folder / SPEC_NAME
    if not path.is_file():
        return None
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        raise UsageError(f"{path} is not readable; it is not a sweep folder vibrofeed wrote "
                         "(choose another -o DIR)") from None


def check_folder(folder: Path, spec: SweepSpec) -> bool:
    """Refuse a folder that holds another sweep or other files; True if it holds this sweep."""
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"-o {folder}: not a folder")
    old = recorded(folder) if folder.is_dir() else None
    if old is None:
        if folder.is_dir() and any(p.name in (H5_NAME, CSV_NAME, JOURNAL_NAME, "jobs")
                                   for p in folder.iterdir()):
            raise UsageError(f"{folder} holds sweep files but no {SPEC_NAME}: not a sweep vibrofeed "
                             "can resume; choose another -o DIR")
        return False
    if old.get("fingerprint") != spec.fingerprint:
        change = describe_change(old.get("spec", {}), spec.data)
        raise UsageError(
            f"{folder} holds another sweep (from {old.get('source', '?')}; {spec.source} differs in "
            f"{change}); its results would be mixed: give another -o DIR, or remove {folder} "
            "to start over")
    return True


def lock(folder: Path, what: str = "sweep"):
    """Hold ``folder``'s lock for this process (released when it exits, even by SIGKILL);
    UsageError when another ``what`` (a sweep, a study) holds it."""
    import fcntl

    fd = os.open(folder / LOCK_NAME, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        os.close(fd)
        raise UsageError(f"another vibrofeed {what} is running in {folder}; wait for it "
                         "or give another -o DIR") from None
    return fd


def clear_leftovers(folder: Path, runs: str = "jobs") -> list[Path]:
    """Remove what a killed sweep (or study) can leave behind: half-written summary or
    manifest copies (``.NAME.*.tmp``, never renamed into place), the runs' scratch
    folders (``<runs>/.vibrofeed-*``) and the logs of killed runs that left no frames
    (``<runs>/*.log.part`` without an ``.h5.part``). Call with the lock held."""
    from ..engine import scratch

    gone = [p for p in folder.glob(".*.tmp") if p.is_file()]
    gone += [p for p in (folder / runs).glob(scratch.PREFIX + "*") if p.is_dir()]
    # a killed run's log (OUT.log.part) without frames beside it (no OUT.h5.part): nothing runs
    # while the lock is held, so it belongs to no run, and no result keeps it company
    gone += [p for p in (folder / runs).glob("*.log.part")
             if not p.with_name(p.name.removesuffix(".log.part") + ".h5.part").exists()]
    for p in gone:
        if p.is_dir():
            scratch.remove(p)  # (and a killed run's log, when it left no frames)
        else:
            p.unlink(missing_ok=True)
    return gone


def write_manifest(folder: Path, spec: SweepSpec, jobs: list[Job], deck_path: str) -> None:
    old = recorded(folder) or {}
    now = datetime.now(UTC).isoformat(timespec="seconds")
    doc = {
        "format": "vibrofeed-sweep", "fingerprint": spec.fingerprint, "source": str(spec.source),
        "deck": deck_path, "vibrofeed": __version__, "created": old.get("created", now),
        "updated": now, "spec": spec.data,
        "jobs": [{"job": j.index, "file": j.file, "replicate": j.replicate, "seed": j.seed,
                  "parameters": j.params, "run_id": j.run_id, "cost": j.cost} for j in jobs],
    }
    text = json.dumps(doc, indent=1)
    replace_atomically(folder / SPEC_NAME, lambda tmp: tmp.write_text(text))


def result_is_true(folder: Path, job: Job) -> bool:
    """Whether ``job``'s result is there, complete, and of this very run (its run id)."""
    from ..errors import ResultError
    from ..results.reader import Result

    path = folder / job.file
    if not path.is_file():
        return False
    try:
        with Result(path) as r:  # refuses a file whose run did not complete
            return r.run_id == job.run_id and r.n_frames > 0
    except (ResultError, OSError, KeyError):
        return False


def resume(jobs: list[Job], rows: list[dict], retry_failed: bool, verify) -> tuple[list[dict], list[Job]]:
    """(rows kept, jobs to run) of a rerun.

    ``rows``: the summary's rows (:func:`.summary.read`: the snapshot and its
    journal, so every job recorded before a kill); ``verify(job)``: whether a done job's result
    still checks (see :func:`result_is_true`). A row is kept only if it
    belongs to a planned job with the same run id and, when ``done``, its file
    checks; a ``failed`` row is kept unless ``retry_failed``."""
    by_job = {row["job"]: row for row in rows}
    kept, todo = [], []
    for job in jobs:
        row = by_job.get(job.index)
        if row is not None and row.get("run_id") == job.run_id:
            if row.get("status") == DONE and verify(job):
                kept.append(row)
                continue
            if row.get("status") == FAILED and not retry_failed:
                kept.append(row)
                continue
        todo.append(job)
    return kept, todo
