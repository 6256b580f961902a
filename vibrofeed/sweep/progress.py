"""A sweep's progress on stderr: jobs done / running / failed, and the ETA.

On a terminal, one bar (tqdm, as ``vibrofeed run``'s) with the counts; else
(a batch job's log) one line per finished job. The ETA scales the expected
cost of the jobs left (``plan.cost``) by the wall seconds per unit of cost of
the jobs finished so far in this session, divided by the workers.
"""

from __future__ import annotations

import sys
import time

from ..values import duration


class SweepProgress:
    def __init__(self, jobs, workers: int, already_done: int = 0, already_failed: int = 0,
                 enabled: bool = True, stream=None, label=None):
        self.stream = stream or sys.stderr
        self.enabled = enabled
        self.total = len(jobs) + already_done + already_failed
        self.done, self.failed = already_done, already_failed
        self.workers = max(1, workers)
        self.cost = {job.index: job.cost for job in jobs}
        self.pending = set(self.cost)
        self.running: dict[int, float] = {}
        self.spent_wall = self.spent_cost = 0.0
        self.label = label or (lambda job: f"job {job.index}")
        self.bar = None
        if enabled and self.stream.isatty():
            from tqdm import tqdm

            self.bar = tqdm(total=self.total, initial=self.done + self.failed, desc="sweep",
                            unit="job", file=self.stream, leave=True)
            self._refresh()

    def eta(self) -> float | None:
        if self.spent_cost <= 0:
            return None
        left = sum(self.cost[i] for i in self.pending) + sum(self.cost[i] for i in self.running)
        return left * self.spent_wall / self.spent_cost / self.workers

    def status(self) -> str:
        eta = self.eta()
        return (f"{self.done} done, {len(self.running)} running, {self.failed} failed"
                + (f", ETA {duration(eta)}" if eta is not None else ""))

    def _refresh(self) -> None:
        if self.bar is not None:
            self.bar.set_postfix_str(self.status(), refresh=True)

    def started(self, job) -> None:
        self.pending.discard(job.index)
        self.running[job.index] = time.monotonic()
        self._refresh()

    def finished(self, job, row: dict, computed: bool = True) -> None:
        """``computed``: the job ran here (False: an earlier complete result was
        analysed), so its time counts towards the ETA."""
        began = self.running.pop(job.index, None)
        self.pending.discard(job.index)
        wall = time.monotonic() - began if began is not None else 0.0
        if row.get("status") == "done":
            self.done += 1
            if computed:
                self.spent_wall += wall
                self.spent_cost += self.cost.get(job.index, 0.0)
        else:
            self.failed += 1
        if not self.enabled:
            return
        if row.get("status") != "done":
            what = f"FAILED: {row.get('error')} ({wall:.1f} s)"
        elif computed:
            what = f"done ({wall:.1f} s)"
        else:  # its complete result was there already: only analysed, not run
            what = f"reused (an earlier complete result, analysed in {wall:.1f} s)"
        line = f"sweep: {self.label(job)}: {what}"
        if self.bar is not None:
            if row.get("status") != "done":
                self.bar.write(line, file=self.stream)
            self.bar.update(1)
            self._refresh()
        else:
            print(f"{line} | {self.done + self.failed}/{self.total}: {self.status()}",
                  file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
