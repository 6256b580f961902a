"""Plots (matplotlib, PNG) of the analyses' results, and writing any figure.

:func:`pyplot` and :func:`save` are the one way the package and the validation
figures draw and write; :func:`feedrate_figures` and :func:`singulation_figures`
draw what ``vibrofeed feedrate --plot`` and ``vibrofeed singulation --plot``
write. Every plot names the run it shows (:func:`.caption.run_caption`).
matplotlib is imported by the functions that draw, so importing this module
costs nothing until a figure is made.
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import numpy as np

from .caption import run_caption

# Velocity-profile bins holding fewer than this fraction of the median non-empty bin's
# samples are drawn light: their mean rests on few parts.
THIN_BIN = 0.25
# Characters of a figure's run caption per inch of the figure's width (7-point text).
CAPTION_PER_INCH = 20


def pyplot():
    """matplotlib.pyplot on the file-only backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, path) -> Path:
    """Write ``fig`` to ``path`` (PNG; its folder created if missing), close it, return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120, bbox_inches="tight")
    pyplot().close(fig)
    return path


def name_run(fig, text: str) -> None:
    """Head ``fig`` with ``text`` (which run or sweep it shows), wrapped to the figure."""
    width = int(CAPTION_PER_INCH * fig.get_figwidth())
    fig.suptitle("\n".join(textwrap.wrap(text, width)), fontsize=7, color="0.25")


def thin_bins(count) -> np.ndarray:
    """(bins,) True where a bin holds fewer than ``THIN_BIN`` x the median count of the
    non-empty bins (and at least one sample)."""
    count = np.asarray(count)
    full = count[count > 0]
    if len(full) == 0:
        return np.zeros(len(count), dtype=bool)
    return (count > 0) & (count < THIN_BIN * float(np.median(full)))


def feedrate_figures(analysis, folder) -> list[Path]:
    """Cumulative exits with the steady window and the fitted rate, and the velocity
    profile along the track with its batch-means errors: two PNGs in ``folder``."""
    plt = pyplot()
    r, caption = analysis.results, run_caption(analysis.result)
    out = []
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    t = np.concatenate([[analysis.times[0]], r.event_times])
    n = np.arange(len(t))
    ax.step(t, n, where="post", color="tab:blue", lw=1.2, label="parts exited (outlet events)")
    ax.axvspan(r.steady_from, r.steady_to, color="tab:green", alpha=0.12,
               label=f"steady window {r.steady_from:.3g} .. {r.steady_to:.3g} s")
    n_a = np.searchsorted(r.event_times, r.steady_from, side="left")
    tt = np.array([r.steady_from, r.steady_to])
    ax.plot(tt, n_a + r.parts_per_s * (tt - r.steady_from), "k--", lw=1.0,
            label=f"feed rate {r.parts_per_s:.4g} ± {r.parts_per_s_err:.2g} parts/s (1 sigma)")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("parts exited (cumulative) [-]")
    ax.legend(loc="upper left", fontsize=8)
    name_run(fig, caption)
    out.append(save(fig, Path(folder) / "feedrate_cumulative.png"))

    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    x, v = r.profile_x * 1e3, r.profile_velocity * 1e3
    err = np.nan_to_num(r.profile_velocity_err * 1e3, nan=0.0)
    thin = thin_bins(r.profile_count)
    full = (r.profile_count > 0) & ~thin
    ax.plot(x, v, color="tab:red", lw=0.6, alpha=0.4)  # guide for the eye through every bin
    ax.errorbar(x[full], v[full], yerr=err[full], fmt="o", color="tab:red", ms=4, capsize=3, lw=1.2,
                label="bin mean ± 1 sigma (batch means)")
    if thin.any():
        ax.errorbar(x[thin], v[thin], yerr=err[thin], fmt="o", color="tab:red", mfc="none", ms=4,
                    capsize=2, lw=0.6, alpha=0.45,
                    label=f"bin with < {THIN_BIN:.0%} of the median samples")
        for xi, vi, c in zip(x[thin], v[thin], r.profile_count[thin]):
            ax.annotate(f"n={c}", (xi, vi), textcoords="offset points", xytext=(0, 7), ha="center",
                        fontsize=6, color="0.4")
    ax.axhline(r.mean_velocity * 1e3, color="k", ls="--", lw=1.0,
               label=f"mean {r.mean_velocity * 1e3:.3g} ± {r.mean_velocity_err * 1e3:.2g} mm/s")
    if r.get("profile_height") is not None:  # a bowl: along the helix, then the chute
        from ..postproc.path import bowl_of

        b = bowl_of(analysis.result.parameters)
        sin_a = np.sin(np.radians(b.helix_angle))
        ax.set_xlabel(f"position along the helix and the chute s [mm] (the helix ends at "
                      f"{b.length * 1e3:.3g})")
        # height_at(s) = z_start + s sin(helix angle): linear, inverted here [mm]
        top = ax.secondary_xaxis("top", functions=(lambda s: b.height_at(s * 1e-3) * 1e3,
                                                   lambda z: (z * 1e-3 - b.z_start) / sin_a * 1e3))
        top.set_xlabel("height of the track's centre line [mm]")
    else:
        ax.set_xlabel("position along the track x [mm]")
    ax.set_ylabel("conveying velocity [mm/s]")
    ax.set_title(f"whole-period displacements, {r.steady_from:.3g} .. {r.steady_to:.3g} s; "
                 f"{int(r.profile_count.sum())} samples in {len(x)} bins", fontsize=8)
    ax.legend(fontsize=8)
    name_run(fig, caption)
    out.append(save(fig, Path(folder) / "feedrate_velocity_profile.png"))
    return out


def singulation_figures(analysis, folder) -> list[Path]:
    """Inter-arrival histogram against random arrivals, and the cluster-size
    distribution on a log scale: two PNGs in ``folder``."""
    plt = pyplot()
    r, caption = analysis.results, run_caption(analysis.result)
    out = []
    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    if len(r.interarrival):
        _, edges, _ = ax.hist(r.interarrival * 1e3, bins="auto", color="tab:blue", alpha=0.8,
                              label="arrivals at the outlet")
        # what random (Poisson) arrivals at the same rate would give: exponential times
        mean = r.mean_interarrival * 1e3
        expected = len(r.interarrival) * -np.diff(np.exp(-edges / mean))
        ax.step(edges, np.r_[expected, expected[-1]], where="post", color="k", ls="--", lw=1.0,
                label="random arrivals, same rate")
    if r.gap is not None:
        ax.axvline(r.gap * 1e3, color="tab:red", ls=":", label=f"gap {r.gap * 1e3:.3g} ms")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    ax.set_xlabel("inter-arrival time [ms]")
    ax.set_ylabel("arrivals per bin [-]")
    ax.set_title(f"CV {r.cv_interarrival:.3g}, doubles {r.doubles_rate:.1%}; "
                 f"{r.steady_from:.3g} .. {r.steady_to:.3g} s", fontsize=9)
    name_run(fig, caption)
    out.append(save(fig, Path(folder) / "singulation_interarrival.png"))

    fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    sizes = sorted(r.cluster_sizes)
    counts = [r.cluster_sizes[s] for s in sizes]
    # Log scale: singles outnumber clusters of four and more by a hundred to one.
    ax.bar(sizes, counts, color="tab:orange", label="clusters of touching parts")
    ax.set_yscale("log")
    for s, c in zip(sizes, counts):
        ax.annotate(f"{c:.3g}", (s, c), textcoords="offset points", xytext=(0, 2), ha="center",
                    fontsize=7)
    if sizes:
        ax.set_xticks(sizes)
    ax.set_xlabel("cluster size [parts]")
    ax.set_ylabel("clusters per frame (log scale)")
    ax.set_title(f"{r.cluster_frames} frames; alone on the track: "
                 f"{r.track_singulated_fraction:.1%}", fontsize=9)
    name_run(fig, caption)
    out.append(save(fig, Path(folder) / "singulation_clusters.png"))
    return out


# The states' colours in the orientation census (up: the usual correct state).
STATE_COLOURS = {"up": "tab:green", "down": "tab:red", "side": "tab:orange", "end": "tab:purple"}


def orientation_figure(analysis, path) -> Path:
    """The state fractions of the parts on the track against the path coordinate, stacked,
    the correct fraction over them and the tooling stations marked (their in and out): one
    PNG at ``path``."""
    plt = pyplot()
    r = analysis.results
    fig, ax = plt.subplots(figsize=(8, 4), layout="constrained")
    x = np.asarray(r.census_x) * 1e3
    width = float(np.diff(r.census_edges).mean()) * 1e3 if len(x) else 1.0
    bottom = np.zeros(len(x))
    for name, fractions in r.census_fractions.items():
        f = np.nan_to_num(np.asarray(fractions, dtype=float))
        ax.bar(x, f, width=width, bottom=bottom, color=STATE_COLOURS.get(name), alpha=0.75,
               label=name, edgecolor="white", linewidth=0.3)
        bottom += f
    ax.plot(x, r.census_correct, "k.-", lw=1.0, label=f"correct ({r.correct})")
    for st in r.stations:
        ax.axvspan(st["x_in"] * 1e3, st["x_out"] * 1e3, color="0.5", alpha=0.15)
        ax.annotate(st["name"], (st["x_in"] * 1e3, 1.01), fontsize=7, rotation=30,
                    xycoords=("data", "axes fraction"))
    ax.set_xlim(float(r.census_edges[0]) * 1e3, float(r.census_edges[-1]) * 1e3)
    ax.set_ylim(0, 1)
    ax.set_xlabel("path coordinate [mm] (the outlet edge at the right)")
    ax.set_ylabel("fraction of the parts on the track [-]")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    name_run(fig, f"{run_caption(analysis.result)}; {r.steady_from:.3g} .. {r.steady_to:.3g} s")
    return save(fig, path)
