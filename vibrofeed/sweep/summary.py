"""The sweep's summary: one row per finished job, kept as a snapshot and a journal.

Three files in the sweep's folder (``stem`` = ``summary``; another table of the
same layout, such as the optimiser's ``study``, passes its own stem):

* ``summary.journal.jsonl``: one JSON line per finished job, appended with a
  single ``write`` and flushed to disk before the job counts as recorded: O(1)
  per job. A kill can tear only the last line, which readers ignore.
* ``summary.h5`` and ``summary.csv``: a snapshot of every row, each file
  written whole to a temporary file, flushed and renamed over the old one
  (:func:`replace_atomically`). It is rewritten only now and then
  (:class:`Ledger`: once the journal holds a quarter of the rows, a minute
  after the last one, and at the end), so its cost per job is bounded
  whatever the number of rows.

The journal's first line names the snapshot it follows (``generation``, also
an attribute of the HDF5 file); a compaction writes the new snapshot with a
new generation first, then removes the journal. A kill between the two leaves
a journal of the old generation, which readers skip: its rows are all in the
new snapshot, and a row a resumed sweep dropped (no longer true) does not come
back. :func:`read` is the snapshot plus the journal lines of its generation (a
later line for a job replaces an earlier one), each value stored as a rewrite
of the snapshot would store it. A reader that opens ``summary.csv`` alone sees
an older snapshot, true of every job it lists. Layout in FORMAT.md, "Sweep
summary".

Columns: ``job``, ``replicate``, ``seed``, the parameters the sweep file names
(resolved values, deck defaults applied), ``status`` (``done``, ``failed``),
``error`` (empty when done), ``file`` (relative to the folder; for a failed
run, the partial ``.h5.part`` when it left frames, else empty), ``run_id``,
``wall_s`` (seconds the job took), then the metrics (:mod:`.metrics`).
Missing values are NaN in HDF5, empty cells in the CSV and null in the
journal; rows read back hold None for them.
"""

from __future__ import annotations

import csv
import errno
import io
import json
import math
import os
import tempfile
import time
import uuid
from pathlib import Path

from ..values import to_json

FORMAT = "vibrofeed-sweep-summary"
FORMAT_VERSION = (1, 1)
JOURNAL_FORMAT = "vibrofeed-sweep-journal"
STEM = "summary"
H5_NAME, CSV_NAME, JOURNAL_NAME = f"{STEM}.h5", f"{STEM}.csv", f"{STEM}.journal.jsonl"
HEAD = ("job", "replicate", "seed")
STATE = ("status", "error", "file", "run_id", "wall_s")
DONE, FAILED = "done", "failed"
# Root attributes the snapshot writes itself (or read adds): never taken from the caller's meta.
OWN_ATTRS = ("format", "format_version", "generation", "columns", "parameters", "metrics")


def paths(folder, stem: str = STEM) -> tuple[Path, Path, Path]:
    """(HDF5 snapshot, CSV snapshot, journal) of the table ``stem`` in ``folder``."""
    folder = Path(folder)
    return folder / f"{stem}.h5", folder / f"{stem}.csv", folder / f"{stem}.journal.jsonl"


def columns(rows: list[dict], parameters: list[str]) -> list[str]:
    """Column order: HEAD, the parameters, STATE, then the metrics as they first appear."""
    fixed = list(HEAD) + [p for p in parameters if p not in HEAD] + list(STATE)
    seen = set(fixed)
    metrics = []
    for row in rows:
        for key in row:
            if key not in seen:
                seen.add(key)
                metrics.append(key)
    return fixed + metrics


def _missing(value) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def _kind(values: list) -> str:
    """``int``, ``float`` or ``str``: how a column is stored."""
    present = [v for v in values if not _missing(v)]
    if len(present) == len(values) and all(isinstance(v, int) and not isinstance(v, bool)
                                           for v in present):
        return "int"
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in present):
        return "float"
    return "str"


def _typed(values: list) -> tuple[str, list]:
    """(kind, values as the snapshot stores and reads them back: missing and empty text None)."""
    kind = _kind(values)
    if kind == "int":
        return kind, [int(v) for v in values]
    if kind == "float":
        return kind, [None if _missing(v) else float(v) for v in values]
    return kind, [None if _missing(v) or v == "" else str(v) for v in values]


def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _umask() -> int:
    """The process' umask, read without changing it (Linux), else set and restored."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def replace_atomically(path: Path, write) -> None:
    """``write(tmp_path)`` then fsync and rename over ``path``: readers see the
    old file or the new one, never a part of either."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:  # mkstemp's 0600 would keep the summary from the rest of the group: a new file's mode
        os.fchmod(fd, 0o666 & ~_umask())
    finally:
        os.close(fd)
    try:
        write(Path(tmp))
        with open(tmp, "rb+") as f:
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _fsync_dir(path.parent)


def _cell(value) -> str:
    if _missing(value):
        return ""
    return repr(value) if isinstance(value, float) else str(value)  # repr: every digit kept


def csv_text(rows: list[dict], cols: list[str]) -> str:
    out = io.StringIO()
    w = csv.writer(out, lineterminator="\n")
    w.writerow(cols)
    for row in rows:
        w.writerow([_cell(row.get(c)) for c in cols])
    return out.getvalue()


def _layout(rows: list[dict], parameters: list[str]) -> dict:
    """The columns of ``rows`` (sorted by job) and which are parameters and metrics."""
    cols = columns(rows, parameters)
    return {"columns": cols, "parameters": [c for c in cols if c in parameters],
            "metrics": [c for c in cols if c not in HEAD and c not in STATE and c not in parameters]}


# ----------------------------------------------------------------- the snapshot
def _write_snapshot(folder, rows: list[dict], parameters: list[str], meta: dict, stem: str,
                    generation: str) -> None:
    """Replace the snapshot (CSV, then HDF5) by ``rows``, as of journal ``generation``."""
    h5_path, csv_path, _ = paths(folder, stem)
    rows = sorted(rows, key=lambda r: r["job"])
    layout = _layout(rows, parameters)

    def write_h5(tmp: Path) -> None:
        import h5py
        import numpy as np

        with h5py.File(tmp, "w") as f:
            for key, value in meta.items():
                if key not in OWN_ATTRS:
                    f.attrs[key] = value
            f.attrs["format"] = FORMAT
            f.attrs["format_version"] = np.array(FORMAT_VERSION, dtype=np.int32)
            f.attrs["generation"] = generation
            g = f.create_group("jobs")
            for key, names in layout.items():
                g.attrs[key] = names
            for c in layout["columns"]:
                kind, values = _typed([row.get(c) for row in rows])
                if kind == "int":
                    g.create_dataset(c, data=np.array(values, dtype=np.int64))
                elif kind == "float":
                    g.create_dataset(c, data=np.array([math.nan if v is None else v for v in values],
                                                      dtype=np.float64))
                else:
                    g.create_dataset(c, data=["" if v is None else v for v in values],
                                     dtype=h5py.string_dtype())

    # Each file is replaced whole; a kill between the two leaves each true (the CSV
    # may then hold rows the HDF5 file has only through its journal).
    text = csv_text(rows, layout["columns"])
    replace_atomically(csv_path, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    replace_atomically(h5_path, write_h5)


def _read_snapshot(path: Path) -> tuple[list[dict], dict]:
    import h5py

    from ..errors import ResultError

    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ResultError(f"{path}: not a vibrofeed sweep summary")
        meta = {k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in f.attrs.items()}
        g = f["jobs"]
        cols = [str(c) for c in g.attrs["columns"]]
        meta["parameters"] = [str(c) for c in g.attrs["parameters"]]
        data = {}
        for c in cols:
            ds = g[c]
            if h5py.check_string_dtype(ds.dtype) is not None:
                data[c] = [s or None for s in ds.asstr()[()]]
            elif ds.dtype.kind == "i":
                data[c] = [int(v) for v in ds[()]]
            else:
                data[c] = to_json(ds[()])  # NaN: None
    lengths = {len(data[c]) for c in cols}
    if len(lengths) > 1:  # a torn or edited file: rows cut short would pass for the sweep
        raise ValueError(f"its columns hold {min(lengths)} to {max(lengths)} rows")
    n = lengths.pop() if lengths else 0
    return [{c: data[c][i] for c in cols} for i in range(n)], meta


# ----------------------------------------------------------------- the journal
def _line(row: dict) -> bytes:
    """A plain row (:func:`~vibrofeed.values.to_json`) as one journal line: ASCII JSON,
    so no newline inside."""
    return (json.dumps(row, allow_nan=False, separators=(",", ":")) + "\n").encode()


def _read_journal(path: Path) -> tuple[str | None, list[dict]]:
    """(generation, rows) of a journal; (None, []) when there is none or its header is torn.

    Only the last line can be torn (it lacks its newline): it is dropped. A
    complete line that is not a row is damage, a ResultError naming the file."""
    from ..errors import ResultError

    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None, []
    lines = data.split(b"\n")[:-1]  # what follows the last newline was never completed
    if not lines:
        return None, []
    try:
        head = json.loads(lines[0])
        rows = [json.loads(line) for line in lines[1:]]
    except ValueError:
        raise ResultError(f"{path}: a damaged line (not JSON); not a journal vibrofeed wrote") from None
    if (not isinstance(head, dict) or head.get("format") != JOURNAL_FORMAT
            or not all(isinstance(r, dict) and "job" in r for r in rows)):
        raise ResultError(f"{path}: not a vibrofeed sweep journal")
    return head.get("generation"), rows


def _append(fd: int, data: bytes, size: int) -> None:
    """Append ``data`` (whole lines) in one write, then flush it to disk. A short write
    (a full disk) is undone, so the journal never holds a torn line it goes on after."""
    try:
        written = os.write(fd, data)
        if written != len(data):
            raise OSError(errno.ENOSPC, f"journal: {written} of {len(data)} bytes written")
        os.fdatasync(fd)  # the line's data and the file's size: enough to read it back
    except BaseException:
        os.ftruncate(fd, size)
        raise


# ----------------------------------------------------------------- reading and writing a table
def write(folder, rows: list[dict], parameters: list[str], meta: dict, stem: str = STEM) -> None:
    """Make ``folder``'s table ``stem`` exactly ``rows``: a new snapshot, then no journal.

    ``meta``: attributes of the HDF5 file's root (fingerprint, deck, jobs planned...)."""
    Ledger(folder, parameters, meta, rows=rows, stem=stem).close()


def read(folder, stem: str = STEM) -> tuple[list[dict], dict]:
    """(rows sorted by job, root attributes) of ``folder``'s table ``stem``: the HDF5
    snapshot and the journal lines that follow it; ([], {}) when there is no snapshot.

    Each row holds every column; missing values are None. ``meta`` holds
    ``columns``, ``parameters`` and ``metrics`` besides the root attributes.
    A damaged file is a :class:`~vibrofeed.errors.ResultError` naming it."""
    from ..errors import ResultError

    h5_path, _, journal_path = paths(folder, stem)
    # The journal first: should a compaction run between the two reads, the snapshot
    # read then holds every row of the journal read (of another generation: skipped).
    generation, journal = _read_journal(journal_path)
    if not h5_path.is_file():
        return [], {}
    try:
        rows, meta = _read_snapshot(h5_path)
        follows = meta.pop("generation", None)
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:  # truncated, overwritten...
        from ..results.reader import _reason

        if isinstance(exc, UnicodeDecodeError):
            why = "text that is not ASCII"
        elif isinstance(exc, (TypeError, IndexError)):
            why = "a layout that is not a sweep summary's"
        elif isinstance(exc, (OSError, KeyError)):  # HDF5's words
            why = _reason(exc)
        else:  # (the snapshot's own checks)
            why = str(exc).splitlines()[0]
        raise ResultError(f"{h5_path}: not a readable sweep summary ({why}): damaged, or not written "
                          "by vibrofeed") from None
    if generation is not None and generation == follows:
        rows += journal  # else the journal is older than the snapshot, which holds its rows
    return _merged(rows, meta)


def _merged(rows: list[dict], meta: dict) -> tuple[list[dict], dict]:
    """One row per job (the last given wins), sorted, every value typed as the snapshot stores it."""
    by_job = {row["job"]: row for row in rows}
    rows = sorted(by_job.values(), key=lambda r: r["job"])
    layout = _layout(rows, meta.get("parameters", []))
    data = {c: _typed([row.get(c) for row in rows])[1] for c in layout["columns"]}
    meta.update(layout)
    return [{c: data[c][i] for c in layout["columns"]} for i in range(len(rows))], meta


class Ledger:
    """A table kept O(1) per row: each :meth:`add` is one journal line; the snapshot is
    rewritten (:meth:`compact`) only once the journal holds a quarter of the rows (and at
    least ``MIN_PENDING``), or ``INTERVAL`` s have passed, and on :meth:`close`.

    A new ledger starts with a snapshot of exactly ``rows`` (what a resumed sweep
    keeps; the rows no longer true are dropped), so it never appends to a journal
    an earlier writer may have left torn. One writer per table (the sweep's lock)."""

    MIN_PENDING = 64
    SHARE = 4  # snapshot once the journal holds 1/SHARE of the rows: amortised O(1) per add
    # A time bound keeps summary.csv recent for its readers; stretched to COST_RATIO times
    # the last compaction's duration so that compacting never takes more than 1/COST_RATIO.
    INTERVAL, COST_RATIO = 60.0, 50.0

    def __init__(self, folder, parameters: list[str], meta: dict, *, rows=(), stem: str = STEM):
        self.folder, self.parameters, self.meta, self.stem = Path(folder), parameters, meta, stem
        # plain values (numpy scalars as numbers, NaN as None): the journal and the
        # snapshot then store a row alike
        self.rows = {row["job"]: to_json(row) for row in rows}
        self.journal = paths(folder, stem)[2]
        self.pending = 0  # rows added since the last snapshot
        self.compactions = 0
        self._fd: int | None = None
        self._size = 0
        self._generation = ""
        self._next_due = 0.0
        self.compact()

    def add(self, row: dict) -> None:
        """Record ``row`` (a later row for the same job replaces it): on disk on return."""
        row = to_json(row)
        data = _line(row)
        if self._fd is None:
            self._open_journal()
        _append(self._fd, data, self._size)
        self._size += len(data)
        self.rows[row["job"]] = row
        self.pending += 1
        if self._due():
            self.compact()

    def _open_journal(self) -> None:
        """A new journal whose header (the snapshot's generation) is on disk before any row."""
        head = _line({"format": JOURNAL_FORMAT, "generation": self._generation})
        # O_TRUNC: a journal still there is of an older generation (an unlink that failed)
        fd = os.open(self.journal, os.O_WRONLY | os.O_CREAT | os.O_TRUNC | os.O_APPEND, 0o644)
        try:
            _append(fd, head, 0)
        except BaseException:
            os.close(fd)
            raise
        _fsync_dir(self.folder)  # its name too must survive a power cut
        self._fd, self._size = fd, len(head)

    def _due(self) -> bool:
        return (self.pending >= max(self.MIN_PENDING, len(self.rows) // self.SHARE)
                or time.monotonic() >= self._next_due)

    def compact(self) -> None:
        """Rewrite the snapshot with every row, then drop the journal.

        Should the snapshot fail (a full disk), nothing has changed: the journal,
        still open, goes on following the previous snapshot."""
        started = time.monotonic()
        generation = uuid.uuid4().hex
        _write_snapshot(self.folder, list(self.rows.values()), self.parameters, self.meta, self.stem,
                        generation)
        self._close_journal()
        self._generation, self.pending = generation, 0
        self.journal.unlink(missing_ok=True)  # after the snapshot: see the module's docstring
        self.compactions += 1
        now = time.monotonic()
        self._next_due = now + max(self.INTERVAL, self.COST_RATIO * (now - started))

    def close(self) -> None:
        """A last snapshot when rows are pending; the table is then its snapshot alone."""
        if self.pending:
            self.compact()
        self._close_journal()

    def _close_journal(self) -> None:
        if self._fd is not None:
            os.close(self._fd)
            self._fd = None
