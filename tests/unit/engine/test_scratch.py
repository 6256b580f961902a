"""Runs' scratch folders (engine/scratch.py): a later run removes the ones whose owner is gone."""

import os
import shutil
import socket
import subprocess
import sys
import types
from pathlib import Path

import pytest

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


def test_a_process_start_is_field_22_of_its_stat(tmp_path):
    """proc(5): starttime is the 22nd field; the name (field 2, in parentheses) may hold
    spaces and parentheses, so fields are counted after its last ')'."""
    fields = Path(f"/proc/{os.getpid()}/stat").read_text().split()
    assert " " not in fields[1] and scratch._started(os.getpid()) == fields[21]
    odd = tmp_path / "a) b c"  # the process name: "(a) b c)", two more words in a naive split
    odd.symlink_to(shutil.which("sleep"))
    proc = subprocess.Popen([str(odd), "30"])
    try:
        text = Path(f"/proc/{proc.pid}/stat").read_text()
        assert text.split()[1:4] == ["(a)", "b", "c)"]
        assert scratch._started(proc.pid) == text.split()[23]
    finally:
        proc.kill()
        proc.wait()
    assert scratch._started(proc.pid) is None


@pytest.mark.parametrize("vanished", [False, True])
def test_a_folder_that_cannot_be_owned_is_not_left(tmp_path, monkeypatch, vanished):
    """The owner file cannot be written (no host name): the folder is removed and make raises
    why. The cleanup never hides that reason, even when the folder vanished (removed by
    someone else) before it."""
    def no_host():
        if vanished:
            for tmp in tmp_path.glob(scratch.PREFIX + "*"):
                shutil.rmtree(tmp)
        raise OSError("no host name")

    monkeypatch.setattr(scratch.socket, "gethostname", no_host)
    with pytest.raises(OSError, match="no host name"):
        scratch.make(tmp_path)
    assert list(tmp_path.iterdir()) == []


def test_an_unowned_folder_is_left_behind_only_past_its_age(tmp_path, monkeypatch):
    folder = tmp_path / (scratch.PREFIX + "x")
    folder.mkdir()
    (folder / scratch.OWNER).write_text("only-two words\n")  # malformed: as without an owner
    mtime = 1_000_000_000
    os.utime(folder, ns=(mtime * 10**9, mtime * 10**9))
    clock = types.SimpleNamespace(time=lambda: mtime + scratch.UNOWNED_AGE)
    monkeypatch.setattr(scratch, "time", clock)
    assert scratch.UNOWNED_AGE == 600.0
    assert scratch._abandoned(folder) is False        # exactly the age: not yet
    clock.time = lambda: mtime + scratch.UNOWNED_AGE + 0.5
    assert scratch._abandoned(folder) is True
    assert scratch._abandoned(tmp_path / "vanished") is False  # neither owner nor folder


def test_an_owner_that_names_no_process_of_this_host_is_kept(tmp_path):
    folder = tmp_path / (scratch.PREFIX + "x")
    folder.mkdir()
    (folder / scratch.OWNER).write_text(f"{socket.gethostname()} pid? 1\n")
    assert scratch._abandoned(folder) is False


def test_only_folders_are_removed(tmp_path):
    note = tmp_path / (scratch.PREFIX + "note")
    note.write_text("x")
    os.utime(note, (1, 1))  # older than any scratch folder's age
    assert scratch.remove_abandoned(tmp_path) == [] and note.exists()


def test_two_runs_sweeping_the_same_place_at_once_do_not_fail(tmp_path, monkeypatch):
    """Another run starting beside this one may remove an abandoned folder first: this
    run's sweep goes on without an error and removes the rest."""
    host = socket.gethostname()
    left = []
    for name in ("a", "b"):
        path = tmp_path / (scratch.PREFIX + name)
        path.mkdir()
        (path / scratch.OWNER).write_text(f"{host} {dead_pid()} 1\n")
        left.append(path)
    judged = scratch._abandoned
    raced = []

    def other_run_first(tmp):
        abandoned = judged(tmp)
        if abandoned and not raced:  # the other run removes the first one between judge and remove
            shutil.rmtree(tmp)
            raced.append(tmp)
        return abandoned

    monkeypatch.setattr(scratch, "_abandoned", other_run_first)
    gone = scratch.remove_abandoned(tmp_path)
    assert len(raced) == 1 and not any(p.exists() for p in left)
    second = next(p for p in left if p not in raced)
    assert second in gone


def test_a_killed_runs_log_goes_with_its_folder_only_when_it_left_no_frames(tmp_path):
    logs = {}
    for name, frames in (("bare", False), ("framed", True)):
        tmp = tmp_path / f"{scratch.PREFIX}{name}"
        tmp.mkdir()
        part, log_part = tmp_path / f"{name}.h5.part", tmp_path / f"{name}.log.part"
        log_part.write_text("LIGGGHTS log")
        if frames:
            part.write_bytes(b"frames")
        scratch.name_outputs(tmp, part, log_part)
        scratch.remove(tmp)
        assert not tmp.exists()
        logs[name] = log_part.exists()
    assert logs == {"bare": False, "framed": True}  # beside its frames the log stays
