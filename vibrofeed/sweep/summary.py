"""The sweep's summary: one row per finished job, in ``summary.h5`` and ``summary.csv``.

A row is written only once its job has finished (its result renamed into
place and analysed, or its failure known), and each file is replaced whole
(written to a temporary file in the same folder, flushed to disk, then
``os.replace``d over the old one): a reader, or a sweep killed at any instant,
sees the old summary or the new one, never a mixture, so every row listed is
true of its job. Layout in FORMAT.md, "Sweep summary".

Columns: ``job``, ``replicate``, ``seed``, the parameters the sweep file names
(resolved values, deck defaults applied), ``status`` (``done``, ``failed``),
``error`` (empty when done), ``file`` (relative to the folder; for a failed
run, the partial ``.h5.part`` when it left frames, else empty), ``run_id``,
``wall_s`` (seconds the job took), then the metrics (:mod:`.metrics`).
Missing values are NaN in HDF5 and empty cells in the CSV; rows read back
hold None for them.
"""

from __future__ import annotations

import csv
import io
import math
import os
import tempfile
from pathlib import Path

from ..values import to_json

FORMAT = "vibrofeed-sweep-summary"
FORMAT_VERSION = (1, 0)
H5_NAME, CSV_NAME = "summary.h5", "summary.csv"
HEAD = ("job", "replicate", "seed")
STATE = ("status", "error", "file", "run_id", "wall_s")
DONE, FAILED = "done", "failed"


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


def replace_atomically(path: Path, write) -> None:
    """``write(tmp_path)`` then fsync and rename over ``path``: readers see the
    old file or the new one, never a part of either."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
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


def write(folder, rows: list[dict], parameters: list[str], meta: dict) -> None:
    """Replace ``folder``'s summary.h5 and summary.csv by ``rows`` (sorted by job).

    ``meta``: attributes of the HDF5 file's root (fingerprint, deck, jobs planned...)."""
    folder = Path(folder)
    rows = sorted(rows, key=lambda r: r["job"])
    cols = columns(rows, parameters)
    metrics = [c for c in cols if c not in HEAD and c not in STATE and c not in parameters]

    def write_h5(tmp: Path) -> None:
        import h5py
        import numpy as np

        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["format_version"] = np.array(FORMAT_VERSION, dtype=np.int32)
            for key, value in meta.items():
                f.attrs[key] = value
            g = f.create_group("jobs")
            g.attrs["columns"] = cols
            g.attrs["parameters"] = [p for p in cols if p in parameters]
            g.attrs["metrics"] = metrics
            for c in cols:
                values = [row.get(c) for row in rows]
                kind = _kind(values)
                if kind == "int":
                    g.create_dataset(c, data=np.array(values, dtype=np.int64))
                elif kind == "float":
                    g.create_dataset(c, data=np.array([math.nan if _missing(v) else float(v)
                                                       for v in values], dtype=np.float64))
                else:
                    g.create_dataset(c, data=["" if _missing(v) else str(v) for v in values],
                                     dtype=h5py.string_dtype())

    # Each file is replaced whole; a kill between the two leaves each true (the CSV
    # may then hold one row more than the HDF5 file, which a rerun reads).
    text = csv_text(rows, cols)
    replace_atomically(folder / CSV_NAME, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    replace_atomically(folder / H5_NAME, write_h5)


def read(folder) -> tuple[list[dict], dict]:
    """(rows, root attributes) of ``folder``'s summary.h5; ([], {}) when there is none.

    Each row holds every column; missing values are None. A damaged file is a
    :class:`~vibrofeed.errors.ResultError` naming it."""
    from ..errors import ResultError

    path = Path(folder) / H5_NAME
    if not path.is_file():
        return [], {}
    try:
        return _read(path)
    except (OSError, KeyError, ValueError, TypeError, IndexError) as exc:  # truncated, overwritten...
        raise ResultError(f"{path}: not a readable sweep summary ({type(exc).__name__}: "
                          f"{str(exc).splitlines()[0] if str(exc) else 'damaged'})") from None


def _read(path: Path) -> tuple[list[dict], dict]:
    import h5py

    from ..errors import ResultError

    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ResultError(f"{path}: not a vibrofeed sweep summary")
        meta = {k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in f.attrs.items()}
        g = f["jobs"]
        cols = [str(c) for c in g.attrs["columns"]]
        meta["columns"] = cols
        meta["parameters"] = [str(c) for c in g.attrs["parameters"]]
        meta["metrics"] = [str(c) for c in g.attrs["metrics"]]
        data = {}
        for c in cols:
            ds = g[c]
            if h5py.check_string_dtype(ds.dtype) is not None:
                data[c] = [s or None for s in ds.asstr()[()]]
            elif ds.dtype.kind == "i":
                data[c] = [int(v) for v in ds[()]]
            else:
                data[c] = to_json(ds[()])  # NaN: None
    n = len(data[cols[0]]) if cols else 0
    return [{c: data[c][i] for c in cols} for i in range(n)], meta
