"""``vibrofeed check``: validate result files against the format (FORMAT.md)."""

from __future__ import annotations

import json

from ..errors import EXIT_FAILED

DESCRIPTION = ("Check that result files follow the vibrofeed H5MD layout (FORMAT.md). "
               "Exit status 1 if any file is invalid.")


def add_arguments(p) -> None:
    p.add_argument("files", nargs="+", metavar="FILE.h5")
    p.add_argument("--allow-incomplete", action="store_true",
                   help="accept files of runs that were killed or failed (frames are still checked)")
    p.add_argument("--json", action="store_true", help="print the reports as JSON")


def run(args) -> int:
    from ..results.check import check_file

    reports = [check_file(path, allow_incomplete=args.allow_incomplete) for path in args.files]
    if args.json:
        print(json.dumps([{
            "file": r.path, "ok": r.ok, "frames": r.frames, "parts": r.parts, "status": r.status,
            "problems": [{"level": p.level, "where": "/" + p.where, "message": p.message}
                         for p in r.problems]} for r in reports], indent=2))
    else:
        for r in reports:
            verdict = "OK" if r.ok else "INVALID"
            print(f"{verdict}: {r.path}: {r.frames} frames, {r.parts} parts, status {r.status or '?'}")
            for p in r.problems:
                print(f"  {p}")
    return 0 if all(r.ok for r in reports) else EXIT_FAILED
