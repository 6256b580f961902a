"""A feeder line's recirculation: rejects sent back to the inlet, as a bowl's return.

With ``recirculate=1`` every reject (a part that fell off a side, :class:`.outlet.LineOutlet`)
comes back ``return_delay`` seconds after it crossed the catch plane, as a new part dropped
at rest into the deck's inlet block. LIGGGHTS cannot move a part (or a multisphere clump)
from the driver safely across ranks, so the reject leaves through the box floor like any
other and the driver inserts a new one: at the first frame at or after its return time it
defines a ``fix insert/rate/region`` of the deck's particle distribution (``pdd``) and inlet
region (``inlet``) for the parts due, which inserts them in the next step (and retries at
every step while the block is too crowded to take them all). A return is therefore late by
up to one frame interval (``output_dt``).

The parts returned so far are the sum of those fixes' inserted counts (``f_ID[1]``); they
are part of ``inserted`` in the mass balance (inserted = fresh + returned = on_track +
exited + rejected + lost) and recorded as its ``returned`` count (FORMAT.md).
"""

from __future__ import annotations

import numpy as np

from ..geometry import insertion_seeds


def due_count(reject_times: np.ndarray, delay: float, now: float) -> int:
    """How many of the rejects (their catch-plane crossing times) are due back by ``now``."""
    return int(np.count_nonzero(np.asarray(reject_times, dtype=float) + delay <= now))


class Returns:
    """Sends rejects back to the inlet; one on every rank (the commands are collective).

    ``schedule(lmp, comm, now, reject_times)`` at each frame (``reject_times``: the crossing
    times of all rejects so far, on rank 0; ignored elsewhere) returns the commands to give
    before the next run segment (empty when none are due); a segment after commands needs a
    run with setup, as the insertion fix is new. ``returned(lmp)`` counts the parts inserted
    so far by all return fixes (collective).
    """

    PREFIX = "vf_return"

    def __init__(self, delay: float, seed: int, dt: float):
        if not delay >= 0:
            raise ValueError(f"return_delay must be >= 0, got {delay}")
        self.delay, self.seed, self.dt = float(delay), int(seed), float(dt)
        self.sent = 0  # parts handed to a return fix so far
        self.active: list[tuple[str, int]] = []  # (fix id, parts it must insert)
        self.finished = 0  # parts inserted by fixes since removed
        self._serial = 0

    def returned(self, lmp) -> int:
        return self.finished + sum(self._inserted(lmp, fix) for fix, _ in self.active)

    @staticmethod
    def _inserted(lmp, fix: str) -> int:
        return int(round(lmp.variable(f"{fix}_n")))

    def schedule(self, lmp, comm, now: float, reject_times) -> list[str]:
        due = due_count(reject_times, self.delay, now) - self.sent if comm.rank == 0 else 0
        if comm.size > 1:
            due = comm.bcast(due, root=0)
        if due <= 0:
            return []
        commands = []
        # finished fixes go with this setup (a fix may not be removed before a run without one)
        for fix, wanted in list(self.active):
            got = self._inserted(lmp, fix)
            if got >= wanted:
                self.finished += got
                self.active.remove((fix, wanted))
                commands += [f"unfix {fix}", f"variable {fix}_n delete"]
        self._serial += 1
        fix = f"{self.PREFIX}_{self._serial}"
        seed = insertion_seeds(self.seed + 7919 * self._serial, 1)[0]
        # a rate of (due + 1/2) per step makes all of them due in the first step; the fix
        # stops once it has inserted ``due`` (nparticles), retrying while the block is full
        rate = (due + 0.5) / self.dt
        commands += [
            f"fix {fix} all insert/rate/region seed {seed} distributiontemplate pdd "
            f"nparticles {due} particlerate {rate:.17g} insert_every 1 "
            "overlapcheck yes all_in yes vel constant 0 0 0 orientation ${insert_orientation} "
            "region inlet",  # (the deck's: a box turned at random, others as their template)
            f"variable {fix}_n equal f_{fix}[1]",
        ]
        self.active.append((fix, due))
        self.sent += due
        return commands
