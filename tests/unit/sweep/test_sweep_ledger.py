"""The summary's journal and snapshots (summary.Ledger, summary.read): O(1) per finished job,
true at every instant (a torn line, a kill inside a compaction, SIGKILL), and a resume that
skips exactly the finished jobs. No engine: rows are made by hand."""

from __future__ import annotations

import csv
import errno
import json
import math
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from vibrofeed.errors import ResultError
from vibrofeed.sweep import folder as F
from vibrofeed.sweep import plan as P
from vibrofeed.sweep import summary as S
from vibrofeed.sweep.spec import parse

PARAMS = ["a"]
SPEC = 'deck = "bulk_feeder"\nreplicates = 2\n[grid]\namp_n = [5e-5, 1e-4, 2e-4]\n'


class Killed(BaseException):
    """Stands for SIGKILL at one step: nothing after it runs (not an Exception: never caught)."""


def row(job, status=S.DONE, **metrics):
    out = {"job": job, "replicate": job % 2, "seed": 100 + job, "a": 0.5 * job, "status": status,
           "error": "" if status == S.DONE else "LIGGGHTS error: boom, with a comma",
           "file": f"jobs/job-{job:04d}.h5" if status == S.DONE else "", "run_id": f"id{job}",
           "wall_s": 1.25 + job}
    out.update(metrics)
    return out


def as_snapshot(rows, folder):
    """What read gives for ``rows`` written as a snapshot alone (no journal)."""
    folder.mkdir()
    S.write(folder, rows, PARAMS, {})
    assert not (folder / S.JOURNAL_NAME).exists()
    return S.read(folder)[0]


def journal_jobs(folder):
    """The jobs of the journal's complete row lines (its first line is the header)."""
    text = (folder / S.JOURNAL_NAME).read_text()
    return [json.loads(line)["job"] for line in text.split("\n")[1:-1]]


def csv_jobs(folder):
    with open(folder / S.CSV_NAME, newline="") as f:
        return [int(r["job"]) for r in csv.DictReader(f)]


# ------------------------------------------------------------------ rows in, rows out
def test_rows_read_equal_rows_added_from_the_journal_and_from_the_snapshot(tmp_path):
    added = [row(3, parts_per_s=0.1 + 0.2, n_events=np.int64(288), reason=None),
             row(0, parts_per_s=math.nan, n_events=12, reason="too few exits"),
             row(2, S.FAILED, parts_per_s=None, n_events=None),
             row(1, parts_per_s=np.float64(346.7), n_events=7, reason="")]
    folder = tmp_path / "sweep"
    folder.mkdir()
    ledger = S.Ledger(folder, PARAMS, {"n_jobs": 4})
    for r in added:
        ledger.add(r)
    # nothing compacted yet: what read gives comes from the journal
    assert ledger.compactions == 1 and journal_jobs(folder) == [3, 0, 2, 1]
    back, meta = S.read(folder)
    assert [r["job"] for r in back] == [0, 1, 2, 3]  # sorted by job
    assert meta["n_jobs"] == 4 and meta["parameters"] == PARAMS
    assert meta["metrics"] == ["parts_per_s", "n_events", "reason"]
    # exactly equal (no tolerance): JSON and HDF5 keep every digit of a float
    assert back[3]["parts_per_s"] == 0.1 + 0.2 and back[1]["parts_per_s"] == 346.7
    assert back[0]["parts_per_s"] is None  # NaN: None, as the snapshot reads it
    assert back[2]["error"] == "LIGGGHTS error: boom, with a comma" and back[2]["file"] is None
    assert back[0]["error"] is None and back[1]["reason"] is None and back[0]["reason"] == "too few exits"
    # n_events has a missing value, so the snapshot stores it as float: the journal's rows read so too
    assert back[3]["n_events"] == 288 and isinstance(back[3]["n_events"], float)
    assert back == as_snapshot(added, tmp_path / "alone")  # the same rows as a snapshot of them gives
    # the CSV alone is the last snapshot: older (no row yet), never wrong
    assert csv_jobs(folder) == []
    ledger.close()
    assert not (folder / S.JOURNAL_NAME).exists() and csv_jobs(folder) == [0, 1, 2, 3]
    assert S.read(folder) == (back, meta)


def test_a_later_row_of_a_job_replaces_the_earlier_one(tmp_path):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    ledger.add(row(0, S.FAILED))
    ledger.add(row(1))
    ledger.add(row(0, parts_per_s=5.0))  # --retry-failed ran it again
    back = S.read(tmp_path)[0]
    assert [(r["job"], r["status"]) for r in back] == [(0, S.DONE), (1, S.DONE)]
    assert back[0]["parts_per_s"] == 5.0 and back[0]["error"] is None
    ledger.close()


def test_another_table_keeps_its_own_files(tmp_path):
    S.write(tmp_path, [row(0)], PARAMS, {})
    study = S.Ledger(tmp_path, PARAMS, {"kind": "study"}, stem="study")
    study.add(row(5, objective=2.5))
    assert (tmp_path / "study.journal.jsonl").is_file() and not (tmp_path / S.JOURNAL_NAME).exists()
    rows, meta = S.read(tmp_path, stem="study")
    assert [r["job"] for r in rows] == [5] and rows[0]["objective"] == 2.5 and meta["kind"] == "study"
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0]  # the summary untouched
    study.close()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["study.csv", "study.h5", "summary.csv",
                                                          "summary.h5"]


# ------------------------------------------------------------------ true at every instant
def test_a_torn_last_line_is_ignored_and_the_next_ledger_starts_clean(tmp_path):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    for job in range(3):
        ledger.add(row(job))
    ledger._close_journal()  # killed: no close()
    line = S._line(row(3))
    with open(tmp_path / S.JOURNAL_NAME, "ab") as f:
        f.write(line[: len(line) // 2])  # the kill landed inside the write of job 3's line
    rows = S.read(tmp_path)[0]
    assert [r["job"] for r in rows] == [0, 1, 2]
    resumed = S.Ledger(tmp_path, PARAMS, {}, rows=rows)  # starts with a snapshot, no journal
    assert not (tmp_path / S.JOURNAL_NAME).exists()
    resumed.add(row(3))
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 1, 2, 3]
    assert journal_jobs(tmp_path) == [3]
    resumed.close()


def test_a_torn_header_is_an_empty_journal_and_a_damaged_line_is_named(tmp_path):
    S.write(tmp_path, [row(0)], PARAMS, {})
    (tmp_path / S.JOURNAL_NAME).write_bytes(b'{"format":"vibrofeed-sweep-jour')
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0]
    ledger = S.Ledger(tmp_path, PARAMS, {}, rows=[row(0)])
    ledger.add(row(1))
    ledger._close_journal()
    text = (tmp_path / S.JOURNAL_NAME).read_bytes()
    head, rest = text.split(b"\n", 1)
    (tmp_path / S.JOURNAL_NAME).write_bytes(head + b"\n" + rest[:10] + b"\n" + rest)
    with pytest.raises(ResultError, match=S.JOURNAL_NAME):
        S.read(tmp_path)


def test_a_kill_between_snapshot_and_journal_removal_loses_and_duplicates_nothing(tmp_path, monkeypatch):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    for job in (0, 1, 2):
        ledger.add(row(job))

    def killed(*args, **kwargs):
        raise Killed

    # the new snapshot is in place, the old journal not yet gone: readers skip it
    monkeypatch.setattr(type(ledger.journal), "unlink", killed)
    with pytest.raises(Killed):
        ledger.compact()
    monkeypatch.undo()
    assert journal_jobs(tmp_path) == [0, 1, 2] and csv_jobs(tmp_path) == [0, 1, 2]
    rows = S.read(tmp_path)[0]
    assert [r["job"] for r in rows] == [0, 1, 2]

    # A resumed sweep finds job 1's result untrue and drops its row; killed at the same
    # step, the journal that still holds job 1 must not bring it back.
    kept = [r for r in rows if r["job"] != 1]
    monkeypatch.setattr(type(ledger.journal), "unlink", killed)
    with pytest.raises(Killed):
        S.Ledger(tmp_path, PARAMS, {}, rows=kept)
    monkeypatch.undo()
    assert journal_jobs(tmp_path) == [0, 1, 2]
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 2]


def test_a_kill_between_the_csv_and_the_hdf5_snapshot_loses_and_duplicates_nothing(tmp_path, monkeypatch):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    for job in (0, 1):
        ledger.add(row(job))
    replace, calls = os.replace, []

    def replace_once(src, dst):
        calls.append(dst)
        if len(calls) > 1:
            raise Killed
        replace(src, dst)

    monkeypatch.setattr(os, "replace", replace_once)
    with pytest.raises(Killed):
        ledger.compact()
    monkeypatch.undo()
    assert [os.path.basename(c) for c in calls] == [S.CSV_NAME, S.H5_NAME]
    assert csv_jobs(tmp_path) == [0, 1]  # the new CSV; summary.h5 is the old one, with its journal
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 1]


def test_a_failed_snapshot_leaves_the_journal_going_on(tmp_path, monkeypatch):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    ledger.add(row(0))

    def full(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError, match="disk full"):
        ledger.compact()
    monkeypatch.undo()
    ledger.add(row(1))  # appended to the journal the snapshot on disk still matches
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 1] and journal_jobs(tmp_path) == [0, 1]
    ledger.close()


def test_a_short_write_is_undone_and_the_journal_goes_on(tmp_path, monkeypatch):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    ledger.add(row(0))
    write = os.write
    monkeypatch.setattr(os, "write", lambda fd, data: write(fd, data[: len(data) // 2]))  # disk full
    with pytest.raises(OSError) as info:
        ledger.add(row(1))
    monkeypatch.undo()
    assert info.value.errno == errno.ENOSPC
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0]  # job 1 is not recorded, nor half of it
    ledger.add(row(2))  # after a whole line, not after half of one
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 2] and journal_jobs(tmp_path) == [0, 2]
    ledger.close()


def test_sigkill_after_some_jobs_and_a_resume_skips_exactly_the_finished_jobs(tmp_path):
    spec_path = tmp_path / "s.toml"
    spec_path.write_text(SPEC)
    folder = tmp_path / "out"
    folder.mkdir()
    # A sweep process that records jobs 4, 1 (failed) and 5, then dies by SIGKILL.
    code = f"""
import os, signal
from pathlib import Path
from vibrofeed.sweep.execute import Recorder, base_row
from vibrofeed.sweep.plan import plan
from vibrofeed.sweep.spec import load
jobs = plan(load({str(spec_path)!r}))
recorder = Recorder(Path({str(folder)!r}), [], ["amp_n"], {{"n_jobs": len(jobs)}})
for k in (4, 1, 5):
    row = base_row(jobs[k], ["amp_n"])
    row.update(status="failed" if k == 1 else "done", error="boom" if k == 1 else "", file=jobs[k].file)
    recorder.add(jobs[k], row, True)
os.kill(os.getpid(), signal.SIGKILL)
"""
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    assert journal_jobs(folder) == [4, 1, 5]  # the kill came before any later snapshot
    jobs = P.plan(parse(SPEC, spec_path))
    rows = S.read(folder)[0]
    kept, todo = F.resume(jobs, rows, False, lambda job: True)
    assert [r["job"] for r in kept] == [1, 4, 5] and [j.index for j in todo] == [0, 2, 3]
    kept, todo = F.resume(jobs, rows, True, lambda job: True)
    assert [r["job"] for r in kept] == [4, 5] and [j.index for j in todo] == [0, 1, 2, 3]


# ------------------------------------------------------------------ O(1) per job
def test_add_writes_one_line_and_the_snapshots_are_amortised(tmp_path, monkeypatch):
    monkeypatch.setattr(S.Ledger, "INTERVAL", math.inf)  # the row rule alone: deterministic
    snapshots, flushes = [], []
    write_snapshot = S._write_snapshot

    def counted(folder, rows, *args):
        snapshots.append(len(rows))
        write_snapshot(folder, rows, *args)

    monkeypatch.setattr(S, "_write_snapshot", counted)
    # the disk's speed is not what this test measures: count the flushes instead of waiting
    monkeypatch.setattr(S.os, "fdatasync", flushes.append)
    ledger = S.Ledger(tmp_path, PARAMS, {})
    journal, grew = tmp_path / S.JOURNAL_NAME, []
    n = 1000
    for job in range(n):
        before = journal.stat().st_size if journal.exists() else None
        r = row(job, parts_per_s=1.0 + job, n_events=job)
        ledger.add(r)
        if before is not None and journal.exists():  # no snapshot came between
            grew.append(journal.stat().st_size - before - len(S._line(r)))
    assert len(grew) > 0.95 * n and set(grew) == {0}  # each add: its own line, nothing more
    headers = len(snapshots)  # each snapshot but the last is followed by a journal's header
    assert len(flushes) == n + headers - 1 + journal.exists()  # one flush per add
    # The old summary rewrote every row after each job: 1000 snapshots, 500 500 rows.
    # Now a snapshot waits for a quarter of the rows: O(log n) of them, under 5 rows per add.
    assert len(snapshots) <= 12 and sum(snapshots) <= 5 * n
    ledger.close()
    assert [r["job"] for r in S.read(tmp_path)[0]] == list(range(n))


def test_the_snapshot_follows_the_journal_within_the_interval(tmp_path, monkeypatch):
    now = [1000.0]
    monkeypatch.setattr(S.time, "monotonic", lambda: now[0])
    ledger = S.Ledger(tmp_path, PARAMS, {})
    ledger.add(row(0))
    assert csv_jobs(tmp_path) == []  # 0 s after the last snapshot: the journal only
    now[0] += S.Ledger.INTERVAL
    ledger.add(row(1))
    assert csv_jobs(tmp_path) == [0, 1] and not (tmp_path / S.JOURNAL_NAME).exists()
    ledger.close()


# ------------------------------------------------------------------ how each column is stored
INTS = ("job", "replicate", "seed", "n_parts", "n_events")  # whole numbers in every row


def typed_rows():
    return [row(job, n_parts=300 + job, n_events=np.int64(288 + job), parts_per_s=2.0,
                mixed=[4, 4.5, 5][job], reason=None) for job in range(3)]


def test_an_integer_column_reads_back_as_int_from_the_journal_and_the_snapshot(tmp_path):
    ledger = S.Ledger(tmp_path, PARAMS, {})
    for r in typed_rows():
        ledger.add(r)
    from_journal = S.read(tmp_path)[0]
    ledger.close()
    assert not (tmp_path / S.JOURNAL_NAME).exists()
    from_snapshot = S.read(tmp_path)[0]
    for rows in (from_journal, from_snapshot):
        for job, r in enumerate(rows):
            got = {c: r[c] for c in INTS}
            assert got == {"job": job, "replicate": job % 2, "seed": 100 + job, "n_parts": 300 + job,
                           "n_events": 288 + job}
            # int, never 288.0 (== 288 in Python: the type is the test) nor "288" nor a numpy int
            assert {c: type(v) for c, v in got.items()} == dict.fromkeys(INTS, int)
            # a float column holding whole values stays float; a column of ints and floats is float
            assert type(r["parts_per_s"]) is float and type(r["a"]) is float and type(r["mixed"]) is float
            assert r["mixed"] == [4.0, 4.5, 5.0][job]
            assert r["reason"] is None and type(r["file"]) is str


def test_an_integer_column_is_int64_in_the_hdf5_file_and_written_without_a_point_in_the_csv(tmp_path):
    import h5py

    S.write(tmp_path, typed_rows(), PARAMS, {})
    with h5py.File(tmp_path / S.H5_NAME, "r") as f:
        jobs = f["jobs"]
        assert {c: jobs[c].dtype for c in INTS} == dict.fromkeys(INTS, np.dtype(np.int64))
        assert jobs["parts_per_s"].dtype == np.float64 and jobs["mixed"].dtype == np.float64
        assert jobs["reason"].dtype == np.float64 and np.isnan(jobs["reason"][()]).all()  # no row needed it
        assert h5py.check_string_dtype(jobs["file"].dtype) is not None
        assert jobs["n_events"][()].tolist() == [288, 289, 290]
    with open(tmp_path / S.CSV_NAME, newline="") as f:
        table = list(csv.DictReader(f))
    assert [r["n_events"] for r in table] == ["288", "289", "290"]
    assert [r["seed"] for r in table] == ["100", "101", "102"]
    assert [r["job"] for r in table] == ["0", "1", "2"]
    assert [int(r["n_parts"]) for r in table] == [300, 301, 302]       # int() reads every one
    assert [r["parts_per_s"] for r in table] == ["2.0"] * 3            # a float keeps its point
    assert [r["mixed"] for r in table] == ["4", "4.5", "5"]           # each value as it was given
    assert [r["reason"] for r in table] == ["", "", ""]


def test_one_missing_value_makes_an_integer_column_float_and_none_reads_none(tmp_path):
    rows = typed_rows()
    rows[1]["n_events"] = None
    S.write(tmp_path, rows, PARAMS, {})
    back = S.read(tmp_path)[0]
    assert [r["n_events"] for r in back] == [288.0, None, 290.0]
    assert type(back[0]["n_events"]) is float and type(back[0]["n_parts"]) is int


# ------------------------------------------------------------------ when a snapshot is due
def test_a_snapshot_is_due_at_64_rows_pending_or_a_quarter_of_the_rows(tmp_path, monkeypatch):
    monkeypatch.setattr(S.Ledger, "INTERVAL", math.inf)  # the row rule alone
    monkeypatch.setattr(S.os, "fdatasync", lambda fd: None)  # the disk's speed is not tested here
    (tmp_path / "a").mkdir()
    ledger = S.Ledger(tmp_path / "a", PARAMS, {})
    assert ledger.compactions == 1 and ledger.pending == 0
    for job in range(63):
        ledger.add(row(job))
    assert (ledger.compactions, ledger.pending) == (1, 63)
    ledger.add(row(63))  # 64 pending: max(64, 64 // 4)
    assert (ledger.compactions, ledger.pending) == (2, 0)
    for job in range(64, 127):
        ledger.add(row(job))
    assert ledger.compactions == 2  # 63 pending since: not yet
    ledger.add(row(127))
    assert ledger.compactions == 3
    ledger.close()
    assert [r["job"] for r in S.read(tmp_path / "a")[0]] == list(range(128))
    # 200 rows kept: after m adds, due once m >= (200 + m) // 4, first at m = 66 (266 // 4 = 66;
    # at m = 65, 265 // 4 = 66 is one more than pending)
    (tmp_path / "b").mkdir()
    ledger = S.Ledger(tmp_path / "b", PARAMS, {}, rows=[row(job) for job in range(200)])
    for job in range(200, 265):
        ledger.add(row(job))
    assert (ledger.compactions, ledger.pending) == (1, 65)
    ledger.add(row(265))
    assert (ledger.compactions, ledger.pending) == (2, 0)
    ledger.close()


def test_the_snapshot_is_due_a_minute_after_the_last_one(tmp_path, monkeypatch):
    now = [1000.0]
    monkeypatch.setattr(S.time, "monotonic", lambda: now[0])  # snapshots then take no time
    ledger = S.Ledger(tmp_path, PARAMS, {})
    now[0] += 59.999
    ledger.add(row(0))
    assert ledger.compactions == 1 and csv_jobs(tmp_path) == []
    now[0] = 1000.0 + 60.0
    ledger.add(row(1))
    assert ledger.compactions == 2 and csv_jobs(tmp_path) == [0, 1]
    ledger.close()


def test_rows_and_stem_are_keyword_arguments(tmp_path):
    ledger = S.Ledger(folder=tmp_path, parameters=PARAMS, meta={}, rows=[row(0)], stem="study")
    ledger.close()
    assert [r["job"] for r in S.read(tmp_path, stem="study")[0]] == [0]
    with pytest.raises(TypeError):
        S.Ledger(tmp_path, PARAMS, {}, [row(1)])  # rows must be named


# ------------------------------------------------------------------ the journal's file
def test_a_short_write_of_the_journals_header_leaves_an_empty_journal(tmp_path, monkeypatch):
    ledger = S.Ledger(tmp_path, PARAMS, {}, rows=[row(0)])
    write = os.write
    monkeypatch.setattr(os, "write", lambda fd, data: write(fd, data[: len(data) // 2]))  # disk full
    with pytest.raises(OSError) as info:
        ledger.add(row(1))  # the first add opens the journal: its header is cut short
    monkeypatch.undo()
    assert info.value.errno == errno.ENOSPC  # the full disk, not a failure to undo it
    assert (tmp_path / S.JOURNAL_NAME).read_bytes() == b""  # the half header undone
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0]
    ledger.add(row(2))  # a new journal, its header whole
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 2] and journal_jobs(tmp_path) == [2]
    ledger.close()


def test_the_journal_is_readable_by_all_and_executable_by_none(tmp_path):
    old = os.umask(0o022)
    try:
        ledger = S.Ledger(tmp_path, PARAMS, {})
        ledger.add(row(0))
    finally:
        os.umask(old)
    assert (tmp_path / S.JOURNAL_NAME).stat().st_mode & 0o777 == 0o644
    ledger.close()


def test_a_folder_that_cannot_be_fsynced_or_opened_still_gets_its_summary(tmp_path, monkeypatch):
    import stat

    fsync = os.fsync

    def files_only(fd):  # some file systems refuse fsync on a directory (EINVAL)
        if stat.S_ISDIR(os.fstat(fd).st_mode):
            raise OSError(errno.EINVAL, "Invalid argument")
        fsync(fd)

    monkeypatch.setattr(S.os, "fsync", files_only)
    S.write(tmp_path, [row(0), row(1)], PARAMS, {})
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 1]
    monkeypatch.undo()
    open_ = os.open

    def no_folders(path, flags, *args):  # nor may a directory always be opened
        if os.path.isdir(path):
            raise OSError(errno.EACCES, "Permission denied")
        return open_(path, flags, *args)

    monkeypatch.setattr(S.os, "open", no_folders)
    ledger = S.Ledger(tmp_path, PARAMS, {}, rows=[row(0)])
    ledger.add(row(1))  # the journal's folder is not opened either
    ledger.close()
    monkeypatch.undo()
    assert [r["job"] for r in S.read(tmp_path)[0]] == [0, 1]


# ------------------------------------------------------------------ the snapshot's file
def test_the_snapshot_carries_the_format_version_format_md_gives(tmp_path):
    import re
    from pathlib import Path

    import h5py

    doc = (Path(__file__).resolve().parents[3] / "FORMAT.md").read_text()
    found = re.search(r'format = "vibrofeed-sweep-summary", \+format_version = \[(\d+), (\d+)\]', doc)
    S.write(tmp_path, [row(0)], PARAMS, {})
    with h5py.File(tmp_path / S.H5_NAME, "r") as f:
        assert f.attrs["format"] == S.FORMAT
        assert f.attrs["format_version"].tolist() == [int(found[1]), int(found[2])]


def _damage(folder, how):
    """A snapshot of two rows, then damaged ``how``."""
    import h5py

    S.write(folder, [row(0), row(1)], PARAMS, {})
    path = folder / S.H5_NAME
    if how == "not hdf5":
        path.write_bytes(b"not an HDF5 file at all")
        return
    with h5py.File(path, "a") as f:
        g = f["jobs"]
        if how == "no jobs":
            del f["jobs"]
        elif how == "columns not a list":
            g.attrs["columns"] = 5
        elif how == "undecodable text":
            del g["file"]
            g.create_dataset("file", data=np.array([b"\xff", b"x"], dtype=object),
                             dtype=h5py.string_dtype("ascii"))
        elif how == "a column too short":  # the job column has three rows, the others two
            del g["job"]
            g.create_dataset("job", data=np.array([0, 1, 2], dtype=np.int64))
        elif how == "the job column too short":  # one row, the others two: never cut to one
            del g["job"]
            g.create_dataset("job", data=np.array([0], dtype=np.int64))


@pytest.mark.parametrize("how, error", [
    ("not hdf5", "file signature not found"),
    ("no jobs", "object 'jobs' doesn't exist"),
    ("columns not a list", "a layout that is not a sweep summary's"),
    ("undecodable text", "text that is not ASCII"),
    ("a column too short", "its columns hold 2 to 3 rows"),
    ("the job column too short", "its columns hold 1 to 2 rows"),
])
def test_a_damaged_snapshot_is_a_result_error_naming_the_file_and_why(tmp_path, how, error):
    """In the user's words: no Python exception's name (it said "(TypeError: 'numpy.int64'
    object is not iterable)")."""
    _damage(tmp_path, how)
    with pytest.raises(ResultError) as info:
        S.read(tmp_path)
    message = str(info.value)
    assert message == (f"{tmp_path / S.H5_NAME}: not a readable sweep summary ({error}): damaged, or not "
                       "written by vibrofeed"), message
    assert info.value.__cause__ is None


def test_a_damaged_snapshot_names_the_first_line_of_a_long_error(tmp_path, monkeypatch):
    import h5py

    S.write(tmp_path, [row(0)], PARAMS, {})

    def stack(*args, **kwargs):  # HDF5 can report a stack of errors, one a line
        raise OSError("Unable to open file (bad object header)\n  #001: H5Oint.c line 1 in H5O_protect")

    monkeypatch.setattr(h5py, "File", stack)
    with pytest.raises(ResultError) as info:
        S.read(tmp_path)
    assert str(info.value).endswith("(bad object header): damaged, or not written by vibrofeed")


def test_the_interval_stretches_to_fifty_times_the_last_snapshots_duration(tmp_path, monkeypatch):
    now = [1000.0]
    monkeypatch.setattr(S.time, "monotonic", lambda: now[0])
    write_snapshot = S._write_snapshot

    def slow(*args):  # each snapshot takes 2 s: the next is due 50 x 2 = 100 s later, not 60
        write_snapshot(*args)
        now[0] += 2.0

    monkeypatch.setattr(S, "_write_snapshot", slow)
    ledger = S.Ledger(tmp_path, PARAMS, {})  # its first snapshot ends at 1002 s
    now[0] = 1002.0 + 99.999
    ledger.add(row(0))
    assert ledger.compactions == 1
    now[0] = 1002.0 + 100.0
    ledger.add(row(1))
    assert ledger.compactions == 2 and csv_jobs(tmp_path) == [0, 1]
    ledger.close()


def test_an_interruption_just_after_the_rename_propagates_as_it_is(tmp_path, monkeypatch):
    replace = os.replace

    def renamed_then_killed(src, dst):  # e.g. SIGINT's KeyboardInterrupt as os.replace returns
        replace(src, dst)
        raise Killed

    S.write(tmp_path, [row(0)], PARAMS, {})
    monkeypatch.setattr(os, "replace", renamed_then_killed)
    with pytest.raises(Killed):  # not a FileNotFoundError from cleaning the renamed file up
        S.replace_atomically(tmp_path / "x.txt", lambda tmp: tmp.write_text("new"))
    monkeypatch.undo()
    assert (tmp_path / "x.txt").read_text() == "new"
    assert not list(tmp_path.glob(".*.tmp"))


@pytest.mark.parametrize("head, rows", [
    ({"format": "another-journal", "generation": "g"}, []),   # another format
    ([1, 2], []),                                             # JSON, not a header
    ({"format": S.JOURNAL_FORMAT, "generation": "g"}, [{"status": "done"}]),  # a row without job
    ({"format": S.JOURNAL_FORMAT, "generation": "g"}, [[0]]),                 # a row not a table
])
def test_a_journal_vibrofeed_did_not_write_is_a_result_error_naming_it(tmp_path, head, rows):
    S.write(tmp_path, [row(0)], PARAMS, {})
    lines = [json.dumps(head)] + [json.dumps(r) for r in rows]
    (tmp_path / S.JOURNAL_NAME).write_text("".join(line + "\n" for line in lines))
    with pytest.raises(ResultError, match=f"{S.JOURNAL_NAME}: not a vibrofeed sweep journal"):
        S.read(tmp_path)


def test_a_snapshot_without_columns_holds_no_rows(tmp_path):
    import h5py

    S.write(tmp_path, [row(0)], PARAMS, {})
    with h5py.File(tmp_path / S.H5_NAME, "a") as f:
        f["jobs"].attrs["columns"] = np.array([], dtype=h5py.string_dtype())
    assert S.read(tmp_path)[0] == []


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_snapshots_and_sweep_files_have_the_mode_of_a_new_file(tmp_path, mask):
    # (mkstemp makes its file 0600: a summary others in the group could not read)
    old = os.umask(mask)
    try:
        S.replace_atomically(tmp_path / "a.csv", lambda tmp: tmp.write_text("x"))
        ledger = S.Ledger(tmp_path, PARAMS, {})
        ledger.add(row(0))
        ledger.close()
    finally:
        os.umask(old)
    for name in ("a.csv", S.CSV_NAME, S.H5_NAME):
        assert (tmp_path / name).stat().st_mode & 0o777 == 0o666 & ~mask, name


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_the_umask_is_read_without_setting_it(monkeypatch, mask):
    # Setting the umask to learn it and restoring it would give a file another thread creates
    # meanwhile the wrong mode: on Linux (the project's platform) it is read from /proc, and
    # os.umask is never called.
    old = os.umask(mask)
    try:
        def refuse(_):
            raise AssertionError("the umask was set to read it")

        monkeypatch.setattr(S.os, "umask", refuse)
        assert S._umask() == mask
    finally:
        monkeypatch.undo()
        os.umask(old)
