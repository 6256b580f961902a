"""Replay a measured trial in LIGGGHTS: the platform's motion on a vertical wall.

The DEM engine of ``vibrofeed replay``. The platform moves as the same
interpolant the model uses (``trials.fit_platform``: a quintic spline with a
knot at every frame), played piece by piece: before each frame interval the
driver redefines the deck's ``drive_x`` (position), ``drive_x_p`` (position one
timestep earlier) and ``drive_vx`` (velocity) as that piece's polynomials in
LIGGGHTS' ``time``, then runs the interval with setup (``single_part``,
waveform 4). The plate therefore follows the spline to round-off, exactly as
the model's surface does.

The part is a sphere of the trial's mass (radius 1 cm, density from the mass)
pressed against the wall (``incline = 90``: x up the wall) by
``normal_force``. LIGGGHTS has one friction coefficient, so the DEM is compared
with the model at mu_s = mu_k.

Contact: the model's part is rigid, and the replays are sensitive (0.1 % of
friction moves trial 5 by 0.009 mm), so the contact must be near rigid and
exactly Coulomb:
- tangential damping off: LIGGGHTS adds it beyond the Coulomb cap while the
  spring reloads, i.e. at every stick/slip transition; with it on the DEM is
  0.05-0.2 mm off the model on the low-force trials, at any stiffness;
- 1e13 Pa (a numerical device, ~50x steel): the 9 g part's tangential contact
  then oscillates at ~15 kHz, far above the platform's millisecond changes of
  acceleration. Measured mean |DEM - model| on trials 1-6 at mu = 0.6 and the
  measured forces: <= 0.06 mm at 1e10 Pa with damping off, 0.012 mm at 1e12,
  0.006 mm at 1e13 (target 0.02 mm); ~13 s per trial.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import PPoly

from .fit import EDGE_FRAMES, ReplayResult, compare_with_measurement, prepare
from .trials import Trial

PART_RADIUS = 0.01  # m
CONTACT = {"youngs": "1e13", "poisson": "0.3", "restitution": "0.06", "tangential_damping": "0",
           "rolling": "0"}


def _horner(coefficients, s: str) -> str:
    """A LIGGGHTS formula for sum c_j s^(n-j) (Horner form)."""
    expr = repr(float(coefficients[0]))
    for c in coefficients[1:]:
        expr = f"({expr})*{s}+({float(c)!r})"
    return expr


def platform_schedule(trial, edge_frames: int = EDGE_FRAMES):
    """(before_run, schedule, t0, duration) playing the trial's platform motion.

    Simulation time 0 is the trial's frame ``edge_frames``; positions are
    displacements from the platform's position there.
    """
    prep = prepare(trial)
    tr = prep.trial
    k0, k1 = edge_frames, tr.n_frames - edge_frames
    pp = PPoly.from_spline(prep.fit.spline)
    vel = pp.derivative()
    t0 = float(tr.t[k0])
    z0 = float(pp(t0))
    # Piece of the spline holding each frame interval [t_k, t_k+1).
    segments = []
    for k in range(k0, k1 - 1):
        a, b = float(tr.t[k]), float(tr.t[k + 1])
        i = int(np.searchsorted(pp.x, 0.5 * (a + b)) - 1)
        start = float(pp.x[i]) - t0  # piece origin in simulation time
        c = pp.c[:, i].copy()
        c[-1] -= z0
        s_now = f"(time-({start!r}))"
        s_prev = f"(time-$(v_dt_used)-({start!r}))"
        segments.append({
            "commands": [f"variable drive_x equal {_horner(c, s_now)}",
                         f"variable drive_x_p equal {_horner(c, s_prev)}",
                         f"variable drive_vx equal {_horner(vel.c[:, i], s_now)}"],
            "until": b - t0,
        })
    before = segments[0]["commands"] + [
        "velocity all set $(v_surface_vx) 0 0 units box"]  # the part moves with the platform
    return before, segments, t0, float(tr.t[k1 - 1]) - t0


def deck_parameters(mass: float, normal_force: float, mu: float, duration: float,
                    frame_dt: float) -> dict:
    density = mass / (4.0 / 3.0 * math.pi * PART_RADIUS ** 3)
    return {"waveform": "4", "incline": "90", "amp_t": "0", "amp_n": "0",
            "normal_force": repr(float(normal_force)), "mu": repr(float(mu)),
            "radius": repr(PART_RADIUS), "density": repr(density), **CONTACT,
            "t_end": repr(duration), "output_dt": repr(frame_dt)}


def replay_request(trial: Trial, mass: float, normal_force: float, mu: float, output,
                   edge_frames: int = EDGE_FRAMES, ranks: int = 1, reuse: bool = False):
    """The LIGGGHTS run replaying ``trial``, as a request for the batch executor."""
    from vibrofeed.decks import Deck
    from vibrofeed.engine.batch import RunRequest

    prep = prepare(trial)
    before, segments, t0, duration = platform_schedule(prep, edge_frames)
    params = deck_parameters(mass, normal_force, mu, duration, prep.trial.dt)
    return RunRequest(Deck.find("single_part"), params, output, label=prep.name, ranks=ranks,
                      reuse=reuse, before_run=before, schedule=segments)


def replay_result(trial: Trial, output, normal_force: float, mu: float,
                  edge_frames: int = EDGE_FRAMES) -> ReplayResult:
    """Compare the LIGGGHTS replay in ``output`` with the measured part."""
    from vibrofeed.results.reader import Result

    tr = prepare(trial).trial
    with Result(output) as r:
        t_dem = r.time
        x = r.track(int(r.part_ids[0]))[1][:, 0]
        v = r.track(int(r.part_ids[0]), "velocity")[1][:, 0]
        vs = r.surface_velocity[:, 0]
        xs = r.surface_position[:, 0]
    # Stuck: moving with the wall, to 1 % of the wall's largest speed.
    stuck = np.abs(v - vs) <= 1e-2 * np.abs(vs).max()
    return compare_with_measurement(tr, edge_frames, t_dem - t_dem[0], x - x[0], xs, stuck,
                                    stuck.mean(), float(normal_force), float(mu))


def replay_dem(trial: Trial, mass: float, normal_force: float, mu: float, output,
               edge_frames: int = EDGE_FRAMES, ranks: int = 1, on_event=None) -> ReplayResult:
    """Replay a trial in LIGGGHTS into ``output`` (H5MD) and compare with the
    measured part; fields as ``fit.replay``."""
    from vibrofeed.engine.runner import run_deck

    req = replay_request(trial, mass, normal_force, mu, output, edge_frames, ranks)
    run_deck(req.deck, req.params, req.output, ranks=req.ranks, before_run=req.before_run,
             schedule=req.schedule, on_event=on_event)
    return replay_result(trial, output, normal_force, mu, edge_frames)
