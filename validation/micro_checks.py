"""Cross-check kinds of the micro-scale surface forces (decks/include/surface_forces.liggghts).

Registered in ``crosscheck.KINDS``; each takes the case, its finished DEM
runs of the ``single_part`` deck, the outcome to fill and the figure folder:

``vdw_pulloff``
    A part resting on a plate that vibrates normal to itself leaves it when
    the plate's downward acceleration exceeds g plus the adhesion's pull on it.
    The DEM's pull-off is m (-a_n(t_l) - g) at its lift-off t_l (the gap
    turning positive); the model's is the van der Waals force in contact,
    A R / (6 s^2), s = 0.2 nm + roughness (models/adhesion.py).
``sticking``
    The amplitude at which a part first leaves the track: Gamma_c = 1 +
    F_pulloff / (m g), growing with the Hamaker constant. Each run's Gamma
    sits below or above the model's Gamma_c; the row compares whether the
    part left the plate (gap above ``leave_gap``, default 100 nm) with
    whether the model says it must (1 or 0; tolerance 0: equal).
``squeeze_launch``
    A part launched from a plate vibrating at Gamma > 1 through its air film:
    the velocity deficit at the top of its relative flight and that flight's
    height against the §3.2 ODE (models/squeeze_film.py) started at the DEM's
    own clearance. The DEM deficit is v_p(t_l) - g (t - t_l) - v_p(t) at the
    top of the relative flight (the first frame from which the gap shrinks).

The part's lift-off is where its gap (z - radius - z_s) first turns positive
after the start, interpolated between frames; the contact force cannot be used
as ``postproc.flights`` does, since the recorded force now also holds the
surface forces.

"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..errors import CaseError
from ..models import deck as dm
from ..models.constants import G
from . import plots
from .outcome import row


def _require_flat_plate(case, run) -> None:
    if run.number("incline") != 0 or run.number("amp_t") != 0 or int(run.number("waveform")) != 0:
        raise CaseError(f"case {case.name} [{run.label}]: needs a flat plate (incline 0) moving as a "
                        "sine normal to itself only (amp_t 0, waveform 0)")


def _trajectory(result) -> dict:
    """Time, gap, part and surface normal velocity of the result's part."""
    t, x = result.track(int(result.part_ids[0]))
    _, v = result.track(int(result.part_ids[0]), "velocity")
    radius = float(result.parameters["radius"])
    return {"t": t, "gap": x[:, 2] - radius - result.surface_position[:, 2], "v": v[:, 2],
            "vs": result.surface_velocity[:, 2]}


def lift_off(t: np.ndarray, gap: np.ndarray) -> float | None:
    """Time the gap first turns positive after a frame in contact (linear
    interpolation between the two frames); None if it never does."""
    after = np.flatnonzero((gap[1:] > 0) & (gap[:-1] <= 0))
    if not len(after):
        return None
    i = int(after[0])
    return float(t[i] + (t[i + 1] - t[i]) * (-gap[i]) / (gap[i + 1] - gap[i]))


# ----------------------------------------------------------------- kind: vdw_pulloff
def vdw_pulloff(case, runs, out, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result


    panels = []
    for run in runs:
        _require_flat_plate(case, run)
        p = run.params
        mass = dm.mass(p)
        with Result(run.output) as r:
            tr = _trajectory(r)
        t_l = lift_off(tr["t"], tr["gap"])
        if t_l is None:
            raise CaseError(f"case {case.name} [{run.label}]: the part never left the plate; "
                            "raise gamma above the sticking threshold")
        a_n = float(dm.waveform(p).acceleration(np.array([t_l]))[1][0])
        dem = mass * (-a_n - G)
        model = dm.adhesion(p).pulloff
        out.rows.append(row(case, "pulloff", run.label, model, dem, "N"))
        panels.append({"label": run.label, "hamaker": run.number("hamaker"), "model": model, "dem": dem})
    out.figures.append(plots.plot_vdw_pulloff(case, panels, fig_dir / "pulloff.png"))


# ----------------------------------------------------------------- kind: sticking
def sticking(case, runs, out, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result

    from ..models.adhesion import sticking_gamma

    leave_gap = float(case.compare.get("leave_gap", 1e-7))
    points = []
    for run in runs:
        _require_flat_plate(case, run)
        p = run.params
        gamma = dm.gamma_from_amp(run.number("amp_n"), run.number("freq"))
        gamma_c = sticking_gamma(dm.adhesion(p), dm.mass(p))
        with Result(run.output) as r:
            tr = _trajectory(r)
        left = float(tr["gap"].max() > leave_gap)
        model = float(gamma > gamma_c)
        out.rows.append(row(case, "leaves", run.label, model, left))
        points.append({"hamaker": run.number("hamaker"), "gamma": gamma, "gamma_c": gamma_c,
                       "left": bool(left), "max_gap": float(tr["gap"].max())})
    out.figures.append(plots.plot_sticking(case, points, fig_dir / "sticking.png"))


# ----------------------------------------------------------------- kind: squeeze_launch
def squeeze_launch(case, runs, out, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result

    from ..models.squeeze_film import launch

    panels = []
    for run in runs:
        _require_flat_plate(case, run)
        p = run.params
        if run.number("hamaker") != 0 or run.number("air_viscosity") <= 0:
            raise CaseError(f"case {case.name} [{run.label}]: needs air_viscosity > 0 and hamaker = 0")
        freq, mass, film = run.number("freq"), dm.mass(p), dm.film(p)
        gamma = dm.gamma_from_amp(run.number("amp_n"), freq)
        model = launch(film, mass, freq, gamma)
        if model.end != "apex":
            raise CaseError(f"case {case.name} [{run.label}]: in the model the part never gets free "
                            "(its film deficit exceeds the launch velocity); lower the frequency")
        with Result(run.output) as r:
            tr = _trajectory(r)
        t_l = lift_off(tr["t"], tr["gap"])
        if t_l is None:
            raise CaseError(f"case {case.name} [{run.label}]: the part never left the plate")
        # the top of the relative flight, as in the model: the first frame after
        # lift-off from which the gap shrinks (the plate may overtake the part
        # later in the same flight, at high frequency)
        w_rel = tr["v"] - tr["vs"]
        turn = np.flatnonzero((tr["t"][:-1] > t_l) & (w_rel[:-1] > 0) & (w_rel[1:] <= 0))
        if not len(turn):
            raise CaseError(f"case {case.name} [{run.label}]: the run ends before the top of the "
                            "flight; raise t_end")
        k = int(turn[0]) + int(tr["gap"][turn[0] + 1] > tr["gap"][turn[0]])
        flight = (tr["t"] > t_l) & (tr["t"] <= tr["t"][k] + 0.25 / freq)
        # launched with its own velocity when the contact ends (the softened contact's
        # relaxing overlap adds ~0.3 mm/s to the plate's at 300 Hz, Gamma 10)
        v_l = float(np.interp(t_l, tr["t"], tr["v"]))
        dem_deficit = v_l - G * (tr["t"][k] - t_l) - tr["v"][k]
        out.rows.append(row(case, "deficit", run.label, model.final_deficit, dem_deficit, "m/s"))
        out.rows.append(row(case, "max_gap", run.label, model.max_gap, tr["gap"][k], "m"))
        panels.append({"label": run.label, "dem_t": tr["t"][flight] - t_l, "dem_gap": tr["gap"][flight],
                       "model_t": model.t, "model_gap": model.gap, "freq": freq})
    out.figures.append(plots.plot_launch(case, panels, fig_dir / "launch.png"))


#: The kinds of this module, merged into ``crosscheck.KINDS``.
KINDS = {"vdw_pulloff": vdw_pulloff, "sticking": sticking, "squeeze_launch": squeeze_launch}
