"""`vibrofeed run --target-error E` through LIGGGHTS: a small fed bulk feeder stops as soon
as its feed rate is measured to E, `vibrofeed feedrate` reports that precision on the result,
and the file says why the run ended; a target it cannot reach runs to t_end and says so; a
run killed while it checks leaves a valid file. (One rank: how the other ranks follow rank
0's decision is tests/unit/engine/test_target_error.py's; two ranks cost more than these
tests may on a shared machine.)"""

import json
import signal
import subprocess
import sys
import time

import pytest

from helpers import frames_now, vibrofeed
from vibrofeed.results.check import check_file
from vibrofeed.results.reader import Result

# 150 parts/s dropped on a 4 mm track (no pre-fill): the first exits come after ~0.2 s, and
# the regular inlet brings the rate's error below 0.15 about 0.15 s later. The validated
# floor of youngs (2e7 Pa, vibrofeed validate stiffness_independence) gives a longer step.
FED = ["-p", "n_parts=0", "-p", "inlet_rate=150", "-p", "track_length=0.004",
       "-p", "track_width=1.2e-3", "-p", "output_dt=0.005", "-p", "youngs=2e7", "-q"]


def feedrate(path) -> dict:
    return json.loads(vibrofeed("feedrate", path, "--json", "--no-model", check=True).stdout)


def test_a_loose_target_stops_the_run_early_and_the_result_reports_it(tmp_path):
    out, target, t_end = tmp_path / "fed.h5", 0.15, 0.6
    proc = vibrofeed("run", "bulk_feeder", "-o", out, "-p", f"t_end={t_end}", *FED,
                     "--target-error", target, check=True)
    report = check_file(out)
    assert report.ok, [str(p) for p in report.problems]
    with Result(out) as r:
        t_stop, reason, recorded = float(r.time[-1]), r.stop_reason, r.target_error
        step_dt = r.derived["output_every"] * r.derived["dt_used"]
    assert recorded == target and t_stop < t_end - 10 * step_dt     # ten frames short at least
    fr = feedrate(out)
    error = fr["parts_per_s_err"] / fr["parts_per_s"]
    assert error <= target
    assert reason == f"target error 0.15 reached: {error:.3g} at t = {t_stop:.4g} s"
    assert f"s simulated (stopped early: {reason}) in " in proc.stdout


def test_an_unreachable_target_runs_to_t_end_and_says_so(tmp_path):
    out, t_end = tmp_path / "fed.h5", 0.3
    proc = vibrofeed("run", "bulk_feeder", "-o", out, "-p", f"t_end={t_end}", *FED,
                     "--target-error", 1e-3, check=True)
    assert check_file(out).ok
    with Result(out) as r:
        t_last, reason = float(r.time[-1]), r.stop_reason
    assert t_last == pytest.approx(t_end, abs=0.005)                  # s: to a frame
    assert reason.startswith("t_end (target error 0.001 not reached at t = 0.3 s: ")
    assert "stopped early" not in proc.stdout and f"({reason})" in proc.stdout


def test_a_run_stopped_while_it_checks_its_target_leaves_a_valid_file(tmp_path):
    """SIGTERM (the runner's stop) may come while rank 0 reads the file for a check: the
    worker's SIGTERM thread still flushes, records ``interrupted`` and closes the file."""
    out, part = tmp_path / "k.h5", tmp_path / "k.h5.part"
    proc = subprocess.Popen([sys.executable, "-m", "vibrofeed.cli", "run", "bulk_feeder", "-o",
                             str(out), "-p", "t_end=5", *FED, "--target-error", "1e-3"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        end = time.monotonic() + 120
        while frames_now(part) < 50:  # 0.25 s: checked ~30 times, the first exits judged
            assert proc.poll() is None and time.monotonic() < end, proc.stderr.read()
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 143 and not out.exists()
    with Result(part, allow_incomplete=True) as r:
        assert r.status == "interrupted" and r.n_frames >= 50
        assert r.target_error == 1e-3 and r.stop_reason == ""  # it did not reach its end
    report = check_file(part, allow_incomplete=True)
    assert report.ok, [str(p) for p in report.problems]
