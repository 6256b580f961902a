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

The feeding study (issue 12, README "Micro-scale forces in the feeder"): the
figure of the two bulk sweeps sweeps/adhesion.toml and sweeps/squeeze_film.toml,
``python -m vibrofeed.validation.micro_checks ADHESION_DIR SQUEEZE_DIR -o FIG.png``
(:func:`feeding_figure`; feed rate and conveying speed against the Bond number
of the adhesion, and against the frequency with and without the air film).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import CaseError
from . import deck_models as dm
from .models.constants import G


def _adhesion(p):
    from .models.adhesion import Adhesion

    return Adhesion(float(p["hamaker"]), float(p["roughness"]), radius=float(p["radius"]),
                    face_radius=float(p.get("face_radius", 0.0)))


def _film(p):
    from .models.squeeze_film import Film, clearance

    face = float(p.get("face_radius", 0.0))
    return Film(float(p["air_viscosity"]), face if face > 0 else float(p["radius"]),
                clearance(float(p["roughness"])), flat=face > 0, free_flow=True)


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

    from .crosscheck import _row

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
        model = _adhesion(p).pulloff
        out.rows.append(_row(case, "pulloff", run.label, model, dem, "N"))
        panels.append({"label": run.label, "hamaker": run.number("hamaker"), "model": model, "dem": dem})
    out.figures.append(_plot_pulloff(case, panels, fig_dir / "pulloff.png"))


# ----------------------------------------------------------------- kind: sticking
def sticking(case, runs, out, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result

    from .crosscheck import _row
    from .models.adhesion import sticking_gamma

    leave_gap = float(case.compare.get("leave_gap", 1e-7))
    points = []
    for run in runs:
        _require_flat_plate(case, run)
        p = run.params
        gamma = dm.gamma_from_amp(run.number("amp_n"), run.number("freq"))
        gamma_c = sticking_gamma(_adhesion(p), dm.mass(p))
        with Result(run.output) as r:
            tr = _trajectory(r)
        left = float(tr["gap"].max() > leave_gap)
        model = float(gamma > gamma_c)
        out.rows.append(_row(case, "leaves", run.label, model, left))
        points.append({"hamaker": run.number("hamaker"), "gamma": gamma, "gamma_c": gamma_c,
                       "left": bool(left), "max_gap": float(tr["gap"].max())})
    out.figures.append(_plot_sticking(case, points, fig_dir / "sticking.png"))


# ----------------------------------------------------------------- kind: squeeze_launch
def squeeze_launch(case, runs, out, fig_dir: Path) -> None:
    from vibrofeed.results.reader import Result

    from .crosscheck import _row
    from .models.squeeze_film import launch

    panels = []
    for run in runs:
        _require_flat_plate(case, run)
        p = run.params
        if run.number("hamaker") != 0 or run.number("air_viscosity") <= 0:
            raise CaseError(f"case {case.name} [{run.label}]: needs air_viscosity > 0 and hamaker = 0")
        freq, mass, film = run.number("freq"), dm.mass(p), _film(p)
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
        out.rows.append(_row(case, "deficit", run.label, model.final_deficit, dem_deficit, "m/s"))
        out.rows.append(_row(case, "max_gap", run.label, model.max_gap, tr["gap"][k], "m"))
        panels.append({"label": run.label, "dem_t": tr["t"][flight] - t_l, "dem_gap": tr["gap"][flight],
                       "model_t": model.t, "model_gap": model.gap, "freq": freq})
    out.figures.append(_plot_launch(case, panels, fig_dir / "launch.png"))


# ----------------------------------------------------------------- figures
def _plot_pulloff(case, panels, path: Path) -> Path:
    from vibrofeed.pictures.plots import pyplot, save

    from .plots import DEM_STYLE, MODEL_STYLE

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    x = np.arange(len(panels))
    ax.plot(x, [1e6 * q["model"] for q in panels], "s", mfc="none", **MODEL_STYLE)
    ax.plot(x, [1e6 * q["dem"] for q in panels], "o", **{**DEM_STYLE, "lw": 0})
    ax.set_xticks(x, [q["label"] for q in panels], rotation=20, fontsize=7)
    ax.set_ylabel("pull-off [uN]")
    ax.legend(fontsize=8)
    fig.suptitle(case.title, fontsize=9)
    return save(fig, path)


def _plot_sticking(case, points, path: Path) -> Path:
    from vibrofeed.pictures.plots import pyplot, save

    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 3.6), layout="constrained")
    a = sorted({q["hamaker"] for q in points})
    line = {q["hamaker"]: q["gamma_c"] for q in points}
    ax.plot(a, [line[h] for h in a], "k--", lw=1, label="model: Gamma_c = 1 + F_pulloff / (m g)")
    for left, style in ((True, dict(marker="^", color="tab:red", label="DEM: leaves")),
                        (False, dict(marker="v", color="tab:blue", label="DEM: stays"))):
        sel = [q for q in points if q["left"] == left]
        if sel:
            ax.plot([q["hamaker"] for q in sel], [q["gamma"] for q in sel], ls="none", **style)
    ax.set_xlabel("Hamaker constant [J]")
    ax.set_ylabel("Gamma = a w^2 / g")
    ax.legend(fontsize=8)
    fig.suptitle(case.title, fontsize=9)
    return save(fig, path)


def _plot_launch(case, panels, path: Path) -> Path:
    from vibrofeed.pictures.plots import pyplot, save

    from .plots import DEM_STYLE, MODEL_STYLE

    plt = pyplot()
    fig, axes = plt.subplots(len(panels), 1, figsize=(7, 2.3 * len(panels)), squeeze=False,
                             layout="constrained")
    for ax, q in zip(axes[:, 0], panels):
        T = 1.0 / q["freq"]
        ax.plot(q["dem_t"] / T, 1e6 * q["dem_gap"], **DEM_STYLE)
        ax.plot(q["model_t"] / T, 1e6 * q["model_gap"], **{**MODEL_STYLE, "label": "ODE of §3.2"})
        ax.set_ylabel("gap [um]")
        ax.set_title(q["label"], fontsize=9, loc="left")
    axes[-1, 0].set_xlabel("(t - t_lift-off) / T")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle(case.title, fontsize=9)
    return save(fig, path)


#: The kinds of this module, merged into ``crosscheck.KINDS``.
KINDS = {"vdw_pulloff": vdw_pulloff, "sticking": sticking, "squeeze_launch": squeeze_launch}


# ------------------------------------------------------------------ the feeding study
def bond_number(p: dict) -> float:
    """Pull-off over weight of a bulk_feeder part (parameters ``p``, deck defaults
    for the rest): A R / (6 s^2) for a sphere, A S / (6 pi s^3) over a chip's or
    disc's face S (models/adhesion.py), over m g."""
    from .models.adhesion import Adhesion

    size, thick, rho = float(p.get("part_size", 3e-4)), float(p.get("part_thickness", 1.5e-4)), \
        float(p.get("density", 2330.0))
    shape = {"sphere": 0, "chip": 1, "disc": 2}.get(str(p.get("shape", 0)), None)
    shape = int(float(p.get("shape", 0))) if shape is None else shape
    hamaker, roughness = float(p.get("hamaker", 0.0)), float(p.get("roughness", 0.0))
    if shape == 0:
        adh, mass = Adhesion(hamaker, roughness, radius=size / 2), np.pi / 6 * size ** 3 * rho
    elif shape == 1:
        adh, mass = Adhesion(hamaker, roughness, face_side=size), size ** 2 * thick * rho
    else:
        adh, mass = Adhesion(hamaker, roughness, face_radius=size / 2), np.pi / 4 * size ** 2 * thick * rho
    return adh.pulloff / (mass * G) if hamaker > 0 else 0.0


#: The feeding study's analysis window [s]: from 5 periods at 100 Hz (the start-up) to
#: the end of the run. One window for every job, not each run's detected steady window:
#: a pre-filled track drains, and a window that moves between runs moves the rate with
#: it (by up to 40 % between otherwise equal runs of the sphere variant).
STUDY_START = 0.05


def _settings(folder, start: float = STUDY_START) -> list[dict]:
    """The finished settings of a sweep (``vibrofeed sweep-report``'s grouping: the mean over
    the replicates with its standard error, one run: its batch-means error), each job's
    figures taken over [start, t_end] instead of its detected steady window: feed rate and
    conveying speed (postproc.feedrate), doubles and singulated fraction at the outlet and
    the fraction of parts alone on the track (postproc.singulation). ``parameters`` holds
    the fixed ones too, ``deck_parameters`` one job's resolved deck parameters."""
    import json

    from vibrofeed.postproc.feedrate import FeedRate
    from vibrofeed.postproc.singulation import Singulation
    from vibrofeed.results.reader import Result
    from vibrofeed.sweep import report

    folder = Path(folder)
    rows, meta = report.load(folder)
    done = [r for r in rows if r["status"] == "done"]
    if not done:
        raise CaseError(f"{folder}: no finished job in the sweep's summary")
    deck_parameters = {}
    for row in done:
        with Result(folder / row["file"]) as result:
            window = {"start": start, "end": float(result.time[-1])}
            fr = FeedRate(result, **window).run().results
            sg = Singulation(result, **window).run().results
            deck_parameters[row["job"]] = dict(result.parameters)
        figures = {**{k: fr[k] for k in STUDY_FEEDRATE}, **{k: sg[k] for k in STUDY_SINGULATION}}
        row.update({k: (float(v) if v == v else None) for k, v in figures.items()})  # NaN: None
        for k in STUDY_SINGULATION:  # one run's figure has no error of its own
            row[k + "_err"] = None
    varied = [p for p in meta["varied"] if p != "seed"]
    fixed = json.loads((folder / "sweep.json").read_text())["spec"].get("fixed", {})
    entries = report.settings(done, varied, "parts_per_s")
    for e in entries:
        k = "track_singulated_fraction"  # not a sweep-report figure
        e[k], e[k + "_err"] = report.mean_err([r[k] for r in done if r["job"] in e["jobs"]], [])
        e["parameters"] = {**fixed, **e["parameters"]}
        e["deck_parameters"] = deck_parameters[e["jobs"][0]]
        e["runs"] = e["done"]
    return entries


#: The figures the study takes over its window (each with a ``_err`` from the analysis).
STUDY_FEEDRATE = ("parts_per_s", "parts_per_s_err", "mean_velocity", "mean_velocity_err")
STUDY_SINGULATION = ("doubles_rate", "singulated_fraction", "track_singulated_fraction")


def _number(p: dict, name: str, default: float) -> float:
    value = p.get(name)
    return default if value in (None, "") else float(value)


def _gamma_n(p: dict) -> float:
    return _number(p, "amp_n", 5e-5) * (2 * np.pi * _number(p, "freq", 100.0)) ** 2 / G


def _errorbars(ax, x, entries, name, scale, label):
    y = [scale * e[name] if e[name] is not None else np.nan for e in entries]
    err = [scale * (e[name + "_err"] or 0.0) for e in entries]
    ax.errorbar(x, y, err, marker="o", capsize=3, label=label)


FIGURE_PANELS = (("parts_per_s", 1.0, "feed rate [parts/s]"),
                 ("mean_velocity", 1e3, "conveying speed [mm/s]"),
                 ("track_singulated_fraction", 100.0, "parts alone on the track [%]"))


def sticky_model_speed(p: dict, bond: float) -> float | None:
    """The single-part model's conveying speed [m/s] (Khan & Sarma, §2.3.2, as
    ``vibrofeed feedrate``'s dilute limit) of a part held to the track by a
    constant pull-off of ``bond`` times its weight, for deck parameters ``p``:
    while it never leaves the track (peak normal acceleration below g (1 + Bo)),
    the pull-off is exactly a heavier gravity, g (1 + Bo). None when it would
    hop (the vdW force then falls off in flight, which that model lacks)."""
    from .models.part_on_surface import PartParams, mean_velocity

    a_n = float(p["amp_n"]) * (2 * np.pi * float(p["freq"])) ** 2  # the sine's peak (waveform 0)
    if int(float(p.get("waveform", 0))) != 0 or a_n >= G * (1 + bond):
        return None
    motion = dm.waveform(p)
    mu = float(p["mu"])
    part = PartParams(mu_s=mu, mu_k=mu, e=min(float(p["restitution"]), 0.999))
    state = mean_velocity(motion, part, incline=float(p.get("incline", 0.0)), g=G * (1 + bond))
    return float(state.velocity)


def _mode(p: dict) -> str:
    gamma = round(_gamma_n(p), 1)
    return f"{'hopping' if gamma > 1 else 'in-plane'}, Gamma_n {gamma:g}"


def _film_label(p: dict) -> str:
    if _number(p, "air_viscosity", 0.0) <= 0:
        return "no air film"
    return f"air, clearance {1e6 * max(_number(p, 'roughness', 0.0), 6.8e-8):g} um"


def _films(study: dict) -> list[tuple[str, list[dict]]]:
    """The squeeze sweep's lines: no air film first, then the clearances from wide to narrow."""
    def clearance(item):
        entries = item[1]
        air = _number(entries[0]["parameters"], "air_viscosity", 0.0) > 0
        return (air, -_number(entries[0]["parameters"], "roughness", 0.0))
    return sorted(study["squeeze"].items(), key=clearance)


def _versus_free(study: dict, e: dict) -> tuple[float, float] | None:
    """``e``'s conveying speed over that without the air film at its frequency, with the
    ratio's standard error (the two errors combined), or None without that setting."""
    free = dict(_films(study)).get("no air film", [])
    ref = next((f for f in free if f["freq"] == e["freq"]), None)
    if ref is None or not ref["mean_velocity"]:
        return None
    ratio = e["mean_velocity"] / ref["mean_velocity"]
    rel = math.hypot((e["mean_velocity_err"] or 0.0) / e["mean_velocity"],
                     (ref["mean_velocity_err"] or 0.0) / ref["mean_velocity"])
    return ratio, ratio * rel


def feeding_study(adhesion_dir, squeeze_dir) -> dict:
    """The two sweeps' settings (:func:`_settings`), grouped: ``adhesion`` mode -> settings
    by Bond number, ``squeeze`` film -> settings by frequency."""
    study: dict = {"adhesion": {}, "squeeze": {}}
    for e in _settings(adhesion_dir):
        e["bond"] = bond_number(e["parameters"])
        e["model"] = sticky_model_speed(e["deck_parameters"], e["bond"])
        study["adhesion"].setdefault(_mode(e["parameters"]), []).append(e)
    for e in _settings(squeeze_dir):
        e["freq"] = _number(e["parameters"], "freq", 100.0)
        study["squeeze"].setdefault(_film_label(e["parameters"]), []).append(e)
    for group, key in (("adhesion", "bond"), ("squeeze", "freq")):
        for entries in study[group].values():
            entries.sort(key=lambda e: e[key])
    return study


def _relative(entries, e, name="mean_velocity") -> str:
    """``e``'s figure over that of the first setting of its line (no adhesion / no film)."""
    ref = entries[0][name]
    return f"{e[name] / ref:5.2f}" if ref else "  n/a"


def _fraction(value) -> str:
    return "  n/a" if value is None else f"{100 * value:4.0f} %"


def study_text(study: dict) -> str:
    """The study's table: one line per setting, mean ± standard error over the replicates."""
    lines = ["adhesion: mode, A [J], roughness [m], Bo, runs, feed rate [parts/s], conveying [mm/s], "
             "conveying / Bo 0, one part never leaving [mm/s], singulated at the outlet, alone on the track"]
    for mode, entries in sorted(study["adhesion"].items()):
        for e in entries:
            p = e["parameters"]
            hamaker, roughness = _number(p, "hamaker", 0.0), _number(p, "roughness", 0.0)
            lines.append(f"  {mode:20s} {hamaker:7.2g} {roughness:7.2g} {e['bond']:6.3g} {e['runs']:3d}  "
                         f"{e['parts_per_s']:6.1f} ± {e['parts_per_s_err']:4.1f}  "
                         f"{1e3 * e['mean_velocity']:6.2f} ± {1e3 * e['mean_velocity_err']:4.2f}  "
                         f"{_relative(entries, e)}  "
                         + ("   n/a" if e["model"] is None else f"{1e3 * e['model']:6.2f}")
                         + f"  {_fraction(e['singulated_fraction'])}  "
                         f"{_fraction(e['track_singulated_fraction'])}")
    lines.append("squeeze film: air film, freq [Hz], runs, feed rate [parts/s], conveying [mm/s], "
                 "conveying / no film")
    for film, entries in _films(study):
        for e in entries:
            versus = _versus_free(study, e)
            lines.append(f"  {film:26s} {e['freq']:5g} {e['runs']:3d}  {e['parts_per_s']:6.1f} ± "
                         f"{e['parts_per_s_err']:4.1f}  {1e3 * e['mean_velocity']:6.2f} ± "
                         f"{1e3 * e['mean_velocity_err']:4.2f}  "
                         + ("  n/a" if versus is None else f"{versus[0]:5.2f} ± {versus[1]:4.2f}"))
    return "\n".join(lines)


def feeding_figure(study: dict, path) -> Path:
    """Six panels: feed rate, conveying speed and the fraction of parts alone on
    the track (mean over the replicates, with its standard error) against the
    Bond number, one line per mode (Gamma_n), from the adhesion sweep; and
    against the frequency, one line per air-film setting, from the squeeze-film
    sweep (there the conveying speed over that without the film)."""
    from vibrofeed.pictures.plots import pyplot, save

    plt = pyplot()
    fig, axes = plt.subplots(2, 3, figsize=(13, 6.4), layout="constrained")
    for mode, sel in sorted(study["adhesion"].items()):
        for ax, (name, scale, _) in zip(axes[0], FIGURE_PANELS):
            _errorbars(ax, [e["bond"] for e in sel], sel, name, scale, mode)
        model = [(e["bond"], e["model"]) for e in sel if e["model"] is not None]
        if model:
            color = axes[0, 1].lines[-1].get_color()
            axes[0, 1].plot([b for b, _ in model], [1e3 * v for _, v in model], ls=":", color=color,
                            label=f"one part, never leaving: g (1 + Bo) ({mode.split(',')[0]})")
    for ax in axes[0]:
        ax.set_xscale("symlog", linthresh=0.1)
        ax.set_xlabel("Bond number: vdW pull-off / weight")
    bottom = (FIGURE_PANELS[0], ("versus_free", 1.0, "conveying speed / without the air film"),
              FIGURE_PANELS[2])
    for film, sel in _films(study):
        for e in sel:
            e["versus_free"], e["versus_free_err"] = _versus_free(study, e) or (None, None)
        for ax, (name, scale, _) in zip(axes[1], bottom):
            _errorbars(ax, [e["freq"] for e in sel], sel, name, scale, film)
    axes[1, 1].axhline(1.0, color="k", lw=0.8)
    for ax in axes[1]:
        ax.set_xscale("log")
        ax.set_xticks([50, 100, 200, 400], ["50", "100", "200", "400"])
        ax.minorticks_off()
        ax.set_xlabel("frequency [Hz] (Gamma_n = Gamma_t = 2)")
    for ax, (_, _, ylabel) in zip(axes[1], bottom):
        ax.set_ylabel(ylabel)
    for ax, (_, _, ylabel) in zip(axes[0], FIGURE_PANELS):
        ax.set_ylabel(ylabel)
    for ax in axes.flat:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    axes[0, 0].set_title("van der Waals adhesion (sweeps/adhesion.toml)", fontsize=9, loc="left")
    axes[1, 0].set_title("squeeze-film air damping (sweeps/squeeze_film.toml)", fontsize=9, loc="left")
    return save(fig, path)


def main(argv=None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="python -m vibrofeed.validation.micro_checks",
                                     description="The figure of the feeding study (README, "
                                     "'Micro-scale forces in the feeder') from its two sweep folders.")
    parser.add_argument("adhesion_dir")
    parser.add_argument("squeeze_dir")
    parser.add_argument("-o", "--output", default="micro_feeding.png")
    args = parser.parse_args(argv)
    study = feeding_study(args.adhesion_dir, args.squeeze_dir)
    print(study_text(study))
    print(feeding_figure(study, args.output))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
