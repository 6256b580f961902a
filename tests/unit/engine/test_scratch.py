"""Runs' scratch folders (engine/scratch.py): a later run removes the ones whose owner is gone."""

import os
import socket
import subprocess
import sys

from vibrofeed.engine import scratch


def dead_pid() -> int:
    proc = subprocess.Popen([sys.executable, "-c", "pass"])
    proc.wait()
    return proc.pid


def test_only_folders_whose_owner_is_gone_are_removed(tmp_path):
    mine = scratch.make(tmp_path)
    host = socket.gethostname()
    owner = (mine / scratch.OWNER).read_text().split()
    assert owner[:2] == [host, str(os.getpid())]

    def folder(name, text=None, age=0.0):
        path = tmp_path / (scratch.PREFIX + name)
        path.mkdir()
        if text is not None:
            (path / scratch.OWNER).write_text(text)
        if age:
            os.utime(path, (path.stat().st_mtime - age,) * 2)
        return path

    dead = folder("dead", f"{host} {dead_pid()} 1\n")
    reused_pid = folder("reused", f"{host} {os.getpid()} 1\n")  # this pid, another start time
    elsewhere = folder("other-host", f"{host}-not {dead_pid()} 1\n")
    fresh = folder("being-made")  # no owner file yet
    old = folder("old-vibrofeed", age=2 * scratch.UNOWNED_AGE)
    unrelated = tmp_path / "keep"
    unrelated.mkdir()

    gone = scratch.remove_abandoned(tmp_path)
    assert sorted(gone) == sorted([dead, reused_pid, old])
    assert all(p.is_dir() for p in (mine, elsewhere, fresh, unrelated))
    assert not any(p.exists() for p in gone)
