"""What a line's deck is given for one run: its further sections as LIGGGHTS commands.

decks/bulk_feeder.liggghts runs one section, or a line of any number of them: at four
places it includes a file written for the run (``${mesh_dir}/line_*.in``) that declares
sections 2 ... n. For a single track the files hold no command (its run is exactly the
single track's). Section k's numbers are the deck's ``s<k>_*`` tunables, so each file is
an ordinary piece of a deck a user can read; for two sections the commands are, to the
character, those the deck held for its section 2 before lines of more sections existed.

* ``line_derived.in``: each section's angular frequency, phase, lowest floor, peak speed
  and catch plane; the deck's ``v_peak`` (the fastest surface: the contact speed and dt),
  ``outlet_x`` (the last section's end) and ``catch_z`` (below the lowest floor) redefined;
* ``line_meshes.in``: the further sections' meshes, each placed where its sine puts it at
  t = 0, and the wall contact over every mesh;
* ``line_catch.in``: by hand, the rejects' catch face under the further sections;
* ``line_motion.in``: each further section's movers and its recorded motion
  (``s<k>_surface_*``, FORMAT.md).

:func:`guard_lines` is the part of prepared.in that refuses, in a run by hand, any value
other than those the geometry was checked and built for: the rules live in Python
(:mod:`vibrofeed.feeders`) and the deck repeats none of them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from pathlib import Path

from .feeder import Feeder

FILES = ("line_derived.in", "line_meshes.in", "line_catch.in", "line_motion.in")
_WALLS = ("fix walls all wall/gran ${gran_model} mesh n_meshes %d meshes %s &\n"
          "     tangential_damping ${tdamp} limitForce ${limitf}\n")


def _max(a: str, b: str) -> str:
    return f"({a}+{b}+abs({a}-{b}))/2"


def _min(a: str, b: str) -> str:
    return f"({a}+{b}-abs({a}-{b}))/2"


def line_files(feeder: Feeder) -> dict[str, str]:
    """The four files (module docstring) for ``feeder``, a linear line of n >= 1 sections."""
    n = len(feeder.linear_sections)
    head = f"# written by vibrofeed.feeders.deck for one run: a line of {n} section(s)\n"
    out = {name: head for name in FILES}
    if n == 1:
        out["line_meshes.in"] += _WALLS % (1, "track")
        return out
    further = range(2, n + 1)
    d = []
    for k in further:
        level = "+".join(f"v_s{j}_step" for j in range(2, k + 1))
        d += [f"variable s{k}_omega equal 2*PI*v_s{k}_freq",
              f"variable s{k}_phi equal v_s{k}_phase*PI/180",
              f"variable s{k}_low equal -({level}+v_s{k}_width*tan(v_s{k}_cross_tilt*PI/180))"]
    d += ["variable s1_peak equal v_omega*sqrt(v_amp_t^2+v_amp_n^2)"]
    d += [f"variable s{k}_peak equal v_s{k}_omega*sqrt(v_s{k}_amp_t^2+v_s{k}_amp_n^2)" for k in further]
    d += ["variable s1_catch equal -(v_amp_n+2*v_r_ext)-v_track_width*tan(v_cross_tilt*PI/180)"]
    d += [f"variable s{k}_catch equal v_s{k}_low-(v_s{k}_amp_n+2*v_r_ext)" for k in further]
    # the fastest and the lowest over the sections, pairwise (LIGGGHTS has no max())
    peak, catch = "v_s1_peak", "v_s1_catch"
    for k in further:
        if k < n:
            d += [f"variable peak_1_{k} equal {_max(peak, f'v_s{k}_peak')}",
                  f"variable catch_1_{k} equal {_min(catch, f'v_s{k}_catch')}"]
            peak, catch = f"v_peak_1_{k}", f"v_catch_1_{k}"
    lengths = "+".join(["v_track_length"] + [f"v_s{k}_length" for k in further])
    d += ["variable v_peak delete", f"variable v_peak equal {_max(peak, f'v_s{n}_peak')}",
          "variable outlet_x delete", f"variable outlet_x equal {lengths}",
          "variable catch_z delete", f"variable catch_z equal {_min(catch, f'v_s{n}_catch')}"]
    out["line_derived.in"] += "\n".join(d) + "\n"

    m = [f"fix track_s{k} all mesh/surface file ${{mesh_dir}}/track_s{k}.stl type 2 "
         f"move 0 0 $(v_s{k}_amp_n*sin(v_s{k}_phi))" for k in further]
    out["line_meshes.in"] += "\n".join(m) + "\n" + _WALLS % (
        n, " ".join(["track"] + [f"track_s{k}" for k in further]))

    scale = "${s2_length}" if n == 2 else "$(" + "+".join(f"v_s{k}_length" for k in further) + ")"
    out["line_catch.in"] += (
        'if "${driver} == 0" then &\n'
        f'  "fix reject_catch all mesh/surface file ${{mesh_dir}}/catch.stl type 2 scale {scale} &\n'
        '     move ${track_length} 0 ${catch_z}" &\n'
        '  "fix rejects all massflow/mesh mesh reject_catch vec_side 0 0 -1 count once file '
        'rejects.txt writeTime"\n')

    mo = []
    for k in further:
        s = f"s{k}"
        half = f"$(v_{s}_omega*v_dt_used/2)"
        mo += [f"fix {s}_shake_t all move/mesh mesh track_{s} wiggle amplitude ${{{s}_amp_t}} 0 0 "
               f"period $(1/v_{s}_freq)",
               f"fix {s}_shake_n all move/mesh mesh track_{s} viblin axis 0 0 1 order 1 amplitude "
               f"${{{s}_amp_n}} &\n     phase $(v_{s}_phi-PI/2) period $(1/v_{s}_freq)",
               f"variable {s}_surface_x equal &\n"
               f"$(v_{s}_amp_t*v_{s}_omega*v_dt_used/sin(v_{s}_omega*v_dt_used/2))&\n"
               f"*sin(step*{half})*cos((step+1)*{half})",
               f"variable {s}_surface_y equal 0",
               f"variable {s}_surface_z equal &\n"
               f"$(v_{s}_amp_n*sin(v_{s}_phi))&\n"
               f"+$(v_{s}_amp_n*v_{s}_omega*v_dt_used/sin(v_{s}_omega*v_dt_used/2))&\n"
               f"*sin(step*{half})*cos((step+1)*{half}+$(v_{s}_phi))",
               f"variable {s}_surface_vx equal $(v_{s}_amp_t*v_{s}_omega)*cos($(v_{s}_omega)*time)",
               f"variable {s}_surface_vy equal 0",
               f"variable {s}_surface_vz equal "
               f"$(v_{s}_amp_n*v_{s}_omega)*cos($(v_{s}_omega)*time+$(v_{s}_phi))"]
    out["line_motion.in"] += "\n".join(mo) + "\n"
    return out


def write_line_files(feeder: Feeder, folder: str | Path) -> None:
    for name, text in line_files(feeder).items():
        (Path(folder) / name).write_text(text)


def guard_lines(values: Mapping, names: Iterable[str]) -> list[str]:
    """prepared.in's refusals of a run by hand with other values of ``names`` than the
    ``values`` the geometry was checked and written for (numbers compare as numbers)."""
    lines = []
    for name in names:
        if name not in values:
            continue
        x = float(values[name])
        if not math.isfinite(x):
            continue
        shown = repr(x)
        lines.append(f'if "${{{name}}} != {shown}" then &\n'
                     f"  \"print 'Invalid {name}: the geometry in mesh_dir was checked and written for "
                     f"{name}={shown}; run vibrofeed prepare again with the new value'\" \"quit\"\n")
    return lines
