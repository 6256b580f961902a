"""A run's scratch folder (``.vibrofeed-*`` next to its output), and the ones killed runs left.

The runner removes its folder when the run ends, however it ends, except when
vibrofeed itself is killed (SIGKILL, a node's crash). Each folder names its
owner in ``owner`` (host, pid, process start time), so a later run in the same
place removes the folders whose owner is gone, and only those: a live run's
folder, or one made on another host of a shared file system, stays.
"""

from __future__ import annotations

import os
import shutil
import socket
import tempfile
import time
from pathlib import Path

PREFIX = ".vibrofeed-"
OWNER = "owner"
OUTPUTS = "outputs"  # the run's OUT.h5.part and OUT.log.part, a line each
# A folder without an owner file (being created, or left by an older vibrofeed)
# counts as left behind once it is this old.
UNOWNED_AGE = 600.0


def _started(pid: int) -> str | None:
    """The start time of process ``pid`` (clock ticks after boot), None if there is none."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    return text.rsplit(")", 1)[1].split()[19]  # field 22; the name before ")" may hold spaces


def make(folder: Path) -> Path:
    """A new scratch folder in ``folder``, owned by this process."""
    tmp = Path(tempfile.mkdtemp(prefix=PREFIX, dir=folder))
    try:
        (tmp / OWNER).write_text(f"{socket.gethostname()} {os.getpid()} {_started(os.getpid())}\n")
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return tmp


def _abandoned(tmp: Path) -> bool:
    try:
        host, pid, started = (tmp / OWNER).read_text().split()
    except (OSError, ValueError):
        try:
            return time.time() - tmp.stat().st_mtime > UNOWNED_AGE
        except OSError:
            return False
    if host != socket.gethostname() or not pid.isdigit():
        return False
    return _started(int(pid)) != started


def name_outputs(tmp: Path, part: Path, log_part: Path) -> None:
    """Record in scratch folder ``tmp`` the run's unfinished result and log (``OUT.h5.part``,
    ``OUT.log.part``), so that whoever removes the folder after a kill knows them."""
    (tmp / OUTPUTS).write_text(f"{part}\n{log_part}\n")


def remove_abandoned(folder: Path) -> list[Path]:
    """Remove the scratch folders in ``folder`` whose owner process is gone; those removed.
    A killed run's log (``OUT.log.part``) goes with its folder when the run left no frames
    (no ``OUT.h5.part``): it belongs to nothing kept; beside a ``.part`` of frames it stays."""
    gone = []
    for tmp in folder.glob(PREFIX + "*"):
        if tmp.is_dir() and _abandoned(tmp):
            remove(tmp)
            gone.append(tmp)
    return gone


def remove(tmp: Path) -> None:
    """Remove a killed run's scratch folder ``tmp``, and its log when it left no frames
    (:func:`remove_abandoned`)."""
    try:
        part, log_part = (tmp / OUTPUTS).read_text().split("\n")[:2]
    except (OSError, ValueError):
        part = log_part = ""
    if part and log_part and not Path(part).exists():
        Path(log_part).unlink(missing_ok=True)
    shutil.rmtree(tmp, ignore_errors=True)
