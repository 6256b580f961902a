"""``vibrofeed demo``: the main job — a feeder line that delivers one part at a time.

Runs a named case of the ``bulk_feeder`` deck, then prints its feed rate (per section
for a line), its singulation and its rejects, and writes the result, a picture of the
last frame of the steady feeding window (parts with an orientation: its last frame with the
most correctly oriented parts) and the plots into one folder. The cases:

``line`` (the default)
    A feeder line fed continuously by a bulk supply that drops micro-parts in clumps of
    three: a slow bulk section whose floor tilts towards one wall (the parts gather into
    a file against it), then a faster single-file section with a side drop (parts beside
    the file fall off: rejects) and a wiper (stacked parts are swept off). The speed
    step opens gaps between the parts of the file (continuity: the same parts per
    second cross the joint, so the line density falls by the speed ratio).
``track``
    The same supply, parts and drive on one uniform level track of the line's length
    and width, without tooling: the feeder the line replaces, for comparison.
``bowl``
    A small vibratory bowl (``bowl_feeder``, docs/bowl.md): 500 um silicon dies climb
    half a turn of a helical track up a 20 mm bowl under its torsional and vertical
    vibration, then leave along a straight chute. A few dies lie in the bowl, the track
    and the chute are pre-filled, so the exit feeds at once; 0.4 s of vibration, about
    five minutes on one core.
``bowl-line``
    That bowl (a shorter chute) handing its dies to a linear exit section of its own drive
    and tooling (feeders/bowl_line.toml, docs/bowl.md, "The exit line"): faster than the
    chute's queue, its floor tilted towards a wall, a side drop, a wiper and a camera whose
    air jet blows off a die too close behind the last one it passed; the dies leave one at a
    time.
``orient``
    Chip components (1.0 x 0.5 x 0.35 mm boxes, their marked face +z) delivered lengthwise
    with the marked face up (feeders/orient_ledge.toml, docs/orientation.md, "The demo"):
    drawn from a store at 110 parts/s onto a hopping bulk section that lays many on a broad
    face; a faster section narrows to a ledge along its wall that only lengthwise boxes stay
    on, and a camera with an air jet blows off every part not up and lengthwise; the rejects
    fall back into the store. The report adds the rate of correct single parts, each
    station's census and the recirculation load; the picture colours the parts by state.
"""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

DESCRIPTION = ("Run the main job: a feeder line (a bulk section, then a faster single-file section "
               "with a side drop and a wiper) fed with 300 um silicon spheres; print its feed rate "
               "per section, singulation and rejects and write DIR/CASE.h5, a picture of the last "
               "frame of the steady feeding window (DIR/CASE.png) and the plots (DIR/plots/). "
               "--case track runs the single uniform track it replaces, --case bowl a small "
               "vibratory bowl feeding dies, --case bowl-line that bowl with an exit line that "
               "singulates them, --case orient a line that delivers chip components the right way up.")

# The supply both cases share: 30 parts/s of 300 um silicon spheres dropped in clumps of
# three above the track start, nothing pre-filled (a line that only drains is a batch,
# not a feeder), 2.5 s: the line is full after ~0.6 s.
SUPPLY = {"n_parts": "0", "inlet_rate": "30", "inlet_batch": "3", "t_end": "2.5", "output_dt": "0.005"}
# Sized by continuity (docs/feeder-lines.md): section 1 (4 mm, its floor tilted 10 deg
# towards one wall, a short stroke: ~14 mm/s) gathers the clumps into a file; section 2
# (4 mm, the same tilt, sub-hopping with a long stroke at a 30 deg lag: ~47 mm/s, 3.4
# times faster) opens gaps of 2.4 diameters between parts that touched in the file.
# Section 2 does not hop: hopping spheres convey at scattered speeds and catch up with
# each other. Its side drop keeps only the file against the wall; its wiper passes one
# sphere and sweeps off a stacked one.
LINE = {
    "sections": "2", "track_length": "0.004", "track_width": "1.2e-3", "wall_height": "1e-3",
    "cross_tilt": "10", "amp_t": "3.5e-5",
    "s2_length": "0.004", "s2_width": "1.2e-3", "s2_wall_height": "6e-4", "s2_step": "5e-5",
    "s2_cross_tilt": "10", "s2_amp_t": "1.8e-4", "s2_amp_n": "2e-5", "s2_phase": "-30",
    "s2_drop_from": "0.2", "s2_drop_to": "0.5", "s2_drop_width": "4e-4",
    "s2_wiper_height": "4.5e-4", "s2_wiper_at": "0.7",
}
# The same supply on one level track of the line's length and width at section 1's
# default drive, without tooling.
TRACK = {"track_length": "0.008", "track_width": "1.2e-3", "wall_height": "1e-3"}
# The bowl: 500 x 500 x 250 um dies (chips: what bowls feed; spheres roll back down a helix
# unless their rolling friction exceeds its slope), the stiffness floor the bulk feeder is
# validated for, half a turn of a 3 deg helix, and the drive the single-part model finds
# fastest up it within 5 g (75 Hz, 0.2 mm of torsional stroke at the track, 40 um of lift
# 60 deg behind: 48 mm/s in the dilute limit; the vertical motion stays below 1 g, so the
# dies slide and do not hop). The track and chute hold about 30 dies at once.
BOWL = {"shape": "1", "part_size": "5e-4", "part_thickness": "2.5e-4", "n_parts": "10",
        "n_track": "40", "turns": "0.5", "youngs": "2e7", "freq": "75", "amp_t": "2e-4",
        "amp_n": "4e-5", "phase": "-60", "t_end": "0.4", "output_dt": "0.005"}
# case -> (result name, deck or feeder description (feeders/), parameters). The bowl with an
# exit line is its description's (feeders/bowl_line.toml: its numbers and why they are so).
CASES = {"line": ("feeder_line", "bulk_feeder", {**SUPPLY, **LINE}),
         "track": ("bulk_feeder", "bulk_feeder", {**SUPPLY, **TRACK}),
         "bowl": ("bowl_feeder", "bowl_feeder", BOWL),
         "bowl-line": ("bowl_line", "bowl_line.toml", {}),
         "orient": ("orient_ledge", "orient_ledge.toml", {})}


def add_arguments(p) -> None:
    from .options import ranks

    p.add_argument("--case", choices=sorted(CASES), default="line",
                   help="line (default): the singulating feeder line; track: the uniform track it "
                        "replaces, with the same supply; bowl: a small vibratory bowl feeding dies; "
                        "bowl-line: that bowl with an exit line that singulates them; orient: chip "
                        "components delivered lengthwise, marked face up (a ledge, a camera and "
                        "an air jet)")
    p.add_argument("-o", "--output", default="results", metavar="DIR",
                   help="folder for the result, the picture and the plots (default: results)")
    p.add_argument("-p", "--param", action="append", metavar="NAME=VALUE",
                   help="change a parameter of the case (see `vibrofeed params bulk_feeder`, "
                        "`vibrofeed params bowl_feeder` for the bowl)")
    p.add_argument("-n", "--ranks", type=ranks, default=1, metavar="RANKS",
                   help="MPI ranks for LIGGGHTS (default 1)")
    p.add_argument("--reuse", action="store_true",
                   help="keep DIR/CASE.h5 if it is a complete run of the same case")
    p.add_argument("--no-pictures", action="store_true", help="skip the picture and the plots")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    from ..decks import Deck, feeders_dir
    from ..engine.runner import run_deck
    from ..parameters import parse_assignments
    from ..run_progress import RunProgress
    from ..run_summary import run_summary
    from .outputs import folder_destination, written

    folder = folder_destination("-o", args.output, create=False, parents=True)
    name, deck_name, case = CASES[args.case]
    deck = Deck.find(feeders_dir() / deck_name if deck_name.endswith(".toml") else deck_name)
    params = {**case, **parse_assignments(args.param)}
    output = folder / f"{name}.h5"
    progress = RunProgress(name, enabled=False if args.quiet else None)
    try:
        result = run_deck(deck, params, output, ranks=args.ranks, on_event=progress,
                          reuse=args.reuse, command=shlex.join(["vibrofeed"] + sys.argv[1:]))
    finally:
        progress.close()
    written(result.output)
    print(run_summary(result))
    from .options import refuse

    text, reason = report(output, None if args.no_pictures else folder)
    print(text)
    return refuse(output, reason)


def report(path, folder: Path | None = None) -> tuple[str, str | None]:
    """The feed-rate and singulation reports of a bulk result, and its orientation report
    when its parts have an orientation state (clumps: boxes, chips, discs), and why they
    measure nothing (too few exits; None when they measure); with ``folder``, also its
    picture (folder/<name>.png: coloured by orientation state when the parts have one, else
    by speed) and plots (folder/plots/)."""
    from ..postproc.feedrate import FeedRate
    from ..postproc.singulation import Singulation
    from ..results.reader import Result
    from . import feedrate as F
    from . import singulation as S
    from .options import figures_written, unmeasured
    from .outputs import written

    lines, figures = [], []
    with Result(path) as result:
        fr = FeedRate(result).run()
        summary = fr.summary()
        reason = unmeasured(summary, F.RATE_KEYS)
        # over feed rate's window, found once (Singulation would search it again)
        sg = Singulation(result, start=summary["steady_from"], end=summary["steady_to"]).run()
        singulation = sg.summary()
        reason = reason or unmeasured(singulation, S.ARRIVAL_KEYS)
        lines += ["", "Feed rate", F.table(summary), "", "Singulation", S.table(singulation)]
        oriented = result.body_template is not None  # spheres have no orientation state
        if oriented:
            from ..postproc.orientation import Orientation
            from . import orientation as O

            # the same window, feed rate and arrivals (as a sweep's metrics); "up, lengthwise"
            o = Orientation(result, start=summary["steady_from"], end=summary["steady_to"],
                            feedrate=fr.results, singulation=sg.results).run().summary()
            reason = reason or unmeasured(o, O.RATE_KEYS)
            lines += ["", "Orientation", O.table(o)]
        if folder is not None:
            from ..pictures.plots import feedrate_figures, singulation_figures
            from ..pictures.render import render

            plots = folder / "plots"
            plots.mkdir(parents=True, exist_ok=True)
            figures += figures_written(feedrate_figures(fr, plots) + singulation_figures(sg, plots))
            picture = folder / f"{Path(path).stem}.png"
            frame = picture_frame(result.time, summary["steady_to"])
            if oriented:  # the window's frame with the most correct parts, if one has any
                import numpy as np

                from ..pictures.render import most_correct_frame

                t = result.time
                window = np.nonzero((t >= summary["steady_from"]) & (t <= summary["steady_to"]))[0]
                best = most_correct_frame(result, window)
                frame = frame if best is None else best
            figures.append(written(render(result, picture, frame=frame,
                                          color="state" if oriented else "speed").path))
    lines += [f"figure: {f}" for f in figures]
    return "\n".join(lines), reason


def picture_frame(times, steady_to: float) -> int:
    """The frame the demo draws: the last one of the steady window (the track still
    feeding, as late as the measured rate holds); the last frame without a window."""
    import numpy as np

    k = int(np.searchsorted(times, steady_to + 1e-12, side="right")) - 1
    return k if np.isfinite(steady_to) and k >= 0 else -1
