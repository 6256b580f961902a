"""When an engine worker has stopped answering.

The worker's rank 0 says ``alive`` every second with the engine's step
(:class:`~vibrofeed.engine.worker.Heartbeat`) besides its progress messages.
A worker is hung when nothing came for ``floor`` seconds (it was stopped, or
is frozen), or when, once the run has begun, the step has not advanced for
``SLOWEST_FACTOR`` times the longest pause seen so far in this run, and never
less than ``floor`` (waiting for an MPI rank that hangs: rank 0 still beats,
but no step is taken). Before the run (reading the deck, settling a fill)
steps may legitimately stand still, so only the first test applies there.
"""

from __future__ import annotations

from ..environment import stall_seconds

FLOOR_SECONDS = 60.0
SLOWEST_FACTOR = 10.0


def floor_seconds() -> float:
    """The floor: ``VIBROFEED_STALL_SECONDS`` if set (a positive number, else refused:
    :mod:`vibrofeed.environment`), else FLOOR_SECONDS."""
    value = stall_seconds()
    return FLOOR_SECONDS if value is None else value


class Watchdog:
    def __init__(self, now: float, floor: float | None = None):
        self.floor = floor_seconds() if floor is None else float(floor)
        self.last_seen = now
        self.running = False
        self.step = None
        self.last_advance = now
        self.slowest = 0.0

    def saw(self, event: dict, now: float) -> None:
        """Note a message of the worker, received at ``now``. A heartbeat's own time
        (``at``, the same monotonic clock) times the steps: messages read late, after
        this process was suspended, still tell how the worker went."""
        self.last_seen = now
        kind = event.get("event")
        if kind == "run":
            self.running, self.last_advance = True, now
            return
        if kind != "alive":
            return
        step, at = event.get("step"), min(float(event.get("at", now)), now)
        advanced = step is not None and self.step is not None and step != self.step
        self.step = step
        if advanced and self.running and at > self.last_advance:
            self.slowest = max(self.slowest, at - self.last_advance)
            self.last_advance = at

    def limit(self) -> float:
        """Seconds without a step that mean the run is hung, now."""
        return max(self.floor, SLOWEST_FACTOR * self.slowest)

    def stalled(self, now: float) -> str | None:
        """Why the worker counts as hung at ``now``, or None."""
        quiet = now - self.last_seen
        if quiet > self.floor:
            return f"the engine worker has not answered for {quiet:.0f} s (stopped or frozen)"
        still = now - self.last_advance
        if self.running and still > self.limit():
            return (f"the engine took no step for {still:.0f} s (limit {self.limit():.0f} s: "
                    f"{SLOWEST_FACTOR:g} x the longest pause of this run, at least {self.floor:g} s; "
                    "a hung MPI rank?)")
        return None
