"""Figures of `vibrofeed validate` and `vibrofeed replay`: DEM overlaid on the model (PNG).

matplotlib is imported by the functions that draw, so importing this module
(or the cross-check) costs nothing until a figure is made.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..pictures.plots import pyplot, save

DEM_STYLE = dict(color="tab:red", lw=1.2, label="DEM (LIGGGHTS)")
MODEL_STYLE = dict(color="black", lw=1.0, ls="--", label="model")
SURFACE_STYLE = dict(color="tab:blue", lw=0.8, alpha=0.7, label="surface")
# Swept quantities that are not deck variables: their axis labels.
DERIVED_AXES = {"gamma": "Gamma_n = amp_n w^2 / g [-]", "gamma_t": "Gamma_t = amp_t w^2 / g [-]"}


def heading(case) -> str:
    """The case a figure shows: its name (as `vibrofeed validate --case` takes it) and title."""
    return f"{case.name}: {case.title}"


def axis_label(case, name: str) -> str:
    """``name [unit]`` of a swept quantity, the unit from the case's deck."""
    if name in DERIVED_AXES:
        return DERIVED_AXES[name]
    from vibrofeed.decks import Deck
    from vibrofeed.errors import VibrofeedError

    try:
        variable = Deck.find(case.deck).variables.get(name)
    except VibrofeedError:
        variable = None
    unit = variable.unit if variable is not None else ""
    return f"{name} [{unit}]" if unit else name


def _column(n: int, width: float, height: float):
    """(figure, axes) of ``n`` panels stacked, each ``height`` inches high."""
    fig, axes = pyplot().subplots(n, 1, figsize=(width, height * n), squeeze=False, layout="constrained")
    return fig, axes[:, 0]


def _finish(fig, axes, xlabel: str | None, title: str | None, path: Path, legend: dict | None = None,
             title_size: int = 10) -> Path:
    """A column's x label under its last panel, the legend in its first (``legend``: its
    options; None: each panel has its own), the title over it all; saved to ``path``."""
    if xlabel is not None:
        axes[-1].set_xlabel(xlabel)
    if legend is not None:
        axes[0].legend(**legend)
    if title is not None:
        fig.suptitle(title, fontsize=title_size)
    return save(fig, path)


def plot_flights(case, panels: list[dict], path: Path) -> Path:
    """Height of the part's lowest point and of the surface vs time, per sweep point."""
    fig, axes = _column(len(panels), 8, 2.3)
    for ax, p in zip(axes, panels):
        T, um = p["T"], 1e6
        surf = np.interp(p["dem_t"], p["surface_t"], p["surface_z"])
        ax.plot(p["surface_t"] / T, p["surface_z"] * um, **SURFACE_STYLE)
        ax.plot(p["dem_t"] / T, (p["dem_gap"] + surf) * um, **DEM_STYLE)
        ax.plot(p["model_t"] / T, (p["model_gap"] + p["surface_z"]) * um, **MODEL_STYLE)
        ax.set_ylabel("height [µm]")
        ax.set_title(p["label"], fontsize=9, loc="left")
    return _finish(fig, axes, "t / T (vibration periods) [-]", heading(case), path,
                   dict(fontsize=8, loc="upper right"))


def plot_chute(case, points, curve, helix: float, path: Path) -> Path:
    """A bowl's chute: the parts' mean speed in bins along it (DEM, the number of intervals
    by each), the sliding block between its walls (model curve, the tolerance about it), and
    the speed the helix's drive alone would give (the 1D model: no drive across)."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    cx, cv = curve
    ax.plot(np.asarray(cx) * 1e3, np.asarray(cv) * 1e3, **MODEL_STYLE)
    xs = np.array([x for x, _, _, _ in points]) * 1e3
    model = np.array([m for _, _, m, _ in points]) * 1e3
    tol = case.tolerance_of("chute_speed")
    err = tol.value * np.abs(model) if tol.kind == "rel" else np.full_like(model, tol.value * 1e3)
    ax.errorbar(xs, model, yerr=err, fmt="none", ecolor="gray", capsize=3, label="tolerance")
    ax.plot(xs, [d * 1e3 for _, _, _, d in points], "o", color=DEM_STYLE["color"], label=DEM_STYLE["label"])
    for x, n, _, d in points:
        ax.annotate(str(n), (x * 1e3, d * 1e3), textcoords="offset points", xytext=(4, 4), fontsize=7)
    ax.axhline(helix * 1e3, color="gray", ls=":", lw=1, label="the helix's drive alone (1D model)")
    ax.axhline(0, color="gray", lw=0.5)
    ax.set_xlabel("x along the chute from the slot [mm]")
    ax.set_ylabel("speed along the chute [mm/s]")
    ax.set_title(heading(case), fontsize=10)
    ax.legend(fontsize=8)
    return save(fig, path)


def plot_speed_curve(case, runs, points, axis: str, path: Path) -> Path:
    """Mean conveying speed vs the swept quantity: model curve, DEM points."""
    from ..models import deck as dm
    from ..postproc.path import bowl_of

    plt = pyplot()

    xs = np.array([float(r.values[axis]) for r, _, _ in points])
    fig, ax = plt.subplots(figsize=(6, 4))
    lo, hi = xs.min(), xs.max()
    bowl = bowl_of(points[0][0].params) is not None  # its model is the drive the helix sees: points
    if hi > lo and len(points) > 1 and not case.zip_sweep and not bowl:
        # dense model curve between the swept values, other parameters as the first run
        base = dict(points[0][0].params)
        grid = np.linspace(lo, hi, 25)
        curve = []
        for x in grid:
            p = dict(base)
            if axis in ("gamma", "gamma_t"):
                target = "amp_n" if axis == "gamma" else "amp_t"
                p[target] = repr(float(dm.amp_from_gamma(x, float(p["freq"]))))
            else:
                p[axis] = repr(float(x))
            curve.append(dm.transport(p).velocity)
        ax.plot(grid, np.array(curve) * 1e3, **MODEL_STYLE)
    else:
        ax.plot(xs, np.array([m for _, m, _ in points]) * 1e3, "kx", label="model")
    dem = np.array([d for _, _, d in points]) * 1e3
    model = np.array([m for _, m, _ in points]) * 1e3
    if "mean_speed" in case.tolerance:  # (a threshold case judges the sign, not the speed)
        tol = case.tolerance_of("mean_speed")
        err = tol.value * np.abs(model) if tol.kind == "rel" else np.full_like(model, tol.value * 1e3)
        ax.errorbar(xs, model, yerr=err, fmt="none", ecolor="gray", capsize=3, label="tolerance")
    ax.plot(xs, dem, "o", color=DEM_STYLE["color"], label=DEM_STYLE["label"])
    ax.axhline(0, color="gray", lw=0.5)
    ax.set_xlabel(axis_label(case, axis))
    ax.set_ylabel("mean speed along the track [mm/s]")
    ax.set_title(heading(case), fontsize=10)
    ax.legend(fontsize=8)
    return save(fig, path)


def plot_bifurcation(case, grid, diagram, dem_points, path: Path) -> Path:
    """Jump lengths (flight durations in periods) vs Gamma: model and DEM."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for g, jumps in zip(grid, diagram):
        ax.plot(np.full(len(jumps), g), jumps, ",", color="black")
    ax.plot([], [], ".", color="black", label="model")
    for g, jumps in dem_points:
        ax.plot(np.full(len(jumps), g), jumps, "o", mfc="none", color=DEM_STYLE["color"], ms=5)
    ax.plot([], [], "o", mfc="none", color=DEM_STYLE["color"], label=DEM_STYLE["label"])
    ax.set_xlabel(DERIVED_AXES["gamma"])
    ax.set_ylabel("jump length [periods]")
    ax.set_title(heading(case), fontsize=10)
    ax.legend(fontsize=8)
    return save(fig, path)


def plot_vertical(case, panels: list[dict], path: Path) -> Path:
    """Part displacement up the wall vs time: DEM, model and the wall itself."""
    fig, axes = _column(len(panels), 8, 2.5)
    for ax, p in zip(axes, panels):
        T = p["T"]
        ax.plot(p["dem_t"] / T, p["surface_x"] * 1e3, **SURFACE_STYLE)
        ax.plot(p["dem_t"] / T, p["dem_x"] * 1e3, **DEM_STYLE)
        ax.plot(p["model_t"] / T, p["model_x"] * 1e3, **MODEL_STYLE)
        ax.set_ylabel("up the wall [mm]")
        ax.set_title(p["label"], fontsize=9, loc="left")
    return _finish(fig, axes, "t / T (vibration periods) [-]", heading(case), path, dict(fontsize=8))


def plot_replay(results, path, engine: str = "model") -> Path:
    """Measured and predicted part position, and the platform, per trial."""
    fig, axes = _column(len(results), 8, 2.8)
    for ax, r in zip(axes, results):
        ax.plot(r.t, r.platform_mm, **{**SURFACE_STYLE, "label": "platform"})
        ax.plot(r.t, r.measured_mm, color="black", lw=1.2, label="part, measured")
        ax.plot(r.t, r.predicted_mm, color=DEM_STYLE["color"], lw=1.2, ls="--",
                label=f"part, predicted ({engine})")
        ax.set_ylabel("vertical displacement [mm]")
        ax.set_title(f"{r.name}: F_n = {r.normal_force:.3g} N, mu_k = {r.mu_k:.3g}; "
                     f"mean abs error {r.mean_abs_error_mm:.3f} mm", fontsize=9, loc="left")
    return _finish(fig, axes, "t [s]", None, Path(path), dict(fontsize=8))


def plot_pulloff(case, panels: list[dict], path: Path) -> Path:
    """Tension on the pulled sphere against time, with JKR's pull-off, per run."""
    fig, axes = _column(len(panels), 7, 2.4)
    for ax, p in zip(axes, panels):
        ax.plot(p["t"], 1e6 * p["tension"], **DEM_STYLE)
        ax.axhline(1e6 * p["model"], **{**MODEL_STYLE, "label": "JKR 1.5 pi gamma R*"})
        ax.set_ylim(-0.5e6 * p["model"], 1.3e6 * p["model"])  # the pull-off, not the initial push
        ax.set_ylabel("tension [µN]")
        ax.set_title(p["label"], fontsize=9, loc="left")
        ax.legend(fontsize=8)
    return _finish(fig, axes, "time [s]", heading(case), path)


def plot_reference(case, runs, figures: dict, ref, quantities: dict, path: Path) -> Path:
    """Each compared quantity vs the first swept parameter: DEM points with
    their 1-sigma errors, the reference point's value and its tolerance band
    (the band uses the reference's own error: each point's limit also
    includes its own, see the table). ``quantities``: name -> (key of its error, unit)."""
    plt = pyplot()
    axis = next(iter(case.sweep))
    names = list(case.tolerance)
    fig, axes = plt.subplots(1, len(names), figsize=(5 * len(names), 3.8), squeeze=False,
                             layout="constrained")
    xs = np.array([float(r.values[axis]) for r in runs])
    for ax, q in zip(axes[0], names):
        err_key, unit = quantities[q]
        scale, unit = (1e3, "mm/s") if unit == "m/s" else (1.0, unit)
        ys = np.array([figures[r.label][q] for r in runs]) * scale
        es = np.array([figures[r.label][err_key] for r in runs]) * scale
        y0, e0 = figures[ref.label][q] * scale, figures[ref.label][err_key] * scale
        k = case.tolerance_of(q).value
        ax.axhspan(y0 - k * e0, y0 + k * e0, color="gray", alpha=0.2,
                   label=f"reference ± {k:g} sigma")
        ax.axhline(y0, color="black", lw=0.8, ls="--")
        ax.errorbar(xs, ys, yerr=es, fmt="o", color=DEM_STYLE["color"], capsize=3,
                    label="DEM ± 1 sigma (batch means)")
        if xs.min() > 0 and xs.max() / xs.min() > 10:
            ax.set_xscale("log")
        ax.set_xlabel(axis_label(case, axis))
        ax.set_ylabel(f"{q.replace('_', ' ')} [{unit}]")
        ax.legend(fontsize=8)
    fig.suptitle(heading(case), fontsize=10)
    return save(fig, path)


# ----------------------------------------------------------------- the micro-scale kinds
def plot_vdw_pulloff(case, panels: list[dict], path: Path) -> Path:
    """Van der Waals pull-off per run: the model's and the DEM's at its lift-off."""
    fig, (ax,) = _column(1, 6, 3.6)
    x = np.arange(len(panels))
    ax.plot(x, [1e6 * q["model"] for q in panels], "s", mfc="none", **MODEL_STYLE)
    ax.plot(x, [1e6 * q["dem"] for q in panels], "o", **{**DEM_STYLE, "lw": 0})
    ax.set_xticks(x, [q["label"] for q in panels], rotation=20, fontsize=7)
    ax.set_ylabel("pull-off [µN]")
    return _finish(fig, [ax], None, heading(case), path, dict(fontsize=8), title_size=9)


def plot_sticking(case, points: list[dict], path: Path) -> Path:
    """Each run's Gamma against the Hamaker constant, left or stayed, under the model's Gamma_c."""
    fig, (ax,) = _column(1, 6, 3.6)
    a = sorted({q["hamaker"] for q in points})
    line = {q["hamaker"]: q["gamma_c"] for q in points}
    ax.plot(a, [line[h] for h in a], "k--", lw=1, label="model: Gamma_c = 1 + F_pulloff / (m g)")
    for left, style in ((True, dict(marker="^", color="tab:red", label="DEM: leaves")),
                        (False, dict(marker="v", color="tab:blue", label="DEM: stays"))):
        sel = [q for q in points if q["left"] == left]
        if sel:
            ax.plot([q["hamaker"] for q in sel], [q["gamma"] for q in sel], ls="none", **style)
    ax.set_ylabel("Gamma = a w^2 / g")
    return _finish(fig, [ax], "Hamaker constant [J]", heading(case), path, dict(fontsize=8), title_size=9)


def plot_launch(case, panels: list[dict], path: Path) -> Path:
    """The gap over the flight after lift-off through the air film: DEM and the §3.2 ODE."""
    fig, axes = _column(len(panels), 7, 2.3)
    for ax, q in zip(axes, panels):
        T = 1.0 / q["freq"]
        ax.plot(q["dem_t"] / T, 1e6 * q["dem_gap"], **DEM_STYLE)
        ax.plot(q["model_t"] / T, 1e6 * q["model_gap"], **{**MODEL_STYLE, "label": "ODE of §3.2"})
        ax.set_ylabel("gap [um]")
        ax.set_title(q["label"], fontsize=9, loc="left")
    return _finish(fig, axes, "(t - t_lift-off) / T", heading(case), path, dict(fontsize=8), title_size=9)


# ----------------------------------------------------------------- feeder lines
def plot_line_speeds(case, panels: list[dict], path: Path) -> Path:
    """Per run, the whole-period speed of every part interval against where it was along the
    line; each section's model speed over its length and the stretch measured (shaded)."""
    fig, axes = _column(len(panels), 8, 2.6)
    for ax, q in zip(axes, panels):
        ax.plot(q["x"] * 1e3, q["v"] * 1e3, ".", ms=3, color=DEM_STYLE["color"],
                label="DEM: a part over one interval")
        for k, ((lo, hi), (a, b), model, dem) in enumerate(zip(q["bounds"], q["stretches"], q["model"],
                                                                q["dem"])):
            ax.axvspan(a * 1e3, b * 1e3, color="gray", alpha=0.15,
                       label="measured stretch" if k == 0 else None)
            ax.hlines(model * 1e3, lo * 1e3, hi * 1e3, colors="black", linestyles="--", lw=1,
                      label="model of the section's drive" if k == 0 else None)
            ax.text(0.5 * (lo + hi) * 1e3, model * 1e3, f"s{k + 1}: DEM {dem * 1e3:.3g}, "
                    f"model {model * 1e3:.3g} mm/s", ha="center", va="bottom", fontsize=7)
        ax.axvline(q["bounds"][1][0] * 1e3, color="tab:blue", lw=0.8)
        ax.set_ylabel("speed [mm/s]")
        ax.set_title(q["label"], fontsize=9, loc="left")
    return _finish(fig, axes, "x along the line [mm] (joint: blue)", heading(case), path,
                   dict(fontsize=7, loc="upper left"), title_size=9)


def plot_line_continuity(case, panels: list[dict], path: Path) -> Path:
    """Per run, the fluxes through the joint and the outlet and each section's rho v (Little's
    law), with their 1-sigma errors, against the inlet's rate (its band: 1 sigma)."""
    fig, axes = _column(len(panels), 6, 2.4)
    names = ["J1 joint", "J2 outlet", "rho1 v1", "rho2 v2"]
    for ax, q in zip(axes, panels):
        values = [*q["fluxes"], *q["flows"]]
        ax.errorbar(range(4), [v for v, _ in values], yerr=[e for _, e in values], fmt="o",
                    color=DEM_STYLE["color"], capsize=3, label="DEM ± 1 sigma")
        feed, err = q["feed"]
        ax.axhspan(feed - err, feed + err, color="gray", alpha=0.2)
        ax.axhline(feed, color="black", lw=0.8, ls="--", label="inlet")
        ax.set_xticks(range(4), names, fontsize=8)
        ax.set_ylabel("parts/s")
        ax.set_title(f"{q['label']}: window {q['window'][0]:.2f} .. {q['window'][1]:.2f} s",
                     fontsize=9, loc="left")
    return _finish(fig, axes, None, heading(case), path, dict(fontsize=7), title_size=9)
