"""``vibrofeed render``: a picture (PNG) of one frame or a movie (MP4) of a run."""

from __future__ import annotations

from .numbers import real, whole

DESCRIPTION = ("Draw a result off-screen (no display needed): the track at the frame's surface "
               "position and the parts with their real shapes (spheres; chips as boxes, discs as "
               "cylinders, oriented), coloured by speed (the scale spans the parts on the track; "
               "faster parts off it are counted on the bar), by cluster of touching parts or, for "
               "boxes, chips and discs, by orientation state (face up, face down, on a side, on an "
               "end; the correctly oriented ones, --correct, in a colour of their own), "
               "true to scale along the track with a scale bar, the run named in the footer. "
               "FILE.png draws one frame (default: the last), FILE.mp4 every frame (frames a whole "
               "number of vibration periods apart are stroboscopic: each frame says so).")


def size(text: str) -> tuple[int, int]:
    """argparse type of --size: WIDTHxHEIGHT in pixels."""
    import argparse

    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be WIDTHxHEIGHT in pixels, got {text or 'nothing'}") from None
    return w, h


def add_arguments(p) -> None:
    p.add_argument("result", metavar="RUN.h5", help="result file")
    p.add_argument("-o", "--output", metavar="FILE.png|FILE.mp4",
                   help="picture (.png) or movie (.mp4) to write (default: RUN.png here)")
    p.add_argument("--frame", type=whole(), metavar="K",
                   help="frame to draw in a PNG, from 0; negative counts from the end (default -1)")
    p.add_argument("--color", choices=("speed", "cluster", "state"), default="speed",
                   help="colour the parts by speed [mm/s], by the size of their cluster of "
                        "touching parts or by their orientation state (up, down, side, end; the "
                        "correct ones green) (default speed)")
    p.add_argument("--correct", metavar="STATE",
                   help="--color state: what counts as correctly oriented, as `vibrofeed orientation "
                        "--correct` reads it: states joined by | (up, down, side, end), then "
                        "lengthwise or any-direction, and lead +x or lead -x (default 'up, lengthwise')")
    p.add_argument("--size", type=size, default=(1280, 720), metavar="WxH",
                   help="picture size in pixels (default 1280x720)")
    p.add_argument("--every", type=whole(1), metavar="N",
                   help="movie: draw every N-th frame (default 1)")
    p.add_argument("--fps", type=real(above=0), help="movie: frames per second (default 25)")
    p.add_argument("--allow-incomplete", action="store_true",
                   help="also draw results of runs that were killed or failed")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar for movies")


def run(args) -> int:
    import sys
    from pathlib import Path

    from ..errors import OutputError
    from ..pictures.render import render
    from .options import no_effect, open_result
    from .outputs import file_destination, not_an_input, replaced

    correct = None
    if args.correct is not None:
        if args.color != "state":
            no_effect("--correct", f"it picks the parts --color state marks correct (not {args.color})")
        else:
            from ..orientation import parse_correct

            correct = parse_correct(args.correct, "--correct")  # before any reading
    output = file_destination("-o", args.output or f"{Path(args.result).stem}.png", (".png", ".mp4"))
    not_an_input("-o" if args.output else None, output, output, [args.result])
    movie = output.suffix.lower() == ".mp4"
    # (given, not defaulted: the options of the other kind of output are named when set)
    if movie and args.frame is not None:
        no_effect("--frame", f"a movie ({output.name}) draws every frame; --frame picks a PNG's")
    for option, value in (("--every", args.every), ("--fps", args.fps)):
        if not movie and value is not None:
            no_effect(option, f"a PNG ({output.name}) is one frame; {option} is for a movie (.mp4)")
    frame = -1 if args.frame is None else args.frame
    every = 1 if args.every is None else args.every
    fps = 25.0 if args.fps is None else args.fps
    with open_result(args) as result:
        bar = None
        if movie and not args.quiet and sys.stderr.isatty():
            from tqdm import tqdm

            bar = tqdm(total=len(range(0, result.n_frames, every)), unit="frame",
                       desc="render", leave=False, file=sys.stderr)
        try:
            # written under a temporary name, checked whole, then renamed: a full disk
            # leaves no cut picture under the name asked for (and keeps an older one)
            with replaced(output) as tmp:
                try:
                    done = render(result, tmp, frame=frame, color=args.color, size=args.size,
                                  every=every, fps=fps, progress=bar.update if bar else None,
                                  correct=correct)
                except OutputError as exc:  # (named as the user named it)
                    raise OutputError(str(exc).replace(str(tmp), str(output))) from None
        finally:
            if bar is not None:
                bar.close()
    w, h = done.size
    what = "1 frame" if done.frames == 1 else f"{done.frames} frames"
    print(f"wrote {output} ({what}, {w}x{h}, {done.seconds:.1f} s)")
    if done.note:
        print(f"note: {done.note}", file=sys.stderr)
    return 0
