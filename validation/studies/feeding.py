"""The feeding study (issue 12, README "Micro-scale forces in the feeder").

The figure of the two bulk sweeps sweeps/adhesion.toml and sweeps/squeeze_film.toml,
``python -m vibrofeed.validation.studies.feeding ADHESION_DIR SQUEEZE_DIR -o FIG.png``
(:func:`feeding_figure`; feed rate and conveying speed against the Bond number
of the adhesion, and against the frequency with and without the air film).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ...errors import CaseError
from ...models import deck as dm
from ...models.constants import G


def bond_number(p: dict) -> float:
    """Pull-off over weight of a bulk_feeder part (parameters ``p``, deck defaults
    for the rest): A R / (6 s^2) for a sphere, A S / (6 pi s^3) over a chip's or
    disc's face S (models/adhesion.py), over m g."""
    shape = {"sphere": 0, "chip": 1, "disc": 2}.get(str(p.get("shape", 0)), None)
    shape = int(float(p.get("shape", 0))) if shape is None else shape
    defaults = {"part_size": 3e-4, "part_thickness": 1.5e-4, "density": 2330.0, "hamaker": 0.0,
                "roughness": 0.0}
    part = {"shape": min(shape, 2), **{name: float(p.get(name, value)) for name, value in defaults.items()}}
    return dm.adhesion(part).pulloff / (dm.mass(part) * G) if part["hamaker"] > 0 else 0.0


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
    from vibrofeed.values import to_json

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
        row.update(to_json(figures))  # NaN: None
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
    return dm.gamma_from_amp(_number(p, "amp_n", 5e-5), _number(p, "freq", 100.0))


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
    a_n = float(p["amp_n"]) * (2 * np.pi * float(p["freq"])) ** 2  # the sine's peak (waveform 0)
    if int(float(p.get("waveform", 0))) != 0 or a_n >= G * (1 + bond):
        return None
    return float(dm.transport(p, g=G * (1 + bond)).velocity)


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

    parser = argparse.ArgumentParser(prog="python -m vibrofeed.validation.studies.feeding",
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
