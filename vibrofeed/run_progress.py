"""Progress of a run on stderr: simulated time, steps/s, ETA; and the run's warnings.

On a terminal a bar (tqdm); elsewhere (a pipe, a batch job's log) a line now
and then: at every further tenth of the run, at most one per LINE_MIN seconds
and at least one per LINE_MAX seconds.
"""

from __future__ import annotations

import os
import sys
import time

from .values import duration

LINE_MIN, LINE_MAX = 5.0, 60.0


class RunProgress:
    """Feeds the worker's events to a progress display on stderr.

    ``enabled``: None (default) shows a bar on a terminal and lines elsewhere;
    True always a bar; False nothing but the warnings.
    """

    def __init__(self, label: str, enabled: bool | None = None, stream=None):
        self.stream = stream or sys.stderr
        tty = self.stream.isatty()
        self.mode = ("bar" if tty else "lines") if enabled is None else ("bar" if enabled else None)
        self.label = label
        self.bar = None
        self.t_end = 0.0
        self.n_steps = 0
        self._last_line = 0.0  # monotonic time of the last progress line
        self._last_tenth = 0

    def __call__(self, event: dict) -> None:
        kind = event["event"]
        if kind == "warning":  # shown with or without a bar (lost parts, a missing template)
            text = f"vibrofeed: warning: {self.label}: {event['message']}"
            if self.bar is not None:
                self.bar.write(text, file=self.stream)
            else:
                print(text, file=self.stream, flush=True)
            return
        if kind == "run":
            self.t_end = event["n_steps"] * event["dt"]
            self.n_steps = event["n_steps"]
            self._last_line = time.monotonic()
        if self.mode == "lines" and kind == "progress":
            self._line(event)
        if self.mode != "bar":
            return
        if kind == "run":
            try:  # a terminal that reports no size (0 columns) gets a fixed width
                sized = os.get_terminal_size(self.stream.fileno()).columns > 0
            except (OSError, ValueError, AttributeError):
                sized = False
            from tqdm import tqdm  # only for a bar: a quiet run or a log does without it

            self.bar = tqdm(total=event["n_steps"], desc=self.label, unit="step", unit_scale=True,
                            file=self.stream, dynamic_ncols=sized, ncols=None if sized else 100,
                            leave=False)
        elif kind == "progress" and self.bar is not None:
            self.bar.update(event["step"] - self.bar.n)
            self.bar.set_postfix_str(f"t={event['time']:.4g}/{self.t_end:.4g} s", refresh=True)
        elif kind == "done":
            self.close()

    def _line(self, event: dict) -> None:
        step, wall = event["step"], event.get("wall", 0.0)
        if not self.n_steps or step <= 0 or step >= self.n_steps:
            return  # the start and the end: the summary line says the rest
        now = time.monotonic()
        tenth = int(10 * step / self.n_steps)
        quiet = now - self._last_line
        if quiet < LINE_MIN or (tenth <= self._last_tenth and quiet < LINE_MAX):
            return
        self._last_line, self._last_tenth = now, tenth
        rate = step / wall if wall > 0 else float("nan")
        eta = f", ETA {duration((self.n_steps - step) / rate)}" if rate > 0 else ""
        print(f"{self.label}: t = {event['time']:.4g}/{self.t_end:.4g} s "
              f"({100 * step / self.n_steps:.3g}%), {rate / 1e3:.3g}k steps/s{eta}",
              file=self.stream, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
