"""Runs that end honestly (issue 19, faults and signals): SIGTERM as Ctrl-C in every
command, abandoned scratch folders, a `.part` never `complete`, a worker that stops
answering, a full disk, a run that loses parts.

Short single-part runs (one part, ~20k frames/s of wall time) and a tiny bulk run."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import pytest

from helpers import frames_now, vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

LONG = ["-p", "t_end=20", "-p", "output_dt=2e-5"]


def children(pid: int) -> list[int]:
    return [int(c) for task in Path(f"/proc/{pid}/task").iterdir()
            for c in (task / "children").read_text().split()]


def start(args, cwd: Path, env=None) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "vibrofeed.cli", *map(str, args)], cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, **(env or {})})


def wait_until(ready, proc, timeout=120.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        got = ready()
        if got:
            return got
        assert proc.poll() is None, proc.communicate()
        time.sleep(0.05)
    raise AssertionError(f"not ready after {timeout} s")


def status(path: Path) -> tuple[str, str]:
    with h5py.File(path, "r") as f:
        run = f["parameters/run"].attrs
        return str(run["status"]), str(run.get("message", ""))


def scratch_folders(folder: Path) -> list[Path]:
    return list(folder.rglob(".vibrofeed-*"))


@pytest.mark.parametrize("command", ["run", "demo"])
def test_sigterm_ends_a_run_as_ctrl_c_does(tmp_path, command):
    if command == "run":
        proc = start(["run", "single_part", "-q", "-o", "t.h5", *LONG], tmp_path)
        part = tmp_path / "t.h5.part"
    else:
        proc = start(["demo", "-q", "-o", ".", "--no-pictures", "-p", "t_end=5"], tmp_path)
        part = tmp_path / "feeder_line.h5.part"
    seen = wait_until(lambda: frames_now(part) >= 3 and frames_now(part), proc)
    proc.send_signal(signal.SIGTERM)  # what timeout, Slurm and preemption send
    _, err = proc.communicate(timeout=60)
    # one line: why, and what the run left (its frames, marked interrupted)
    assert proc.returncode == 143 and len(err.strip().splitlines()) == 1
    assert err.startswith("vibrofeed: error: terminated (SIGTERM); the ")
    assert err.strip().endswith(f"frames written before the interruption are kept in {part} "
                                "(status: interrupted)")
    assert not part.with_suffix("").exists() and not scratch_folders(tmp_path)
    assert status(part) == ("interrupted", "terminated by SIGTERM")
    with Result(part, allow_incomplete=True) as r:
        assert r.n_frames >= seen
    assert check_file(part, allow_incomplete=True).ok and not check_file(part).ok


def test_sigterm_ends_a_sweep_and_a_rerun_finishes_it(tmp_path):
    spec = tmp_path / "s.toml"
    spec.write_text('deck = "single_part"\n[fixed]\nt_end = 1.2\noutput_dt = 1e-3\n'
                    "[grid]\nphase = [0, 90]\n")
    proc = start(["sweep", spec, "-o", "out", "-j", "2", "-q"], tmp_path)
    jobs = tmp_path / "out" / "jobs"
    wait_until(lambda: any(frames_now(p) > 10 for p in jobs.glob("*.h5.part")), proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and err.strip().endswith("vibrofeed: error: terminated (SIGTERM)")
    assert not scratch_folders(tmp_path)
    parts = list(jobs.glob("*.h5.part"))  # (each beside its log, OUT.log.part)
    assert parts and all(status(p)[0] == "interrupted" for p in parts)
    from vibrofeed.sweep import summary as S

    assert all(row["status"] == S.DONE for row in S.read(tmp_path / "out")[0])  # nothing failed
    again = vibrofeed("sweep", spec, "-o", tmp_path / "out", "-q", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert [r["status"] for r in S.read(tmp_path / "out")[0]] == [S.DONE, S.DONE]
    assert not list(jobs.glob("*.part")) and not scratch_folders(tmp_path)


def test_sigterm_ends_a_validation_and_starts_no_further_run(tmp_path):
    proc = start(["validate", "hop_period", "-o", "v", "-j", "1"], tmp_path)
    out = tmp_path / "v"
    wait_until(lambda: any(frames_now(p) > 10 for p in out.rglob("*.h5.part")), proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143 and err.strip().endswith("vibrofeed: error: terminated (SIGTERM)")
    assert not scratch_folders(tmp_path)
    parts = list(out.rglob("*.h5.part"))  # (beside its log, OUT.log.part)
    assert len(parts) == 1 and status(parts[0])[0] == "interrupted"
    assert not list(out.rglob("*.h5"))  # the queued runs never started


def test_sigkill_leftovers_are_removed_by_a_later_run(tmp_path):
    proc = start(["run", "single_part", "-q", "-o", "k.h5", *LONG], tmp_path)
    part = tmp_path / "k.h5.part"
    wait_until(lambda: frames_now(part) >= 20, proc)
    (worker,) = children(proc.pid)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    end = time.monotonic() + 20  # the worker is sent SIGTERM as its parent dies
    while Path(f"/proc/{worker}").exists() and time.monotonic() < end:
        time.sleep(0.05)
    # Nobody removed the scratch folder; the worker recorded its own end.
    (left,) = scratch_folders(tmp_path)
    assert status(part) == ("interrupted", "the engine worker was sent SIGTERM")
    # A live run's scratch folder in the same place is not touched.
    live = start(["run", "single_part", "-q", "-o", "live.h5", *LONG], tmp_path)
    try:
        wait_until(lambda: frames_now(tmp_path / "live.h5.part") > 0, live)
        (mine,) = [p for p in scratch_folders(tmp_path) if p != left]
        done = vibrofeed("run", "single_part", "-q", "-o", "next.h5", "-p", "t_end=0.01", cwd=tmp_path)
        assert done.returncode == 0, done.stderr
        assert scratch_folders(tmp_path) == [mine]
    finally:
        live.kill()
        live.wait()


def test_a_part_file_never_says_complete(tmp_path):
    """vibrofeed killed the moment the engine is done: the .part is not 'complete'."""
    script = (
        "import os, signal, sys\n"
        "from vibrofeed.decks import Deck\n"
        "from vibrofeed.engine.runner import run_deck\n"
        "def on_event(e):\n"
        "    if e['event'] == 'done':\n"
        "        os.kill(os.getpid(), signal.SIGKILL)\n"
        "run_deck(Deck.find('single_part'), {'t_end': '0.02'}, sys.argv[1], on_event=on_event)\n")
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / "d.h5")], capture_output=True)
    assert proc.returncode == -signal.SIGKILL
    part = tmp_path / "d.h5.part"
    assert status(part)[0] == "running" and not (tmp_path / "d.h5").exists()
    assert not check_file(part).ok and check_file(part, allow_incomplete=True).ok
    # A .part made to say 'complete' (an older vibrofeed, a hand edit) fails `check` too.
    with h5py.File(part, "r+") as f:
        f["parameters/run"].attrs["status"] = "complete"
    problems = [str(p) for p in check_file(part).problems]
    assert any("a .part file says 'complete'" in p for p in problems), problems
    assert vibrofeed("check", part).returncode == 1


def test_a_worker_that_stops_answering_is_stopped_and_its_frames_kept(tmp_path):
    proc = start(["run", "single_part", "-q", "-o", "h.h5", *LONG], tmp_path,
                 env={"VIBROFEED_STALL_SECONDS": "3"})
    part = tmp_path / "h.h5.part"
    wait_until(lambda: frames_now(part) >= 20, proc)
    (worker,) = children(proc.pid)
    os.kill(worker, signal.SIGSTOP)
    stopped = time.monotonic()
    _, err = proc.communicate(timeout=60)
    assert time.monotonic() - stopped < 30  # 3 s of silence, then at most 10 s to end it
    lines = err.strip().splitlines()
    assert proc.returncode == 1 and "the engine worker has not answered for 3 s" in lines[0]
    assert not Path(f"/proc/{worker}").exists() or "zombie" in Path(f"/proc/{worker}/status").read_text()
    assert status(part)[0] == "failed" and not scratch_folders(tmp_path)
    with Result(part, allow_incomplete=True) as r:
        assert r.n_frames >= 20


def test_a_hung_mpi_rank_is_found_by_the_steps_that_stop(tmp_path):
    """Rank 1 stopped: rank 0 still answers, waiting for it, but takes no step."""
    proc = start(["run", "single_part", "-n", "2", "-q", "-o", "r.h5", *LONG], tmp_path,
                 env={"VIBROFEED_STALL_SECONDS": "3"})
    part = tmp_path / "r.h5.part"
    wait_until(lambda: frames_now(part) >= 5, proc)
    (mpirun,) = children(proc.pid)
    ranks = children(mpirun)
    (rank1,) = [r for r in ranks if b"OMPI_COMM_WORLD_RANK=1\0" in Path(f"/proc/{r}/environ").read_bytes()]
    os.kill(rank1, signal.SIGSTOP)
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 1 and "the engine took no step for" in err and "hung MPI rank" in err
    assert status(part)[0] == "failed"
    end = time.monotonic() + 20  # no rank is left behind, stopped or running
    while any(Path(f"/proc/{r}").exists() for r in ranks) and time.monotonic() < end:
        time.sleep(0.1)
    assert not any(Path(f"/proc/{r}").exists() for r in ranks)



def test_a_full_disk_keeps_what_was_written_and_says_so(small_disk):
    proc = vibrofeed("run", "single_part", "-q", "-o", small_disk / "f.h5", *LONG, timeout=300)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 1 and lines[0].startswith(f"vibrofeed: error: no space left on {small_disk}")
    assert all("HDF5" not in line and "Traceback" not in line for line in lines)
    part = small_disk / "f.h5.part"
    assert part.exists() and not scratch_folders(small_disk)
    assert f"{part}" in lines[0] and len(lines) == 1  # the error and where the frames are, one line
    assert status(part)[0] == "failed"  # it opens (the worker closed it whole) and says so


def test_a_run_that_loses_parts_has_failed(tmp_path):
    """Parts deleted mid-run (no outlet event): the run fails, names the count, keeps its frames.
    (A density of 1e30 kg/m^3 lost every part once; it is refused before running now.)"""
    from vibrofeed.decks import Deck
    from vibrofeed.engine.runner import run_deck
    from vibrofeed.errors import RunError

    sink = ["region vf_sink block INF INF INF INF INF INF units box", "delete_atoms region vf_sink"]
    schedule = [{"steps": 500}, {"steps": 500, "commands": sink}, {"steps": 500}]
    with pytest.raises(RunError) as err:
        run_deck(Deck.find("bulk_feeder"), {"n_parts": "20", "t_end": "0.02"}, tmp_path / "l.h5",
                 schedule=schedule)
    message = str(err.value)
    assert "20 of 20 parts were lost" in message and "mass balance does not close" in message
    assert not (tmp_path / "l.h5").exists()
    assert status(tmp_path / "l.h5.part") == ("failed", message)
