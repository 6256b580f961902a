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
    cell, the best setting framed."""
    plt = pyplot()
    xs = sorted({e["parameters"][a] for e in part})
    ys = sorted({e["parameters"][b] for e in part})
    grid = np.full((len(ys), len(xs)), np.nan)
    for e in part:
        if e["merit"] is not None:
            grid[ys.index(e["parameters"][b]), xs.index(e["parameters"][a])] = e["merit"] * scale
    fig, ax = plt.subplots(figsize=(6.5, 4.8), layout="constrained")
    im = ax.imshow(grid, origin="lower", aspect="auto", cmap="viridis")
    ax.set_xticks(range(len(xs)), [f"{x:g}" for x in xs])
    ax.set_yticks(range(len(ys)), [f"{y:g}" for y in ys])
    for (i, j), v in np.ndenumerate(grid):
        if np.isfinite(v):
            ax.text(j, i, f"{v:.3g}", ha="center", va="center", fontsize=8,
                    color="w" if v < np.nanmean(grid) else "k")
    ax.set_xlabel(axis_label(a))
    ax.set_ylabel(axis_label(b))
    ax.set_title(f"{label}: mean over each setting's replicates (blank: no result)", fontsize=8)
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
    error bars, one line per value of ``series`` (or one line)."""
    plt = pyplot()
    fig, row = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), layout="constrained",
                            squeeze=False)
    row = row[0]
    for value in sorted({e["parameters"][series] for e in part}) if series else [None]:
        line = sorted((e for e in part if series is None or e["parameters"][series] == value),
                      key=lambda e: e["parameters"][a])
        name = f"{axis_label(series)} = {value:g}" if series else "setting mean ± 1 sigma"
        x = [e["parameters"][a] for e in line]
        for ax, (key, _, k) in zip(row, panels):
            y = [math.nan if e[key] is None else e[key] * k for e in line]
            err = [0.0 if e[f"{key}_err"] is None else e[f"{key}_err"] * k for e in line]
            ax.errorbar(x, y, yerr=err, marker="o", ms=4, capsize=3, label=name)
    for ax, (_, ylabel, _) in zip(row, panels):
        ax.set_xlabel(axis_label(a))
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=8, title=ERROR_BARS, title_fontsize=7)
    name_run(fig, title)
    return save(fig, path)
