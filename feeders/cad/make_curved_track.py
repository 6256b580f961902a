"""The example CAD track of feeders/cad_curved.toml, drawn with build123d and exported as a
designer would: an STL in millimetres.

An S-bend: 4 mm straight, two arcs of 20 mm radius turning 30 degrees right then back left,
4 mm straight (28 mm along x, 5.36 mm across); a U channel swept along it, its floor 1.2 mm
wide between walls 1 mm high, 0.5 mm thick all round. The floor's centre line, the path parts
follow, lies at z = 0 from the origin along +x: the description's ``path`` samples it every
5 degrees on the arcs (:func:`path_points` prints it).

    pip install -e '.[cad]'          # build123d
    python feeders/cad/make_curved_track.py    # writes feeders/cad/curved_track.stl
"""

import math
import sys
from pathlib import Path

RADIUS, TURN, STRAIGHT = 20.0, 30.0, 4.0  # mm, deg, mm
WIDTH, WALL, THICK = 1.2, 1.0, 0.5  # mm: between the walls, their height above the floor, material


def path_points(step: float = 5.0) -> list[tuple[float, float, float]]:
    """The floor's centre line: the straights' ends and the arcs every ``step`` degrees [mm]."""
    a = math.radians(TURN)
    pts = [(0.0, 0.0, 0.0)]
    n = round(TURN / step)
    for i in range(n + 1):  # right turn about (4, -R)
        t = a * i / n
        pts.append((STRAIGHT + RADIUS * math.sin(t), -RADIUS * (1 - math.cos(t)), 0.0))
    cx, cy = STRAIGHT + 2 * RADIUS * math.sin(a), -2 * RADIUS * (1 - math.cos(a)) + RADIUS
    for i in range(1, n + 1):  # back left about its centre, to the x direction again
        t = a * (n - i) / n
        pts.append((cx - RADIUS * math.sin(t), cy - RADIUS * math.cos(t), 0.0))
    end = pts[-1]
    pts.append((end[0] + STRAIGHT, end[1], 0.0))
    return pts


def track():
    """The swept U channel (a build123d Part)."""
    from build123d import CenterArc, Line, Plane, Polyline, Transition, Wire, make_face, sweep

    p = path_points()
    right = CenterArc((STRAIGHT, -RADIUS), RADIUS, 90, -TURN)  # clockwise from the top of its circle
    left = CenterArc((p[-2][0], p[-2][1] + RADIUS), RADIUS, 270 - TURN, TURN)  # to its bottom
    wire = Wire([Line(p[0][:2], p[1][:2]), right, left, Line(p[-2][:2], p[-1][:2])])
    half, out = WIDTH / 2, WIDTH / 2 + THICK
    outline = Polyline((-out, -THICK), (out, -THICK), (out, WALL), (half, WALL), (half, 0), (-half, 0),
                       (-half, WALL), (-out, WALL), close=True)
    profile = Plane.YZ * make_face(outline)  # across the path at its start (x = 0), z up
    return sweep(profile, path=wire, transition=Transition.RIGHT)


def main(argv=None) -> int:
    from build123d import export_stl

    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path(__file__).with_name("curved_track.stl")
    export_stl(track(), str(out), tolerance=0.005, angular_tolerance=0.05)
    print(f"wrote {out}; its path [mm]:")
    print("path = [" + ", ".join(f"[{x:.10g}, {y:.10g}, {z:g}]" for x, y, z in path_points()) + "]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
