"""Progress of a run on a terminal: simulated time, steps/s, ETA; and the run's warnings."""

from __future__ import annotations

import os
import sys

from tqdm import tqdm


class RunProgress:
    """Feeds the worker's events to a progress bar on stderr (only on a terminal)."""

    def __init__(self, label: str, enabled: bool | None = None, stream=None):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty() if enabled is None else enabled
        self.label = label
        self.bar = None
        self.t_end = 0.0

    def __call__(self, event: dict) -> None:
        kind = event["event"]
        if kind == "warning":  # shown with or without a bar (lost parts, a missing template)
            text = f"vibrofeed: warning: {self.label}: {event['message']}"
            if self.bar is not None:
                self.bar.write(text, file=self.stream)
            else:
                print(text, file=self.stream)
            return
        if not self.enabled:
            return
        if kind == "run":
            self.t_end = event["n_steps"] * event["dt"]
            try:  # a terminal that reports no size (0 columns) gets a fixed width
                sized = os.get_terminal_size(self.stream.fileno()).columns > 0
            except (OSError, ValueError, AttributeError):
                sized = False
            self.bar = tqdm(total=event["n_steps"], desc=self.label, unit="step", unit_scale=True,
                            file=self.stream, dynamic_ncols=sized, ncols=None if sized else 100,
                            leave=False)
        elif kind == "progress" and self.bar is not None:
            self.bar.update(event["step"] - self.bar.n)
            self.bar.set_postfix_str(f"t={event['time']:.4g}/{self.t_end:.4g} s", refresh=True)
        elif kind == "done":
            self.close()

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None
