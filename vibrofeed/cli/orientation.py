"""``vibrofeed orientation``: how many parts a feeder delivers the right way up."""

from __future__ import annotations

import sys

from ..values import fmt
from .numbers import real
from .options import print_figures, refuse, slips, unmeasured

DESCRIPTION = ("Orientation of the parts a bulk feeder of clumps (chips, discs, boxes) delivers, over "
               "the steady window: the fraction face up, face down, on a side and on an end at the "
               "outlet, the fraction correctly oriented (the run's parameter correct, or --correct), "
               "the rate of correctly oriented "
               "single parts with its error, the parts per second sent back (recirculation), and for "
               "each tooling station (gate, side drop, wiper, air jet) the states of the parts in and "
               "out, its orienting efficiency and the share it takes off.")
# An angle below this many degrees is more likely radians (0.35 rad is 20 degrees).
RADIANS_BELOW = 1.6
# The rates and fractions too few exits do not measure.
RATE_KEYS = ("correct_fraction", "correct_rate", "correct_rate_err", "oriented_rate", "oriented_rate_err",
             "lengthwise_fraction", "singulated_fraction")


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result of a bulk-feeder deck whose parts are clumps")
    p.add_argument("--correct", metavar="STATE",
                   help="what counts as correctly oriented: states joined by | (up, down, side, end), "
                        "then lengthwise or any-direction, and lead +x or lead -x (default: the run's "
                        "parameter correct, 'up, lengthwise' for a result that records none); given, "
                        "it overrides the run's, and the figures say so")
    p.add_argument("--within", type=real(above=0, at_most=90), default=20.0, metavar="DEG",
                   help="lengthwise: the long axis within DEG degrees of the path (default 20)")
    p.add_argument("--start", type=real(), metavar="S", help="start of the window [s] (default: "
                   "the detected steady window)")
    p.add_argument("--end", type=real(), metavar="S", help="end of the window [s]")
    p.add_argument("--json", action="store_true", help="print the figures as JSON")
    p.add_argument("--plot", metavar="FILE.png",
                   help="write the states along the path, stations marked, as a PNG")


def radians_advice(option: str, degrees: float | None) -> str | None:
    """One line when an angle in degrees looks like one in radians."""
    if degrees is None or not 0 < degrees < RADIANS_BELOW:
        return None
    return (f"{option} {degrees:g} deg looks like radians ({degrees:g} rad is "
            f"{degrees * 57.29577951308232:.3g} deg; {option} is in degrees)")


def _states(fractions: dict) -> str:
    return ", ".join(f"{name} {fmt(v, 100, '.1f')} %" for name, v in fractions.items())


def _source(s: dict) -> str:
    """Where the rule came from: the run's parameter correct, or --correct over it."""
    if s.get("correct_source") == "given":
        return f"--correct, overriding the run's {s.get('run_correct')}"
    return "the run's parameter correct"


def table(s: dict) -> str:
    """The figures as the command prints them."""
    source = {"returned": "returned to the inlet (the run recirculates)",
              "rejected": "rejected (what a return would send back; the run removes them)",
              "fell": "fallen back into the bowl, and its exit line's rejects"}[s["recirculation_source"]]
    lines = [
        f"window         {fmt(s['steady_from'])} .. {fmt(s['steady_to'])} s, {s['n_delivered']} parts "
        "delivered" + (f"; {s['reason']}" if s.get("reason") else ""),
        f"correct        {s['correct']} ({_source(s)}; lengthwise within {s['within']:g} deg)",
        f"oriented rate  {fmt(s['oriented_rate'], spec='.4g')} ± {fmt(s['oriented_rate_err'], spec='.2g')} "
        f"parts/s correct and single (of {fmt(s['parts_per_s'], spec='.4g')} parts/s; correct "
        f"{fmt(s['correct_rate'], spec='.4g')} ± {fmt(s['correct_rate_err'], spec='.2g')} parts/s)",
        f"at the outlet  {_states(s['state_fractions'])}; lengthwise "
        f"{fmt(s['lengthwise_fraction'], 100, '.1f')} %; correct {fmt(s['correct_fraction'], 100, '.1f')} %, "
        f"single {fmt(s['singulated_fraction'], 100, '.1f')} %",
        f"recirculation  {fmt(s['recirculation_per_s'], spec='.4g')} ± "
        f"{fmt(s['recirculation_per_s_err'], spec='.2g')} parts/s {source}",
    ]
    if not s["stations"]:
        lines.append("stations       none (the feeder has no tooling)")
    else:
        lines.append("station          in  correct     out  correct  efficiency  taken off  rejects/s")
    for st in s["stations"]:
        rejects = "-" if st["rejects_per_s"] is None else fmt(st["rejects_per_s"], spec=".3g")
        out = "outlet" if st["out_at"] == "outlet" else ""
        lines.append(f"  {st['name']:<14} {st['n_in']:>4}  {fmt(st['correct_in'], 100, '.1f'):>5} %  "
                     f"{st['n_out']:>6}  {fmt(st['correct_out'], 100, '.1f'):>5} %  "
                     f"{fmt(st['efficiency'], spec='.3g'):>10}  "
                     f"{fmt(st['rejected_share'], 100, '.1f'):>7} %  "
                     f"{rejects:>9}" + (f"  (out: {out})" if out else ""))
    return "\n".join(lines)


def run(args) -> int:
    from ..orientation import parse_correct
    from ..postproc.orientation import Orientation
    from ..results.reader import Result
    from .outputs import file_destination, written

    correct = None  # the run's own, read from the result
    if args.correct is not None:
        correct = parse_correct(args.correct, "--correct", args.within)  # before any reading
    slips(("--start", args.start, "s"), ("--end", args.end, "s"))
    advice = radians_advice("--within", args.within)
    if advice:
        print(f"vibrofeed: warning: {advice}", file=sys.stderr)
    plot = file_destination("--plot", args.plot, (".png",)) if args.plot is not None else None
    with Result(args.result) as result:
        analysis = Orientation(result, correct=correct, within=args.within, start=args.start,
                               end=args.end).run()
        summary = analysis.summary()
        figures = []
        if plot is not None:
            from ..pictures.plots import orientation_figure

            figures = [written(orientation_figure(analysis, plot))]
    reason = unmeasured(summary, RATE_KEYS)
    print_figures(summary, figures, args.json, table)
    return refuse(args.result, reason)
