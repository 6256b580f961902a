"""A sweep's progress lines (no terminal: one line per finished job) from hand-set jobs,
costs and a fake clock: the counts, the total, and the ETA = cost left x wall seconds per
unit of cost spent so far / workers."""

from __future__ import annotations

import io
from types import SimpleNamespace

import pytest

from helpers import FakeClock
from vibrofeed.sweep import progress as P


@pytest.fixture
def clock(monkeypatch):
    c = FakeClock()
    monkeypatch.setattr(P, "time", c)
    return c


def jobs(*costs):
    return [SimpleNamespace(index=i, cost=c) for i, c in enumerate(costs)]


def test_lines_count_jobs_of_earlier_sessions_and_the_eta_scales_the_cost_left(clock):
    out = io.StringIO()
    js = jobs(1.0, 2.0, 3.0)
    p = P.SweepProgress(js, 2, already_done=1, already_failed=1, stream=out)
    assert p.total == 5 and p.eta() is None  # nothing finished here yet: no rate
    p.started(js[0])
    p.started(js[1])
    clock.now = 10.0
    p.finished(js[0], {"status": "done"})
    # left: pending job 2 (cost 3) + running job 1 (cost 2) = 5; 10 s per unit; 2 workers
    assert p.eta() == pytest.approx(5 * 10.0 / 1.0 / 2, rel=1e-12)
    clock.now = 12.0
    p.finished(js[1], {"status": "failed", "error": "boom"})
    assert out.getvalue().splitlines() == [
        "sweep: job 0: done (10.0 s) | 3/5: 2 done, 1 running, 1 failed, ETA 25s",
        "sweep: job 1: FAILED: boom (12.0 s) | 4/5: 2 done, 0 running, 2 failed, ETA 15s",
    ]


def test_one_worker_and_no_earlier_jobs(clock):
    out = io.StringIO()
    js = jobs(2.0, 4.0)
    p = P.SweepProgress(js, 1, stream=out, label=lambda job: f"J{job.index}")
    p.started(js[0])
    clock.now = 3.0
    p.finished(js[0], {"status": "done"})
    # 3 s for a cost of 2: 1.5 s per unit; cost 4 left on one worker: 6 s
    assert out.getvalue() == "sweep: J0: done (3.0 s) | 1/2: 1 done, 0 running, 0 failed, ETA 6s\n"


def test_a_reused_result_counts_as_done_but_not_towards_the_eta(clock):
    out = io.StringIO()
    js = jobs(1.0, 1.0)
    p = P.SweepProgress(js, 1, stream=out)
    clock.now = 2.0
    p.finished(js[0], {"status": "done"}, computed=False)
    assert p.eta() is None
    assert out.getvalue() == ("sweep: job 0: reused (an earlier complete result, analysed in 0.0 s)"
                              " | 1/2: 1 done, 0 running, 0 failed\n")


def test_disabled_counts_silently(clock):
    out = io.StringIO()
    js = jobs(1.0)
    p = P.SweepProgress(js, 1, enabled=False, stream=out)
    p.finished(js[0], {"status": "failed", "error": "x"})
    assert (p.done, p.failed, out.getvalue()) == (0, 1, "")


def test_no_workers_counts_as_one(clock):
    js = jobs(1.0, 2.0)
    p = P.SweepProgress(js, 0, stream=io.StringIO())
    p.started(js[0])
    clock.now = 5.0
    p.finished(js[0], {"status": "done"})
    assert p.eta() == pytest.approx(2.0 * 5.0, rel=1e-12)


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_on_a_terminal_the_bar_counts_and_only_failures_get_a_line(clock):
    out = Terminal()
    js = jobs(1.0, 1.0)
    p = P.SweepProgress(js, 1, stream=out)
    p.finished(js[0], {"status": "done"})
    p.finished(js[1], {"status": "failed", "error": "boom"})
    p.close()
    text = out.getvalue()
    assert "sweep: job 1: FAILED: boom (0.0 s)" in text and "sweep: job 0" not in text
    assert "2/2" in text and p.bar is None
