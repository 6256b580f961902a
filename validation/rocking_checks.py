"""Cross-check kinds of a box part rocking, tipping or sliding (deck ``box_on_plate``).

Registered in ``crosscheck.KINDS``; each takes the case, its finished DEM runs, the
outcome to fill and the figure folder. The closed forms are vibrofeed.models.rocking's,
with the clump's pivot geometry (b = (D_along - d)/2, h = D_vertical/2, clump_pivot) of
the run's pose (vibrofeed.poses.pose_dims); the DEM's tilt is read off the recorded
orientation quaternions (vibrofeed.poses.tilt_angle), its angular velocity off the
recorded body's.

``rocking_onset``
    Whether the part rocks on a plate driven by the sine: the DEM rocks when its tilt
    from upright exceeds ``[compare] rock_angle`` [deg] at some frame; the model when
    Housner's margin (rocking.sine_rocking_margin) is positive. Row ``rocks``: 1 or 0,
    each (tolerance 0: equal). Refused if mu <= b/h (the part would slide first).
``free_rocking``
    A part released tilted about its pivot: at each of the first ``[compare] impacts``
    impacts (the signed tilt crossing 0) the ratio of the angular velocity just after to
    just before, each a straight-line fit of w_y over ``window`` [s] on its side of the
    impact, leaving out ``gap_before`` and ``gap_after`` [s] next to it (the landing face's
    contacts ring for ~0.4 ms at the default stiffness), evaluated at the crossing; rows
    ``impact_ratio`` (Housner's r with the box's true inertia,
    rocking.clump_impact_ratio) and ``impact_speed`` (w just before the first impact
    against energy conservation, rocking.impact_speed).
``tip_or_slide``
    A part at rest on a plate whose incline is ramped up: the DEM's regime is TIP when its
    tilt exceeds ``[compare] tip_angle`` [deg], else SLIDE when it moved along the track
    by more than ``slide_distance`` [m] relative to the plate, else REST; the model's
    rocking.incline_regime. Row ``regime``: 0 rest, 1 slide, 2 tip (tolerance 0).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..models import rocking as K
from ..poses import pose_dims, tilt_angle
from .outcome import row


def _geometry(run) -> tuple[float, float, float]:
    """(b, h, gyration_sq about the rocking axis) of the run's pose."""
    along, vertical, d = pose_dims(run.params)
    b, h = K.clump_pivot(along, vertical, d)
    return b, h, (along**2 + vertical**2) / 12


def _motion(run) -> dict:
    from vibrofeed.results.reader import Result

    stand, facing = int(run.number("stand")), int(run.number("facing"))
    with Result(run.output) as r:
        pid = int(r.part_ids[0])
        t, q = r.track(pid, "orientation")
        _, w = r.track(pid, "angular_velocity")
        _, x = r.track(pid, "position")
        xs = r.surface_position[: len(t), 0]
    signed, total = tilt_angle(q, stand, facing)
    return {"t": t, "signed": signed, "total": total, "wy": w[:, 1], "x": x[:, 0] - xs}


def rocking_onset(case, runs, out, fig_dir: Path) -> None:
    limit = math.radians(float(case.compare.get("rock_angle", 0.5)))
    for run in runs:
        b, h, _ = _geometry(run)
        if K.slides_first(run.number("mu"), b, h):
            raise CaseError(f"case {case.name} [{run.label}]: mu = {run.number('mu'):g} <= b/h = "
                            f"{b / h:.3g}: the part slides before it can rock")
        margin = K.sine_rocking_margin(b, h, run.number("freq"), run.number("amp_t"),
                                       run.number("amp_n"), run.number("phase"), run.number("incline"))
        m = _motion(run)
        out.rows.append(row(case, "rocks", run.label, float(margin > 0), float(m["total"].max() > limit)))


def impacts(t: np.ndarray, signed: np.ndarray) -> np.ndarray:
    """Times the signed tilt crosses 0 (linear interpolation between frames)."""
    k = np.flatnonzero(np.sign(signed[1:]) != np.sign(signed[:-1]))
    return t[k] - signed[k] * (t[k + 1] - t[k]) / (signed[k + 1] - signed[k])


def side_fit(t: np.ndarray, w: np.ndarray, t_i: float, lo: float, hi: float) -> float:
    """w at t_i from a straight line fitted to the frames with lo <= t - t_i <= hi."""
    sel = (t - t_i >= lo) & (t - t_i <= hi)
    if sel.sum() < 3:
        raise CaseError(f"fewer than 3 frames between {lo:g} s and {hi:g} s of the impact at {t_i:g} s: "
                        "a finer output_dt or a wider window")
    slope, intercept = np.polyfit(t[sel] - t_i, w[sel], 1)
    return float(intercept)


def free_rocking(case, runs, out, fig_dir: Path) -> None:
    n_impacts = int(case.compare.get("impacts", 2))
    window = float(case.compare.get("window", 1.5e-3))
    gap_before, gap_after = (float(case.compare.get(k, v)) for k, v in (("gap_before", 1e-4),
                                                                         ("gap_after", 5e-4)))
    for run in runs:
        b, h, gyr = _geometry(run)
        r_model = K.clump_impact_ratio(b, h, gyr)
        m = _motion(run)
        hits = impacts(m["t"], m["signed"])
        if len(hits) < n_impacts:
            raise CaseError(f"case {case.name} [{run.label}]: {len(hits)} impacts in the run, "
                            f"{n_impacts} compared; a longer t_end")
        bounds = np.r_[0.0, hits, m["t"][-1]]
        for k, t_i in enumerate(hits[:n_impacts], start=1):
            before = min(window, 0.5 * (t_i - bounds[k - 1]))
            after = min(window, 0.5 * (bounds[k + 1] - t_i))
            w1 = side_fit(m["t"], m["wy"], t_i, -before, -gap_before)
            w2 = side_fit(m["t"], m["wy"], t_i, gap_after, after)
            if k == 1:
                d = pose_dims(run.params)[2]
                speed = K.impact_speed(math.radians(run.number("tilt")), b, h, gyr, rolling_radius=d / 2)
                out.rows.append(row(case, "impact_speed", run.label, speed, abs(w1), "rad/s"))
            out.rows.append(row(case, "impact_ratio", f"{run.label},#{k}", r_model, w2 / w1))


def regime_of(m: dict, tip_angle: float, slide_distance: float) -> int:
    """The DEM's regime (rocking.REST, SLIDE, TIP) of a run's motion."""
    if m["total"].max() > tip_angle:
        return K.TIP
    if np.abs(m["x"] - m["x"][0]).max() > slide_distance:
        return K.SLIDE
    return K.REST


def tip_or_slide(case, runs, out, fig_dir: Path) -> None:
    tip = math.radians(float(case.compare.get("tip_angle", 5.0)))
    slide = float(case.compare.get("slide_distance", 1e-4))
    for run in runs:
        b, h, _ = _geometry(run)
        model = K.incline_regime(run.number("incline"), run.number("mu"), b, h)
        out.rows.append(row(case, "regime", run.label, model, regime_of(_motion(run), tip, slide)))


#: The kinds of this module, merged into ``crosscheck.KINDS``.
KINDS = {"rocking_onset": rocking_onset, "free_rocking": free_rocking, "tip_or_slide": tip_or_slide}
