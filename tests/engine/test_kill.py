"""A run killed with SIGKILL or interrupted leaves a file that opens and holds its frames."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from helpers import frames_now
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result


def children(pid: int) -> list[int]:
    out = []
    for task in Path(f"/proc/{pid}/task").iterdir():
        text = (task / "children").read_text().split()
        out += [int(c) for c in text]
    return out


def start_run(tmp_path):
    out = tmp_path / "k.h5"
    proc = subprocess.Popen([sys.executable, "-m", "vibrofeed.cli", "run", "single_part", "-q",
                             "-o", str(out), "-p", "t_end=20", "-p", "output_dt=2e-5"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    return proc, out, tmp_path / "k.h5.part"


def wait_for_frames(part: Path, n: int, proc, timeout=60.0) -> int:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        k = frames_now(part)
        if k >= n:
            return k
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.05)
    raise AssertionError(f"fewer than {n} frames after {timeout} s")


def assert_valid_partial(part: Path, at_least: int, status: str):
    with Result(part, allow_incomplete=True) as r:
        assert r.status == status
        assert r.n_frames >= at_least
        assert (r.ids[:, 0] == 1).all()
        assert (r.step[1:] > r.step[:-1]).all()
    report = check_file(part, allow_incomplete=True)
    assert report.ok, report.problems


@pytest.mark.parametrize("frames", [3, 150, 700])
def test_sigkill_of_the_engine_worker(tmp_path, frames):
    proc, out, part = start_run(tmp_path)
    try:
        seen = wait_for_frames(part, frames, proc)
        (worker,) = children(proc.pid)
        os.kill(worker, signal.SIGKILL)  # the process that writes the file
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode != 0 and not out.exists()
    assert "killed by signal 9" in proc.stderr.read().decode()
    # vibrofeed survived its engine and recorded how the run ended.
    assert_valid_partial(part, seen, "failed")


def test_sigkill_of_vibrofeed_itself(tmp_path):
    proc, out, part = start_run(tmp_path)
    seen = wait_for_frames(part, 50, proc)
    worker = children(proc.pid)[0]
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    # The worker is told to stop when its parent dies (no orphaned engine).
    end = time.monotonic() + 20
    while Path(f"/proc/{worker}").exists() and time.monotonic() < end:
        time.sleep(0.05)
    assert not Path(f"/proc/{worker}").exists() or \
        Path(f"/proc/{worker}/status").read_text().find("zombie") >= 0
    # The worker, sent SIGTERM as its parent died, flushed its frames and recorded the end.
    assert_valid_partial(part, seen, "interrupted")


def test_ctrl_c_marks_the_file_interrupted_and_exits_130(tmp_path):
    proc, out, part = start_run(tmp_path)
    try:
        seen = wait_for_frames(part, 20, proc)
        proc.send_signal(signal.SIGINT)  # what Ctrl-C sends
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    err = proc.stderr.read().decode()
    # one line: why, and what the run left (its frames, marked interrupted)
    assert proc.returncode == 130 and len(err.strip().splitlines()) == 1
    assert err.startswith("vibrofeed: error: interrupted; the ")
    assert err.strip().endswith(f"kept in {part} (status: interrupted)")
    assert not out.exists() and not list(tmp_path.glob(".vibrofeed-*"))  # scratch folder removed
    assert_valid_partial(part, seen, "interrupted")


def test_a_killed_rerun_keeps_the_finished_result(tmp_path):
    # A complete result first, then a rerun into the same name (another run id) killed midway.
    done = subprocess.run([sys.executable, "-m", "vibrofeed.cli", "run", "single_part", "-q",
                           "-o", str(tmp_path / "k.h5"), "-p", "t_end=0.002",
                           "-p", "output_dt=2e-4"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    before = (tmp_path / "k.h5").read_bytes()
    proc, out, part = start_run(tmp_path)
    seen = wait_for_frames(part, 20, proc)
    worker = children(proc.pid)[0]
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    end = time.monotonic() + 20  # the worker, sent SIGTERM, marks its file and ends
    while Path(f"/proc/{worker}").exists() and time.monotonic() < end and \
            "zombie" not in Path(f"/proc/{worker}/status").read_text():
        time.sleep(0.05)
    assert out.read_bytes() == before  # the finished file, untouched
    assert check_file(out).ok
    assert_valid_partial(part, seen, "interrupted")
