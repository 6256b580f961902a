"""Write plate.stl: the unit plate of the single-part decks.

A strip along x from -0.5 to 0.5, 0.005 wide (y from -0.0025 to 0.0025), at
z = 0, normal +z, split into 20 rectangles of two triangles so no triangle is
thinner than 10:1. Decks scale it by the plate length they need; the strip is
narrow so the simulation box, and LIGGGHTS' neighbour bins, stay small across
the track (a single part feels no force along y and stays at y = 0).

    python decks/meshes/make_plate.py > decks/meshes/plate.stl
"""

N, HALF_WIDTH = 20, 0.0025


def facet(a, b, c):
    return ("  facet normal 0 0 1\n    outer loop\n"
            + "".join(f"      vertex {x:.6g} {y:.6g} 0\n" for x, y in (a, b, c))
            + "    endloop\n  endfacet\n")


def main():
    out = ["solid plate\n"]
    for i in range(N):
        x0, x1 = -0.5 + i / N, -0.5 + (i + 1) / N
        lo, hi = -HALF_WIDTH, HALF_WIDTH
        out.append(facet((x0, lo), (x1, lo), (x1, hi)))
        out.append(facet((x0, lo), (x1, hi), (x0, hi)))
    out.append("endsolid plate\n")
    print("".join(out), end="")


if __name__ == "__main__":
    main()
