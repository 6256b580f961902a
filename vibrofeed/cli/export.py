"""``vibrofeed export``: a result as a ParaView time series (.pvd of VTK files), or as an H5MD
trajectory for molecular-dynamics tools (MDAnalysis, znh5md/ASE)."""

from __future__ import annotations

from .numbers import whole

DESCRIPTION = ("Write a result as a ParaView time series: DIR/RUN.pvd referencing, per frame, the "
               "parts as points with their fields (id, radius, velocity, speed, orientation "
               "quaternion, glyph-ready axes and shape tensor), the parts' real shapes as "
               "triangles and the track mesh at the frame's position (DIR/RUN/*.vtp); outlet "
               "events, if any, in DIR/RUN_outlet.vtp. Open the .pvd in ParaView as it is. "
               "--format h5md-md writes DIR/RUN.h5md instead: H5MD that MDAnalysis, znh5md and "
               "pyh5md read (lengths in nm, the parts present first at each frame, then padding "
               "rows of id -1: keep id >= 0; znh5md reads it with variable_shape=False, MDAnalysis "
               "takes masses from the file: docs/commands.md, 'Reading an h5md-md export').")


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result file")
    p.add_argument("-o", "--output", metavar="DIR", default=".",
                   help="folder to write into (created if needed; default: here)")
    p.add_argument("--format", choices=("paraview", "h5md-md"), default="paraview",
                   help="paraview: DIR/RUN.pvd (default); h5md-md: DIR/RUN.h5md for MDAnalysis, "
                        "znh5md, pyh5md")
    p.add_argument("--every", type=whole(1), default=1, metavar="N",
                   help="export every N-th frame (default 1)")
    p.add_argument("--no-shapes", action="store_true",
                   help="leave out the parts' triangle meshes (points with their fields only)")
    p.add_argument("--allow-incomplete", action="store_true",
                   help="also export results of runs that were killed or failed")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def run(args) -> int:
    import sys
    from pathlib import Path

    from ..errors import UsageError
    from .options import open_result
    from .outputs import folder_destination, names_in, not_an_input, written

    folder_destination("-o", args.output, create=False, parents=True)
    stem = Path(args.result).stem
    for name in [f"{stem}.h5md"] if args.format == "h5md-md" else [f"{stem}.pvd", f"{stem}_outlet.vtp"]:
        not_an_input("-o", args.output, Path(args.output) / name, [args.result])
    names_in("-o", args.output, [f"{stem}.h5md"] if args.format == "h5md-md" else
             [f"{stem}.pvd", f"{stem}_outlet.vtp"])
    frames = Path(args.output) / stem  # the ParaView export's folder of per-frame files
    if args.format == "paraview" and frames.exists() and not frames.is_dir():
        raise UsageError(f"-o {args.output}: {frames} is a file; the export writes its frames "
                         "into a folder of that name")
    if args.format == "h5md-md":
        if args.no_shapes:
            raise UsageError("--no-shapes is for --format paraview: an h5md-md export has no shapes")
        return _h5md_md(args)
    from ..pictures.export import export

    with open_result(args) as result:
        bar = None
        if not args.quiet and sys.stderr.isatty():
            from tqdm import tqdm

            bar = tqdm(total=len(range(0, result.n_frames, max(args.every, 1))), unit="frame",
                       desc="export", leave=False, file=sys.stderr)
        try:
            done = export(result, args.output, every=args.every, shapes=not args.no_shapes,
                          progress=bar.update if bar else None)
        finally:
            if bar is not None:
                bar.close()
    written(done.pvd)
    print(f"wrote {done.pvd} ({done.frames} frames, {done.files} files, {done.seconds:.1f} s)")
    return 0


def _h5md_md(args) -> int:
    import time
    from pathlib import Path

    from ..errors import OutputError, UsageError
    from ..results.md_export import export_md
    from ..results.reader import unreadable
    from .options import open_result

    if args.every < 1:
        raise UsageError(f"--every must be >= 1, got {args.every}")
    start = time.perf_counter()
    folder = Path(args.output)
    path = folder / (Path(args.result).stem + ".h5md")
    created = not folder.exists()
    try:
        with open_result(args) as result:
            try:
                folder.mkdir(parents=True, exist_ok=True)
                export_md(result, path, every=args.every)
            except OSError as exc:  # (not the result's: an h5py error reading it names the result)
                if unreadable(exc, result.path) is not None:
                    raise
                raise OutputError(f"cannot write {path}: {exc}") from exc
            frames = len(range(0, result.n_frames, args.every))
    except BaseException:
        if created and folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()  # a failed export leaves no folder it made
        raise
    print(f"wrote {path} ({frames} frames, {time.perf_counter() - start:.1f} s)")
    return 0
