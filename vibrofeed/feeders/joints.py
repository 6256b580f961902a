"""Joints: where one element hands its parts to the next, and what makes one sound.

A joint passes parts from element a's exit onto element b. It is sound when at every
instant b's floor lies below a's edge (a step down larger than the floors' relative
normal motion: no edge a part can catch), the step is small (below a part's
thickness: a part steps down, it does not fall), b is at least as wide as a's exit, and
the gap the two drives open along the path stays below half a part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..errors import ParameterError
from .records import Part


@dataclass(frozen=True)
class Joint:
    """The joint from element ``a`` to element ``b``: its position along the path ``at`` [m],
    the step down at rest at its least and most across a's exit [m], and how far the floors
    move apart normal (``dz``) and along (``dx``) [m]."""

    a: object  # an element (vibrofeed.feeders: a LinearSection, a Chute, a bowl)
    b: object

    @property
    def at(self) -> float:
        return self.b.x0

    @property
    def steps(self) -> tuple[float, float]:
        """The step down from a's floor to b's at rest, least and most across a's exit: both
        floors are planes tilted down towards -y, so the step is linear in y and its extremes
        lie at the exit's two ends."""
        e = self.a.exit_width / 2
        steps = [float(self.a.exit_z(y) - self.b.entry_z(y)) for y in (-e, e)]
        return min(steps), max(steps)

    @property
    def motion(self) -> tuple[float, float]:
        """(dz, dx): the floors' relative motion at most, normal and along [m]."""
        return self.a.drive.relative_to(self.b.drive)

    def check(self, part: Part) -> None:
        """One-line ParameterError naming b's parameter when the joint is not sound."""
        a, b = self.a, self.b
        step = b.name(("step",))
        chute = getattr(a, "sway", 0.0)  # (a bowl's chute end also moves across)
        cross = a.drive.sway_from(b.drive)  # (and so do cross strokes)
        sway = chute + cross
        if b.width < a.exit_width + 2 * sway:
            moves = (f"swaying {sway:.3g} m either way with the torsion" if chute and not cross
                     else f"the two moving {sway:.3g} m apart across" if sway else "")
            exit_ = (f"the bowl's chute ({a.exit_width:g} m, {moves})" if chute
                     else f"section {a.number}'s exit ({a.exit_width:g} m{', ' + moves if moves else ''})")
            hint = ("widen it or shorten chute_length" if chute
                    else f"narrow section {a.number} with its gate"
                    + (" or lessen the cross strokes ("
                       + ", ".join(e.name(("drive", "amp_c")) for e in (a, b) if e.drive.amp_c) + ")"
                       if cross else ""))
            raise ParameterError(
                f"{b.name(('width',))}={b.width:g} m is narrower than {exit_}: the elements do not "
                f"join (parts would fall at the joint); {hint}")
        dz, dx = self.motion
        low, high = self.steps
        # the step the tilted floors leave differs from the parameter across the exit, or
        # everywhere where the two widths differ (each floor is tilted about its own centre)
        tilted = not (math.isclose(low, high, rel_tol=0, abs_tol=1e-15)
                      and math.isclose(low, b.step, rel_tol=0, abs_tol=1e-15))
        if low <= dz:
            raise ParameterError(
                f"{step}={b.step:g} m: the joint must step down by more than the floors move apart "
                f"normal to them ({dz:.3g} m: the two drives' amp_n and phases), or section "
                f"{b.number}'s floor rises above section {a.number}'s and parts catch its edge"
                + (f" (the floors as tilted leave a step of {low:.3g} m at its least)" if tilted else ""))
        if high >= part.tallest:
            raise ParameterError(f"{step}={b.step:g} m is not a small step: keep it below a part's "
                                 f"thickness ({part.tallest:g} m)"
                                 + (f" (with the cross tilts it is {high:.3g} m at its most)"
                                    if tilted else ""))
        if dx >= part.size / 2:
            raise ParameterError(f"the joint opens by up to "
                                 f"{dx:.3g} m along the track ({a.name(('drive', 'amp_t'))}, "
                                 f"{b.name(('drive', 'amp_t'))}), more than half a part "
                                 f"({part.size / 2:g} m): parts would fall into it")
