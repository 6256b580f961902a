"""``vibrofeed sweep-report``: a sweep's settings, the best one, and the maps.

Settings are the summary's rows grouped over their replicates (same
parameters, different seeds). A setting's figure is the mean over its done
replicates; its uncertainty is the standard error of that mean over the
replicates (independent seeds: the honest spread, run-to-run noise included)
when there are two or more, else the run's own batch-means error. A figure
that one of the done replicates could not measure (too few exits, a bed still
drifting: the row's ``feedrate_reason`` or ``singulation_reason``) is
*unmeasured* for the setting, with that reason: the replicates that did
measure it would give a mean biased towards them.

The figure of merit is the feed rate (``parts_per_s``) of a bulk-feeder deck,
else the mean conveying velocity. **Best setting**: among the settings with a
measured figure (an unmeasured one is never best), those whose
figure is within one combined standard error (sqrt(err_best^2 + err^2)) of the
highest, the one with the largest singulated fraction (a feeder that delivers
as much and singulates better is the better feeder); without singulation
figures, simply the highest.

Maps (``--plot DIR``): a heat map of the figure over the first two varied
axes, and the figure against the one of them with more values, with its error
bars (one line per value of the other), beside it the conveying velocity (bulk
decks: the feed rate is the parts' line density times it) and the singulated
fraction.
Other varied axes are held at the best setting's values; a zipped group is one
axis (all its parameters vary together), labelled by its first parameter.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

from ..errors import UsageError
from ..values import fmt
from . import summary as S

# column -> (name, unit shown, scale to that unit, format)
FIGURES = {
    "parts_per_s": ("feed rate", "parts/s", 1.0, ".4g"),
    "mean_velocity": ("conveying", "mm/s", 1e3, ".4g"),
    "singulated_fraction": ("singulated", "%", 100.0, ".3g"),
    "doubles_rate": ("doubles", "%", 100.0, ".3g"),
}


# figure -> the row's column saying why it was not measured (vibrofeed.sweep.metrics)
REASONS = {"parts_per_s": "feedrate_reason", "singulated_fraction": "singulation_reason",
           "doubles_rate": "singulation_reason"}


def heading(name: str) -> str:
    title, unit, _, _ = FIGURES[name]
    return f"{title} [{unit}]"


def mean_err(values: list, errors: list) -> tuple[float | None, float | None]:
    """Mean of the values that are not None, and its standard error over them (one value:
    its own error from ``errors``, aligned with ``values``; none: (None, None))."""
    xs = [v for v in values if v is not None]
    if not xs:
        return None, None
    mean = sum(xs) / len(xs)
    if len(xs) >= 2:
        var = sum((x - mean) ** 2 for x in xs) / (len(xs) - 1)
        return mean, math.sqrt(var / len(xs))
    e = errors[values.index(xs[0])] if errors else None
    return mean, e


def settings(rows: list[dict], varied: list[str], merit: str) -> list[dict]:
    """One entry per setting: its varied values, runs done / total, figures (mean, error)."""
    groups: dict[tuple, list[dict]] = {}
    for row in sorted(rows, key=lambda r: r["job"]):
        groups.setdefault(tuple(row.get(p) for p in varied), []).append(row)
    out = []
    for key, members in groups.items():
        done = [r for r in members if r["status"] == S.DONE]
        entry = {"parameters": dict(zip(varied, key)), "runs": len(members), "done": len(done),
                 "jobs": [r["job"] for r in members]}
        for name in FIGURES:
            values = [r.get(name) for r in done]
            mean, err = (None, None) if None in values else mean_err(
                values, [r.get(f"{name}_err") for r in done])
            entry[name], entry[f"{name}_err"] = mean, err
            entry[f"{name}_unmeasured"] = _unmeasured(done, REASONS.get(name))
        entry["merit"], entry["merit_err"] = entry[merit], entry[f"{merit}_err"]
        entry["merit_unmeasured"] = entry[f"{merit}_unmeasured"]
        out.append(entry)
    return out


def _unmeasured(done: list[dict], column: str | None) -> str | None:
    """Why the done runs ``done`` measured no value of a figure (its reason ``column``):
    the reason, preceded by how many of them gave one; None when every run measured it."""
    reasons = [r[column] for r in done if column and r.get(column)]
    if not reasons:
        return None
    return reasons[0] if len(done) == 1 else f"{len(reasons)} of {len(done)} runs: {reasons[0]}"


def best(entries: list[dict]) -> dict | None:
    """The best setting (module docstring), or None when none has a measured figure."""
    scored = [e for e in entries if e["merit"] is not None and not e.get("merit_unmeasured")]
    if not scored:
        return None
    top = max(scored, key=lambda e: e["merit"])
    err_top = top["merit_err"] or 0.0
    close = [e for e in scored
             if top["merit"] - e["merit"] <= math.hypot(err_top, e["merit_err"] or 0.0)]
    if any(e["singulated_fraction"] is not None for e in close):
        return max(close, key=lambda e: (e["singulated_fraction"] if e["singulated_fraction"] is not None
                                         else -1.0, e["merit"]))
    return top


def _with_err(entry, name) -> str:
    _, _, scale, spec = FIGURES[name]
    value, err = entry[name], entry[f"{name}_err"]
    if value is None:
        return "unmeasured" if entry.get(f"{name}_unmeasured") else "n/a"
    return fmt(value, scale, spec) + ("" if err is None else f" ± {fmt(err, scale, '.2g')}")


def table(entries: list[dict], varied: list[str], shown: list[str]) -> str:
    head = varied + ["runs"] + [heading(n) for n in shown]
    rows = [[fmt(e["parameters"][p], spec="g") if isinstance(e["parameters"][p], int | float)
             else str(e["parameters"][p]) for p in varied] + [f"{e['done']}/{e['runs']}"]
            + [_with_err(e, n) for n in shown] for e in entries]
    widths = [max(len(r[i]) for r in [head] + rows) for i in range(len(head))]
    return "\n".join("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip() for r in [head] + rows)


def load(folder) -> tuple[list[dict], dict]:
    folder = Path(folder)
    if not (folder / S.H5_NAME).is_file():
        raise UsageError(f"{folder}: no {S.H5_NAME}; give the -o DIR of a `vibrofeed sweep` "
                         "(its summary appears as the sweep starts)")
    rows, meta = S.read(folder)
    meta["varied"] = json.loads(meta.get("varied", "[]"))
    meta["axes"] = json.loads(meta.get("axes", "[]")) or [[v] for v in meta["varied"]]
    return rows, meta


def report(folder, plot_folder=None) -> dict:
    """Everything ``vibrofeed sweep-report`` shows, JSON-ready."""
    rows, meta = load(folder)
    varied = [p for p in meta["varied"] if p != "seed"]
    # A bulk feeder's merit is its feed rate even when no run measured one (the feeder's
    # rows have its exits counted): the conveying speed is no stand-in for it.
    bulk = any(r.get("n_events") is not None or r.get("parts_per_s") is not None for r in rows)
    merit = "parts_per_s" if bulk else "mean_velocity"
    entries = settings(rows, varied, merit)
    chosen = best(entries)
    failed = [{"job": r["job"], "error": r["error"], "file": r["file"]}
              for r in rows if r["status"] != S.DONE]
    units = json.loads(meta.get("units", "{}"))
    out = {"folder": str(folder), "deck": meta.get("deck"), "jobs_planned": meta.get("n_jobs"),
           "jobs_finished": len(rows), "done": len(rows) - len(failed), "failed": failed,
           "varied": varied, "merit": merit, "settings": entries, "best": chosen, "figures": []}
    if plot_folder is not None and entries:
        groups = [[k for k in axis if k in varied] for axis in meta["axes"]]
        title = (f"sweep {Path(folder).resolve().name}; deck {meta.get('deck')}; {len(entries)} "
                 f"settings, {len(rows) - len(failed)} runs done")
        out["figures"] = plots(entries, [g for g in groups if g], merit, chosen, Path(plot_folder),
                               units, title)
    return out


def _setting(entry: dict) -> str:
    return " ".join(f"{k}={fmt(v, spec='g') if isinstance(v, float) else v}"
                    for k, v in entry["parameters"].items()) or "(the only setting)"


def text(rep: dict) -> str:
    shown = [rep["merit"]] + [n for n in ("singulated_fraction", "doubles_rate")
                              if any(e[n] is not None or e[f"{n}_unmeasured"] for e in rep["settings"])]
    if rep["merit"] == "parts_per_s":
        shown.append("mean_velocity")
    lines = [f"sweep {rep['folder']}: deck {rep['deck']}, {rep['jobs_finished']} of "
             f"{rep['jobs_planned']} jobs finished: {rep['done']} done, {len(rep['failed'])} failed",
             "", table(rep["settings"], rep["varied"], shown), ""]
    for e in rep["settings"]:  # why each "unmeasured" of the table (figures of one reason together)
        said: dict[str, list[str]] = {}
        for name in shown:
            if e[name] is None and e.get(f"{name}_unmeasured"):
                said.setdefault(e[f"{name}_unmeasured"], []).append(FIGURES[name][0])
        for why, names in said.items():
            lines.append(f"unmeasured: {_setting(e)}: {', '.join(names)}: {why}")
    b = rep["best"]
    if b is None:
        unmeasured = any(e["merit_unmeasured"] for e in rep["settings"])
        lines.append(f"best: none (no setting has a measured {FIGURES[rep['merit']][0]})" if unmeasured
                     else "best: none (no job finished with a figure)")
    else:
        setting = _setting(b)
        title, unit, _, _ = FIGURES[rep["merit"]]
        lines.append(f"best: {setting}: {title} {_with_err(b, rep['merit'])} {unit}"
                     + (f", singulated {_with_err(b, 'singulated_fraction')} %"
                        if b["singulated_fraction"] is not None else "")
                     + " (the highest; within one standard error, the better singulation)")
    for f in rep["failed"][:10]:
        lines.append(f"failed: job {f['job']}: {f['error']}")
    if len(rep["failed"]) > 10:
        lines.append(f"... and {len(rep['failed']) - 10} more failed jobs (see summary.csv)")
    lines += [f"figure: {p}" for p in rep["figures"]]
    return "\n".join(lines)


# ---------------------------------------------------------------- figures
def _numeric(entries, name) -> bool:
    return all(isinstance(e["parameters"][name], int | float) for e in entries)


def _slice(entries, keep: list[str], chosen) -> list[dict]:
    """The entries whose varied values other than ``keep`` are the best setting's."""
    if chosen is None:
        return entries
    fixed = {k: v for k, v in chosen["parameters"].items() if k not in keep}
    return [e for e in entries if all(e["parameters"][k] == v for k, v in fixed.items())]


def plotted(entries, groups: list[list[str]], chosen) -> tuple[list[str], list[dict]]:
    """(axes, entries) the maps draw: the first two numeric varied groups with more than one
    value, each drawn along its first parameter (a zipped group's others vary with it), and
    the settings where every other varied parameter has the best setting's value."""
    def n_values(name):
        return len({e["parameters"][name] for e in entries})

    groups = [g for g in groups if _numeric(entries, g[0]) and n_values(g[0]) > 1][:2]
    return [g[0] for g in groups], _slice(entries, [k for g in groups for k in g], chosen)


def plots(entries, groups: list[list[str]], merit: str, chosen, folder: Path, units=None,
          title: str = "") -> list[str]:
    """The maps of the module docstring (drawn by :mod:`vibrofeed.pictures.sweep_maps`, headed
    by ``title``); ``groups``: the varied axes, each the list of parameters that vary
    together (one for a grid axis, several for a zipped group)."""
    from ..pictures.sweep_maps import heat_map, trends

    label, scale = heading(merit), FIGURES[merit][2]
    units = units or {}
    partners = {g[0]: g[1:] for g in groups}

    def axis_label(name):
        u = units.get(name, "")
        text = f"{name} [{u}]" if u and u != "-" else name
        return text + (f" (= {', '.join(partners[name])})" if partners.get(name) else "")

    def n_values(name):
        return len({e["parameters"][name] for e in entries})

    out = []
    axes, part = plotted(entries, groups, chosen)
    held = {k: v for k, v in (chosen or {}).get("parameters", {}).items()
            if k not in [p for g in groups if g[0] in axes for p in g]}
    if held:
        title += "; other parameters at the best setting's: " + ", ".join(
            f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}" for k, v in held.items())
    if len(axes) >= 2:
        out.append(str(heat_map(part, axes[0], axes[1], label, scale, axis_label, chosen,
                                folder / "sweep_map.png", title)))
    if axes:
        a, series = axes[0], (axes[1] if len(axes) > 1 else None)
        if series is not None and n_values(series) > n_values(a):
            a, series = series, a  # along the axis with more values, a line per value of the other
        # The figure of merit, then (bulk decks) the conveying velocity that makes it and the
        # singulation: each against the axis, a line per value of the other axis.
        panels = [(merit, label, scale)]
        if merit == "parts_per_s":
            panels.append(("mean_velocity", heading("mean_velocity"), FIGURES["mean_velocity"][2]))
        panels.append(("singulated_fraction", "singulated fraction [%]", 100.0))
        out.append(str(trends(part, a, series, panels, axis_label, folder / f"sweep_vs_{a}.png", title)))
    return out
