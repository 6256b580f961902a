"""What limits the prediction of the measured trials? (numbers for the notes)

Run ``python -m vibrofeed.validation.studies.vertical_study`` (about 30 s) to
recompute the tables of replay/VERTICAL_TRANSPORT_NOTES.md. Every hypothesis is
scored the same way: each trial predicted with its MEASURED normal force,
every other parameter (mu_k and the hypothesis' own) chosen on a grid to
minimise the mean MAE of the OTHER trials (leave-one-out). A hypothesis
"helps" only if that held-out error drops.
"""

from __future__ import annotations

import dataclasses
import itertools
import time

import numpy as np
from scipy.interpolate import PPoly, make_interp_spline
from scipy.signal import lsim

from ...models.constants import G
from ...models.surface import PolynomialSurface
from ...models.vertical import Contact, simulate
from ..replay.fit import (
    EDGE_FRAMES,
    MU_S,
    PART_MASS,
    PreparedTrial,
    fit_trials,
    leave_one_out,
    measured_normal_force_mg,
    prepare,
    replay,
)
from ..replay.trials import estimate_noise, fit_position, load_trials
from .speed_dependent_friction import simulate_speed_dependent

__all__ = ["error_table", "leave_one_out_from_table", "noise_floor", "run_study"]

MU_GRID = np.linspace(0.30, MU_S, 15)


def error_table(preps, combos, mae) -> np.ndarray:
    """MAE [mm] of every trial (rows) for every parameter combination (columns)."""
    return np.array([[mae(p, *c) for c in combos] for p in preps])


def leave_one_out_from_table(table: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Held-out error of each trial with the combination best on the others."""
    n = table.shape[0]
    if n < 2:
        raise ValueError("need at least two trials")
    chosen = np.array([int(np.argmin(np.delete(table, i, axis=0).mean(axis=0)))
                       for i in range(n)])
    return table[np.arange(n), chosen], chosen


def _mae_coulomb(p, mu_k, scale=1.0):
    fn = scale * measured_normal_force_mg(p) * PART_MASS * G
    return replay(p, PART_MASS, fn, MU_S, mu_k).mean_abs_error_mm


def _with_surface(p: PreparedTrial, surface) -> PreparedTrial:
    return PreparedTrial(trial=p.trial, surface=surface, fit=p.fit)


def _refit(trial, **kwargs) -> PreparedTrial:
    noise = kwargs.pop("noise_factor", 1.0) * estimate_noise(trial.platform.z)
    fit = fit_position(trial.t, trial.platform.z, noise=noise, **kwargs)
    return PreparedTrial(trial=trial, surface=fit.surface, fit=fit)


def _transformed(trial, kind: str, angle_deg: float = 0.0):
    """Platform and part z in another frame: relative to marker s, or a rotated camera."""
    platform, part, marker = trial.platform, trial.part, trial.marker
    if kind == "marker":
        ref = marker.z - marker.z[0]
        platform = dataclasses.replace(platform, z=platform.z - ref)
        part = dataclasses.replace(part, z=part.z - ref)
    elif kind == "tilt":
        c, s = np.cos(np.radians(angle_deg)), np.sin(np.radians(angle_deg))
        platform = dataclasses.replace(platform, z=c * platform.z + s * platform.x)
        part = dataclasses.replace(part, z=c * part.z + s * part.x)
    return dataclasses.replace(trial, platform=platform, part=part)


def _compliant(p: PreparedTrial, f_c: float, zeta: float = 1.0) -> PreparedTrial:
    """Platform motion seen through a tangential spring-damper (natural freq. f_c)."""
    t0, t1 = p.trial.t[0], p.trial.t[-1]
    tt = np.linspace(t0, t1, int((t1 - t0) * 40000) + 1)
    z, v = p.surface.position(tt)[0], p.surface.velocity(tt)[0]
    w = 2 * np.pi * f_c
    sys = (np.array([[0, 1], [-w * w, -2 * zeta * w]]), np.array([[0, 0], [w * w, 2 * zeta * w]]),
           np.array([[1.0, 0.0]]), np.zeros((1, 2)))
    _, y, _ = lsim(sys, np.column_stack([z, v]), tt - t0, X0=[z[0], v[0]])
    return _with_surface(p, PolynomialSurface(PPoly.from_spline(make_interp_spline(tt, y, k=5))))


def _mae_speed(p, mu_k, ratio, v_c):
    tr, e = p.trial, EDGE_FRAMES
    t = tr.t[e:tr.n_frames - e]
    c = Contact(PART_MASS, measured_normal_force_mg(p) * PART_MASS * G, MU_S, mu_k)
    z, _, _ = simulate_speed_dependent(p.surface, c, ratio * mu_k, v_c, float(t[-1]),
                                       float(t[0]), float(tr.part.z[e]), t)
    return float(np.mean(np.abs(z - tr.part.z[e:tr.n_frames - e]))) * 1e3


def _row(name, preps, table, combos, describe):
    loo, chosen = leave_one_out_from_table(table)
    return {"variant": name, "loo_mae_mm": dict(zip([p.name for p in preps], loo)),
            "mean": float(np.mean(loo)),
            "chosen": [describe(combos[k]) for k in chosen]}


def _variant_row(name, preps, variants: dict, describe):
    """Row of a family of modified trials: ``variants`` maps a setting to the
    prepared trials under it; every (setting, mu_k) pair is scored."""
    combos = list(itertools.product(variants, MU_GRID[::2]))
    table = np.array([[_mae_coulomb(variants[v][i], m) for v, m in combos]
                      for i in range(len(preps))])
    return _row(name, preps, table, combos, describe)


def noise_floor(prep: PreparedTrial, normal_force_mg: float, mu_k: float,
                seeds=(0, 1, 2)) -> float:
    """MAE [mm] that tracking noise alone causes, for a trial and parameters.

    Treats the trial's platform spline as the true platform, makes the true
    part with the model, adds white noise of the trial's estimated sigma to
    both tracks (as the tracker would), refits the platform and replays with
    the true parameters. Mean over ``seeds``.
    """
    tr = prep.trial
    contact = Contact(PART_MASS, normal_force_mg * PART_MASS * G, MU_S, mu_k)
    t = tr.t
    truth = prep.surface
    part = simulate(truth, contact, t_end=float(t[-1]), t_start=float(t[0]),
                    z0=float(tr.part.z[0]), t_eval=t).z
    sig_p, sig_o = estimate_noise(tr.platform.z), estimate_noise(tr.part.z)
    errors = []
    for seed in seeds:
        rng = np.random.default_rng(seed)
        noisy = dataclasses.replace(
            tr, platform=dataclasses.replace(tr.platform, z=truth.position(t)[0]
                                             + sig_p * rng.standard_normal(t.size)),
            part=dataclasses.replace(tr.part, z=part + sig_o * rng.standard_normal(t.size)))
        r = replay(prepare(noisy), PART_MASS, contact.normal_force, MU_S, mu_k)
        errors.append(r.mean_abs_error_mm)
    return float(np.mean(errors))


def run_study(trials=None, verbose: bool = True) -> dict:
    """All hypothesis tests; returns {"fit": ..., "rows": [...]}."""
    trials = load_trials() if trials is None else trials
    preps = [prepare(tr) for tr in trials]
    out = {"rows": []}
    clock = time.time()

    def say(msg):
        if verbose:
            print(f"[{time.time() - clock:5.1f} s] {msg}", flush=True)

    fit = fit_trials(preps)
    loo = leave_one_out(preps)
    out["fit"], out["loo"] = fit, loo
    say(f"fit protocol: mean MAE {fit.mean_mae_mm:.4f} mm; leave-one-out {loo.mean_mae_mm:.4f}")
    out["noise_floor"] = {p.name: noise_floor(p, fit.normal_force_mg[p.name], fit.mu_k)
                          for p in preps}
    say("noise floor")

    mus = [(m,) for m in MU_GRID]
    base = error_table(preps, mus, _mae_coulomb)
    out["rows"].append(_row("Coulomb, measured F_n (grid)", preps, base, mus,
                            lambda c: f"mu_k={c[0]:.2f}"))
    say("baseline")

    combos = list(itertools.product(MU_GRID[::2], np.geomspace(0.8, 4.0, 15)))
    table = error_table(preps, combos, _mae_coulomb)
    out["rows"].append(_row("one force scale c for all trials", preps, table, combos,
                            lambda c: f"mu_k={c[0]:.2f},c={c[1]:.2f}"))
    say("force scale")

    for label, kwargs in (("platform spline: unbiased criterion", dict(criterion="unbiased")),
                          ("platform spline: noise x2", dict(noise_factor=2.0)),
                          ("platform spline: noise x4", dict(noise_factor=4.0))):
        variant = [_refit(p.trial, **kwargs) for p in preps]
        out["rows"].append(_row(label, variant, error_table(variant, mus, _mae_coulomb), mus,
                                lambda c: f"mu_k={c[0]:.2f}"))
        say(label)

    variant = [prepare(_transformed(p.trial, "marker")) for p in preps]
    out["rows"].append(_row("z relative to marker s (frame shake)", variant,
                            error_table(variant, mus, _mae_coulomb), mus,
                            lambda c: f"mu_k={c[0]:.2f}"))
    say("marker frame")

    angles = (-15.0, -5.0, 0.0, 5.0, 15.0)
    tilted = {a: [prepare(_transformed(p.trial, "tilt", a)) for p in preps] for a in angles}
    out["rows"].append(_variant_row("camera tilt (x mixed into z)", preps, tilted,
                                    lambda c: f"{c[0]:+.0f}deg,mu_k={c[1]:.2f}"))
    say("tilt")

    soft = {f: [_compliant(p, f) for p in preps] for f in (150.0, 300.0, 600.0)}
    out["rows"].append(_variant_row("grasp compliance (low-pass f_c)", preps, soft,
                                    lambda c: f"f_c={c[0]:.0f}Hz,mu_k={c[1]:.2f}"))
    say("compliance")

    combos = list(itertools.product(MU_GRID[::2], (0.5, 0.75, 1.0, 1.25, 1.5),
                                    (0.02, 0.05, 0.1)))
    table = error_table(preps, combos, _mae_speed)
    out["rows"].append(_row("speed-dependent mu_k (two levels)", preps, table, combos,
                            lambda c: f"mu_k={c[0]:.2f},x{c[1]:g}@{c[2]:g}m/s"))
    say("speed-dependent friction")
    return out


def _print(out):
    fit, loo = out["fit"], out["loo"]
    names = list(fit.mae_mm)
    print("\nFitting protocol (shared mu_k, F_n per trial):")
    print(f"  mu_k = {fit.mu_k:.4f}")
    for n in names:
        r = fit.results[n]
        print(f"  {n}: F_n = {fit.normal_force_mg[n]:.3f} m g, MAE = {fit.mae_mm[n]:.4f} mm, "
              f"max |disp| = {r.max_displacement_mm:.3f} mm, final meas/pred = "
              f"{r.final_measured_mm:+.3f}/{r.final_predicted_mm:+.3f} mm, "
              f"stuck {r.stuck_fraction:.2f}")
    print(f"  mean MAE = {fit.mean_mae_mm:.4f} mm")
    floor = out["noise_floor"]
    print("  noise floor (tracking noise alone, fitted parameters): "
          + ", ".join(f"{n} {floor[n]:.4f}" for n in names)
          + f"; mean {np.mean(list(floor.values())):.4f} mm")
    print("\nLeave-one-out, measured F_n:")
    for n in names:
        print(f"  {n}: mu_k = {loo.mu_k[n]:.3f}, MAE = {loo.mae_mm[n]:.4f} mm")
    print(f"  mean = {loo.mean_mae_mm:.4f} mm\n")
    header = "| hypothesis | " + " | ".join(names) + " | mean |"
    print(header)
    print("|" + "---|" * (len(names) + 2))
    for row in out["rows"]:
        cells = " | ".join(f"{row['loo_mae_mm'][n]:.3f}" for n in names)
        print(f"| {row['variant']} | {cells} | {row['mean']:.3f} |")
    print()
    for row in out["rows"]:
        print(f"{row['variant']}: chosen per held-out trial: {', '.join(row['chosen'])}")


if __name__ == "__main__":
    _print(run_study())
