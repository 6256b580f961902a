"""What a feeder's deck is given for one run: its further elements as LIGGGHTS commands.

decks/bulk_feeder.liggghts runs one section, or a line of any number of them: at four
places it includes a file written for the run (``${mesh_dir}/line_*.in``) that declares
sections 2 ... n. For a single track the files hold no command (its run is exactly the
single track's). decks/bowl_feeder.liggghts includes the same four: a bowl's exit line
(elements 2 ... n after the bowl, in the frame at its chute's end, :data:`FIRST`); a bowl
alone gets the wall contact only, the command its deck held. Section k's numbers are the
deck's ``s<k>_*`` tunables, so each file is an ordinary piece of a deck a user can read; for
two sections the commands are, to the character, those the deck held for its section 2
before lines of more sections existed.

* ``line_derived.in``: each section's angular frequency, phase, lowest floor, peak speed
  and catch plane; the deck's ``v_peak`` (the fastest surface: the contact speed and dt),
  ``outlet_x`` (the last section's end) and ``catch_z`` (below the lowest floor) redefined;
* ``line_meshes.in``: the further sections' meshes, each placed where its sine puts it at
  t = 0, and the wall contact over every mesh;
* ``line_catch.in``: by hand, the rejects' catch face under the further sections;
* ``line_motion.in``: each further section's movers and its recorded motion
  (``s<k>_surface_*``, FORMAT.md), and a section's air jet (its block and force, switched
  on by the driver only: vibrofeed.engine.jets).

:func:`guard_lines` is the part of prepared.in that refuses, in a run by hand, any value
other than those vibrofeed checked and built the folder for: the rules live in Python
(:mod:`vibrofeed.parameters`, :mod:`vibrofeed.feeders`) and the decks repeat none of them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

from ..mesh import write_stl
from .feeder import Feeder

FILES = ("line_derived.in", "line_meshes.in", "line_catch.in", "line_motion.in")
_WALLS = ("fix walls all wall/gran ${gran_model} mesh n_meshes %d meshes %s &\n"
          "     tangential_damping ${tdamp} limitForce ${limitf}\n")


def _max(a: str, b: str) -> str:
    return f"({a}+{b}+abs({a}-{b}))/2"


def _min(a: str, b: str) -> str:
    return f"({a}+{b}-abs({a}-{b}))/2"


# What the deck calls the first element's: its mesh, its peak surface speed and its catch plane
# (LIGGGHTS has no max()/min(): the line files combine them pairwise), where the further
# elements start along x, and where the rejects' catch face lies (x y). A bowl's are its
# deck's own, taken by value ($()) because line_derived.in redefines v_peak and catch_z; its
# further elements' catch planes are in the exit line's frame, whose floor lies above the
# bowl's bottom (BowlElement.line_origin): below their floors in the deck's frame too.
FIRST = {
    "linear": {"mesh": "track", "peak": "v_omega*sqrt(v_amp_t^2+v_amp_n^2)",
               "catch": "-(v_amp_n+2*v_r_ext)-v_track_width*tan(v_cross_tilt*PI/180)",
               "start": "v_track_length", "at": "${track_length} 0"},
    "bowl": {"mesh": "bowl", "peak": "$(v_v_peak)", "catch": "$(v_catch_z)",
             "start": "v_bowl_outlet_x", "at": "${bowl_outlet_x} $(-v_bowl_r_mid)"},
}


def line_files(feeder: Feeder) -> dict[str, str]:
    """The four files (module docstring) for ``feeder``, a line of n >= 1 sections; each
    further element gives its own commands (its ``deck_commands``)."""
    elements = feeder.elements
    n = len(elements)
    first = FIRST[elements[0].kind]
    what = f"a bowl and {n - 1} element(s) after it" if elements[0].kind == "bowl" else \
        f"a line of {n} section(s)"
    head = f"# written by vibrofeed.feeders.deck for one run: {what}\n"
    out = {name: head for name in FILES}
    # every element's air jet (a bowl's on its helix too), each in its own frame
    jets = [line for e in elements if hasattr(e, "jet_commands")
            for line in e.jet_commands(feeder.part, feeder.origin_of(e))]
    if n == 1:
        out["line_meshes.in"] += _WALLS % (1, first["mesh"])
        if jets:
            out["line_motion.in"] += "\n".join(jets) + "\n"
        return out
    further = elements[1:]
    pieces = [e.deck_commands() for e in further]
    d = [line for p in pieces for line in p["derived"]]
    d += [f"variable s1_peak equal {first['peak']}"]
    d += [line for p in pieces for line in p["peak"]]
    d += [f"variable s1_catch equal {first['catch']}"]
    d += [line for p in pieces for line in p["catch"]]
    # the fastest and the lowest over the sections, pairwise (LIGGGHTS has no max())
    peak, catch = "v_s1_peak", "v_s1_catch"
    for e in further[:-1]:
        k = e.number
        d += [f"variable peak_1_{k} equal {_max(peak, f'v_s{k}_peak')}",
              f"variable catch_1_{k} equal {_min(catch, f'v_s{k}_catch')}"]
        peak, catch = f"v_peak_1_{k}", f"v_catch_1_{k}"
    lengths = "+".join([first["start"]] + [f"v_s{e.number}_length" for e in further])
    d += ["variable v_peak delete", f"variable v_peak equal {_max(peak, f'v_s{n}_peak')}",
          "variable outlet_x delete", f"variable outlet_x equal {lengths}",
          "variable catch_z delete", f"variable catch_z equal {_min(catch, f'v_s{n}_catch')}"]
    out["line_derived.in"] += "\n".join(d) + "\n"

    m = [line for p in pieces for line in p["mesh"]]
    out["line_meshes.in"] += "\n".join(m) + "\n" + _WALLS % (
        n, " ".join([first["mesh"]] + [f"track_s{e.number}" for e in further]))

    scale = "${s2_length}" if n == 2 else "$(" + "+".join(f"v_s{e.number}_length" for e in further) + ")"
    out["line_catch.in"] += (
        'if "${driver} == 0" then &\n'
        f'  "fix reject_catch all mesh/surface file ${{mesh_dir}}/catch.stl type 2 scale {scale} &\n'
        f'     move {first["at"]} ${{catch_z}}" &\n'
        '  "fix rejects all massflow/mesh mesh reject_catch vec_side 0 0 -1 count once file '
        'rejects.txt writeTime"\n')
    motion = [line for p in pieces for line in p["motion"]] + jets
    out["line_motion.in"] += "\n".join(motion) + "\n"
    return out


def write_line_files(feeder: Feeder, folder: str | Path) -> list:
    """Each further element's mesh at rest as ``track_s<k>.stl`` and the four files into
    ``folder``; returns the further meshes (none for a single track)."""
    folder = Path(folder)
    meshes = feeder.further_meshes()
    for e, mesh in zip(feeder.elements[1:], meshes):
        write_stl(*mesh, folder / f"track_s{e.number}.stl", f"track_s{e.number}")
    for name, text in line_files(feeder).items():
        (folder / name).write_text(text)
    return meshes


# What a run by hand may set itself: the returns are the driver's (the deck refuses
# recirculate=1 by hand on its own, and prepare prints the line with recirculate 0).
HAND_FREE = ("recirculate",)


def guard_lines(values: Mapping) -> list[str]:
    """prepared.in's refusals of a run by hand with other values than the ``values`` vibrofeed
    checked and wrote the folder for: every number (the part, the elements and their drives,
    the supply, the contact, the run's clock) but :data:`HAND_FREE`; words (a jet's keep, an
    STL's file) are held by the files written for them. Numbers compare as numbers."""
    lines = []
    for name, value in values.items():
        try:
            x = float(value)
        except (TypeError, ValueError):
            continue
        if name in HAND_FREE or not math.isfinite(x):
            continue
        shown = repr(x)
        lines.append(f'if "${{{name}}} != {shown}" then &\n'
                     f"  \"print 'Invalid {name}: mesh_dir was checked and written for "
                     f"{name}={shown}; run vibrofeed prepare again with the new value'\" \"quit\"\n")
    return lines
