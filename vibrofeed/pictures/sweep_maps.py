"""The maps of ``vibrofeed sweep-report --plot``: the figure of merit over the varied axes.

:mod:`vibrofeed.sweep.report` chooses what is drawn (the axes, the settings of the
slice through the best one, the panels); this module draws it, each figure headed
by the sweep it shows.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .plots import name_run, pyplot, save

# What a setting's error bar is (vibrofeed.sweep.report's module docstring).
ERROR_BARS = "1 sigma: standard error over the replicates (one run: its batch means)"


def heat_map(part: list[dict], a: str, b: str, label: str, scale: float, axis_label, chosen,
             path: Path, title: str) -> Path:
    """The figure of merit (``entry["merit"] * scale``, labelled ``label``) of the settings
    ``part`` on the grid of parameters ``a`` (x) and ``b`` (y), its value written in each
    cell ("unmeasured" in a setting's whose runs could not measure it), the best setting
    framed."""
    plt = pyplot()
    xs = sorted({e["parameters"][a] for e in part})
    ys = sorted({e["parameters"][b] for e in part})
    grid = np.full((len(ys), len(xs)), np.nan)
    unmeasured = []
    for e in part:
        cell = ys.index(e["parameters"][b]), xs.index(e["parameters"][a])
        if e["merit"] is not None:
            grid[cell] = e["merit"] * scale
        elif e.get("merit_unmeasured"):
            unmeasured.append(cell)
    fig, ax = plt.subplots(figsize=(6.5, 4.8), layout="constrained")
    im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
    ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs])
    ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
    for (i, j), v in np.ndenumerate(grid):
        if np.isfinite(v):
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=8,
                    color="w" if v < np.nanmean(grid) else "k")
    for i, j in unmeasured:  # no colour: an unmeasured rate is no low rate
        ax.text(j, i, "unmeasured", ha="center", va="center", fontsize=6, color="0.35")
    ax.set_xlabel(axis_label(a))
    ax.set_ylabel(axis_label(b))
    ax.set_title(f"{label}: mean over each setting's replicates (blank: no result; unmeasured: "
                 "too few exits or a drifting bed, see sweep-report)", fontsize=8)
    fig.colorbar(im, ax=ax, label=label)
    if chosen is not None and chosen in part:
        from matplotlib.patches import Rectangle

        # a frame round the best cell: its value stays readable
        j, i = xs.index(chosen["parameters"][a]), ys.index(chosen["parameters"][b])
        ax.add_patch(Rectangle((j - 0.5, i - 0.5), 1, 1, fill=False, ec="red", lw=2.5,
                               label="best setting"))
        ax.legend(loc="upper left", bbox_to_anchor=(0, -0.12), fontsize=8, frameon=False)
    name_run(fig, title)
    return save(fig, path)


def trends(part: list[dict], a: str, series: str | None, panels, axis_label, path: Path,
           title: str) -> Path:
    """Each panel's figure (``panels``: (key, label, scale)) against parameter ``a`` with its
    error bars, one line per value of ``series`` (or one line); a setting that could not
    measure a panel's figure is a cross at the foot of that panel, not a point."""
    from matplotlib.transforms import blended_transform_factory

    plt = pyplot()
    fig, row = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), layout="constrained",
                            squeeze=False)
    row = row[0]
    for i, value in enumerate(sorted({e["parameters"][series] for e in part}) if series else [None]):
        line = sorted((e for e in part if series is None or e["parameters"][series] == value),
                      key=lambda e: e["parameters"][a])
        name = f"{axis_label(series)} = {value:g}" if series else "setting mean ± 1 sigma"
        x = [e["parameters"][a] for e in line]
        for ax, (key, _, k) in zip(row, panels):
            y = [math.nan if e[key] is None else e[key] * k for e in line]
            err = [0.0 if e[f"{key}_err"] is None else e[f"{key}_err"] * k for e in line]
            drawn = ax.errorbar(x, y, yerr=err, marker="o", ms=4, capsize=3, label=name)
            missing = [e["parameters"][a] for e in line
                       if e[key] is None and e.get(f"{key}_unmeasured")]
            if missing:  # at the foot of the axis (x in data, y in axes units, a step up per line)
                ax.plot(missing, [0.03 * i] * len(missing), "x", color=drawn[0].get_color(), ms=7,
                        clip_on=False, transform=blended_transform_factory(ax.transData, ax.transAxes),
                        label=f"{name}: unmeasured (sweep-report says why)")
    for ax, (_, ylabel, _) in zip(row, panels):
        ax.set_xlabel(axis_label(a))
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=8, title=ERROR_BARS, title_fontsize=7)
    name_run(fig, title)
    return save(fig, path)
