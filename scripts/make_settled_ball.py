#!/usr/bin/env python3
"""Cuts a ball of particles from the interior of a settled SPH frame: the fixture
tests/data/settled_ball.ply of tests/sim/magnetics/test_MagnetizationSolver.cpp (disordered
particle sets for the magnetization solver). Pure Python, no dependencies.

How tests/data/settled_ball.ply was made (resting tank: examples/hydrostatic.toml with the
fluid block and box widened to 6 cm, 13,824 particles at 2.5 mm, left 1.5 s from a lattice
at rest; largest particle speed then 1.5 cm/s, 3,615 particles in the ball of 9.5 spacings):

    sed -e 's/max = \\[0.05, 0.05, 0.05\\]/max = [0.06, 0.06, 0.06]/' \\
        -e 's/max = \\[0.05, 0.05, 0.1\\]/max = [0.06, 0.06, 0.12]/' examples/hydrostatic.toml > /tmp/tank.toml
    build/bin/ferro-sim /tmp/tank.toml -o /tmp/tank --threads 1 --max-frames 45
    scripts/make_settled_ball.py /tmp/tank/particles_0045.ply tests/data/settled_ball.ply 9.5

Usage: make_settled_ball.py FRAME.ply OUT.ply RADIUS_IN_SPACINGS
The ball is centred at the fluid's centroid (x, y) at half its height (z); the output is
ASCII PLY with x y z density (the SPH density the frame recorded) and the frame's spacing,
rest density and particle mass as comments, positions relative to the ball's centre.
"""
import math
import struct
import sys

TYPES = {"float": ("f", 4), "double": ("d", 8), "int": ("i", 4), "uint": ("I", 4), "uchar": ("B", 1)}


def read_ply(path):
    with open(path, "rb") as f:
        header = []
        while True:
            line = f.readline().decode("ascii").rstrip("\n")
            header.append(line)
            if line == "end_header":
                break
        comments = [l[len("comment "):] for l in header if l.startswith("comment ")]
        count = next(int(l.split()[2]) for l in header if l.startswith("element vertex"))
        props = [(l.split()[2], l.split()[1]) for l in header if l.startswith("property")]
        if "format binary_little_endian 1.0" not in header:
            sys.exit("make_settled_ball.py: expected a binary little-endian PLY")
        fmt = "<" + "".join(TYPES[t][0] for _, t in props)
        size = struct.calcsize(fmt)
        data = f.read(size * count)
        rows = [struct.unpack_from(fmt, data, i * size) for i in range(count)]
    names = [n for n, _ in props]
    return comments, names, rows


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    comments, names, rows = read_ply(sys.argv[1])
    meta = dict(c.split(" ", 1) for c in comments if " " in c)
    spacing = float(meta["spacing"])
    ix, iy, iz, irho = (names.index(k) for k in ("x", "y", "z", "density"))
    ivx, ivy, ivz = (names.index(k) for k in ("vx", "vy", "vz"))
    n = len(rows)
    cx = sum(r[ix] for r in rows) / n
    cy = sum(r[iy] for r in rows) / n
    zs = sorted(r[iz] for r in rows)
    cz = 0.5 * (zs[0] + zs[-1])
    R = float(sys.argv[3]) * spacing
    ball = [r for r in rows if math.dist((r[ix], r[iy], r[iz]), (cx, cy, cz)) <= R]
    vmax = max(math.sqrt(r[ivx] ** 2 + r[ivy] ** 2 + r[ivz] ** 2) for r in rows)
    print(f"{len(ball)} of {n} particles, centre {cx:.5f} {cy:.5f} {cz:.5f}, max speed {vmax:.2e} m/s")
    with open(sys.argv[2], "w") as out:
        out.write("ply\nformat ascii 1.0\n")
        out.write("comment made by scripts/make_settled_ball.py from a settled resting-tank frame\n")
        for key in ("spacing", "rest_density", "particle_mass", "time"):
            out.write(f"comment {key} {meta[key]}\n")
        out.write(f"element vertex {len(ball)}\n")
        for p in ("x", "y", "z", "density"):
            out.write(f"property float {p}\n")
        out.write("end_header\n")
        for r in ball:
            out.write(f"{r[ix] - cx:.7g} {r[iy] - cy:.7g} {r[iz] - cz:.7g} {r[irho]:.7g}\n")


if __name__ == "__main__":
    main()
