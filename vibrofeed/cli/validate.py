"""``vibrofeed validate``: DEM against the analytic models on the validation cases."""

from __future__ import annotations

import json
import sys

from ..errors import EXIT_FAILED, CaseError, RunError

DESCRIPTION = ("Run each validation case (validation/cases/*.toml) through LIGGGHTS and through the "
               "analytic model on the same parameters, print model vs DEM with tolerances and write "
               "PNG figures. Exit status 1 if any quantity is out of tolerance.")


def add_arguments(p) -> None:
    from .options import jobs, ranks

    p.add_argument("cases", nargs="*", metavar="CASE", help="case names (default: all; see --list)")
    # (no defaults here: run() tells an option given from one left out, see RUN_DEFAULTS)
    p.add_argument("-o", "--output", metavar="DIR",
                   help="folder for DEM results and figures (default: validation-results)")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    p.add_argument("--json", action="store_true",
                   help="print the table as JSON rows (case, quantity, model, dem, rel_diff, "
                        "tolerance, passed)")
    p.add_argument("-j", "--jobs", type=jobs, metavar="N",
                   help="DEM runs at once (default 2)")
    p.add_argument("-n", "--ranks", type=ranks, metavar="RANKS",
                   help="MPI ranks per DEM run (default 1)")
    p.add_argument("--reuse", action="store_true",
                   help="reuse DEM results already in DIR that have the run id of the case's run "
                        "(same deck text, parameters and vibrofeed version)")


def _fmt(x: float) -> str:
    if x != x:
        return "nan"
    if x == int(x) and abs(x) < 1e6:
        return f"{int(x)}"
    return f"{x:.6g}"


def table(rows) -> list[str]:
    """The comparison rows as aligned text lines (header, rule, one line a row)."""
    lines = [("case", "quantity", "model", "DEM", "rel diff", "tolerance", "")]
    for r in rows:
        if r.tolerance_type == "abs":
            tol = f"{_fmt(r.tolerance)} {r.unit}".strip()
        elif r.tolerance_type == "sigma":  # the limit it stands for, in the quantity's unit
            tol = f"{_fmt(r.tolerance)} sigma = {r.tolerance * r.error:.3g} {r.unit}".strip()
        else:
            tol = f"{r.tolerance:.1%}"
        rel = "-" if r.rel_diff is None else f"{r.rel_diff:+.2%}"
        lines.append((r.case, r.quantity, _fmt(r.model), _fmt(r.dem), rel,
                      tol, "pass" if r.passed else "FAIL"))
    widths = [max(len(row[i]) for row in lines) for i in range(len(lines[0]))]
    out = []
    for k, row in enumerate(lines):
        out.append("  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip())
        if k == 0:
            out.append("  ".join("-" * w for w in widths))
    return out


# The options only a run of the cases uses: option -> (attribute, default).
RUN_DEFAULTS = {"-o": ("output", "validation-results"), "-j": ("jobs", 2), "-n": ("ranks", 1),
                "--reuse": ("reuse", False)}


def _run_options(args) -> None:
    """With --list, a warning line per run option given (a listing runs nothing); then
    the defaults of those left out."""
    from .options import no_effect

    if args.list and args.cases:
        no_effect("CASE", f"--list lists every case; {' '.join(args.cases)} would pick cases to run")
    for option, (name, default) in RUN_DEFAULTS.items():
        if getattr(args, name) in (None, False):
            setattr(args, name, default)
        elif args.list:
            no_effect(option, "--list only lists the cases; it runs none")


def run(args) -> int:
    from ..validation import cases as C
    from ..validation.crosscheck import CrossCheck

    _run_options(args)
    if args.list:
        cases = [C.find(name) for name in C.available()]
        if args.json:
            print(json.dumps([{"case": c.name, "kind": c.kind, "title": c.title} for c in cases],
                             indent=2))
            return 0
        width = max(len(c.name) for c in cases)
        for case in cases:
            print(f"{case.name:<{width}}  [{case.kind}] {case.title}")
        return 0
    from ..engine.runner import check_at_once
    from .outputs import folder_destination, os_error, written

    check_at_once(args.jobs, args.ranks, ranks_name="-n ")
    selected = [C.find(n) for n in (args.cases or C.available())]
    folder_destination("-o", args.output, create=False, parents=True)
    say = (lambda *a: None) if args.json else (lambda text: print(text, file=sys.stderr))
    rows, figures, failed, errors = [], [], [], []
    for case in selected:
        say(f"== {case.name}: {case.title}")
        check = CrossCheck(case, args.output, ranks=args.ranks, jobs=args.jobs, reuse=args.reuse,
                           on_run=lambda label, state, c=case: say(f"   {c.name} [{label}]: {state}"))
        try:
            outcome = check.run()
            shown = [written(f) for f in outcome.figures]
        except (RunError, CaseError, OSError) as exc:  # one broken case does not stop the others
            text = os_error(exc)[0] if isinstance(exc, OSError) else str(exc)
            errors.append(f"{case.name}: {text}")
            failed.append(case.name)
            say(f"   {case.name}: error: {text}")
            continue
        rows += outcome.rows
        figures += shown
        if not outcome.passed:
            failed.append(case.name)
        if not args.json and len(selected) > 1:
            say("\n".join("   " + line for line in table(outcome.rows)))
    if args.json:
        print(json.dumps([r.as_dict() for r in rows], indent=2))
    else:
        print("\n".join(table(rows)))
        n_fail = sum(not r.passed for r in rows)
        print(f"\n{len(rows) - n_fail}/{len(rows)} quantities within tolerance"
              + (f"; failing cases: {', '.join(failed)}" if failed else ""))
        for f in figures:
            print(f"figure: {f}")
    for e in errors:
        print(f"vibrofeed: error: case {e}", file=sys.stderr)
    return EXIT_FAILED if failed else 0
