"""The environment variables vibrofeed reads, each read here and checked.

A variable the documentation names, set to a value that means nothing (a rank limit of
``abc``, ``0`` or ``-1``, a stall time of ``nan``, a shim or a folder that does not exist,
``VIBROFEED_DEBUG=maybe``), is a :class:`~vibrofeed.errors.UsageError` naming it and its
value: ignored, it would leave the user believing it in effect. Set to nothing
(``VIBROFEED_MAX_RANKS= vibrofeed ...``) a variable is unset. The command line checks every
one of them before any command (:func:`check`), so a slip stops the command at once, not
a sweep's jobs one by one; the library reads them through the same functions.

============================  ==============================================================
``VIBROFEED_DEBUG``           ``1`` (also ``true``, ``yes``, ``on``): a user error keeps its
                              traceback; ``0`` (``false``, ``no``, ``off``): it does not
``VIBROFEED_MAX_RANKS``       the most MPI ranks a run may ask for here: a whole number >= 1
``VIBROFEED_STALL_SECONDS``   seconds of silence after which a worker counts as hung: > 0
``VIBROFEED_LONG_RUN_HOURS``  a run estimated to take longer than this says so before it
                              starts: hours > 0 (default 1)
``VIBROFEED_ABORT_SHIM``      the abort shim (a shared library): a file that exists
``VIBROFEED_DECKS``           the folder of the decks run by name: a folder that exists
``VIBROFEED_LIGGGHTS_LIB``    LIGGGHTS' shared library: a library name, or a path (with a
                              ``/``) to a file that exists
``VIBROFEED_TRIALS_DIR``      the measured trials' folder: a folder that exists
============================  ==============================================================
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from .errors import UsageError

DEBUG_ON = ("1", "true", "yes", "on")
DEBUG_OFF = ("0", "false", "no", "off")


def _get(name: str) -> str | None:
    """The variable's value, stripped; None when unset or set to nothing."""
    value = os.environ.get(name, "").strip()
    return value or None


def _refuse(name: str, value: str, why: str) -> UsageError:
    return UsageError(f"environment variable {name}={value} {why}; correct it or unset it")


def debug() -> bool:
    """Whether user errors keep their traceback (``VIBROFEED_DEBUG``)."""
    value = _get("VIBROFEED_DEBUG")
    if value is None or value.lower() in DEBUG_OFF:
        return False
    if value.lower() in DEBUG_ON:
        return True
    raise _refuse("VIBROFEED_DEBUG", value, "must be 1 (show tracebacks) or 0 (do not)")


def max_ranks() -> int | None:
    """The rank limit ``VIBROFEED_MAX_RANKS`` sets, or None."""
    value = _get("VIBROFEED_MAX_RANKS")
    if value is None:
        return None
    if not (value.isascii() and value.isdigit()) or int(value) < 1:
        raise _refuse("VIBROFEED_MAX_RANKS", value, "must be a whole number of MPI ranks, at least 1")
    return int(value)


def stall_seconds() -> float | None:
    """The watchdog's floor ``VIBROFEED_STALL_SECONDS`` sets [s], or None."""
    value = _get("VIBROFEED_STALL_SECONDS")
    if value is None:
        return None
    try:
        seconds = float(value) if value.isascii() else math.nan
    except ValueError:
        seconds = math.nan
    if not (math.isfinite(seconds) and seconds > 0):
        raise _refuse("VIBROFEED_STALL_SECONDS", value, "must be a number of seconds > 0")
    return seconds


def _positive(name: str, value: str, unit: str) -> float:
    """The number > 0 of ``unit`` variable ``name`` holds as ``value``; refused otherwise."""
    try:
        x = float(value) if value.isascii() else math.nan
    except ValueError:
        x = math.nan
    if not (math.isfinite(x) and x > 0):
        raise _refuse(name, value, f"must be a number of {unit} > 0")
    return x


def long_run_hours() -> float | None:
    """Hours of estimated run time above which a run says how long it will take
    (``VIBROFEED_LONG_RUN_HOURS``), or None (the runner's default, 1)."""
    value = _get("VIBROFEED_LONG_RUN_HOURS")
    return None if value is None else _positive("VIBROFEED_LONG_RUN_HOURS", value, "hours")


def _existing(name: str, kind: str) -> Path | None:
    value = _get(name)
    if value is None:
        return None
    path = Path(value).expanduser()
    if kind == "folder" and not path.is_dir():
        why = "is not a folder" if path.exists() else "names no folder: it does not exist"
        raise _refuse(name, value, why)
    if kind == "file" and not path.is_file():
        why = "is not a file" if path.exists() else "names no file: it does not exist"
        raise _refuse(name, value, why)
    return path


def abort_shim() -> Path | None:
    """The abort shim ``VIBROFEED_ABORT_SHIM`` names, or None."""
    return _existing("VIBROFEED_ABORT_SHIM", "file")


def decks_dir() -> Path | None:
    """The decks' folder ``VIBROFEED_DECKS`` names, or None."""
    return _existing("VIBROFEED_DECKS", "folder")


def trials_dir() -> Path | None:
    """The measured trials' folder ``VIBROFEED_TRIALS_DIR`` names, or None."""
    return _existing("VIBROFEED_TRIALS_DIR", "folder")


def liggghts_lib() -> str | None:
    """The LIGGGHTS library ``VIBROFEED_LIGGGHTS_LIB`` names (a name the loader searches
    for, or a path), or None. A path must lead to a file."""
    value = _get("VIBROFEED_LIGGGHTS_LIB")
    if value is not None and "/" in value:
        _existing("VIBROFEED_LIGGGHTS_LIB", "file")
    return value


READERS = {"VIBROFEED_DEBUG": debug, "VIBROFEED_MAX_RANKS": max_ranks,
           "VIBROFEED_STALL_SECONDS": stall_seconds, "VIBROFEED_LONG_RUN_HOURS": long_run_hours,
           "VIBROFEED_ABORT_SHIM": abort_shim,
           "VIBROFEED_DECKS": decks_dir, "VIBROFEED_LIGGGHTS_LIB": liggghts_lib,
           "VIBROFEED_TRIALS_DIR": trials_dir}


def check() -> None:
    """Every variable above checked: the first that means nothing is a UsageError."""
    for read in READERS.values():
        read()
