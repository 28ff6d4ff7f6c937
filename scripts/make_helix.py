#!/usr/bin/env python3
"""Writes examples/meshes/helix.obj: a steel wire wound as a helix standing on its end, after
the steel helix that ferrofluid climbs in Huang, Hadrich and Michels (SIGGRAPH 2019), for
[[solids]] shape = "mesh" (examples/helix_climb.toml).

    scripts/make_helix.py [OUT.obj]

The wire is a tube of radius r round the helix c(t) = (R cos t, R sin t, z0 + pitch t / 2 pi),
t from 0 to 2 pi turns, axis +z; its cross-sections are circles in the plane of the radial
direction and the binormal, and its two ends are closed by flat discs (a fan round each end's
centre). The lowest point of the wire stands 0.2 mm above z = 0, so that a solid placed on a
dish floor does not cut it. Closed, outward-facing, about 2,900 triangles (under the
surface-charge solve's dense limit of 6,144 panels). Units: metres.
"""
import math
import sys

R_HELIX, R_WIRE, PITCH, TURNS = 0.006, 0.0012, 0.006, 4.0   # [m], [m], rise a turn [m], turns
Z0 = R_WIRE + 0.0002                                          # the centre line's start height [m]
N_ALONG_TURN, N_AROUND = 30, 12                               # rings a turn, vertices a ring


def centre(t):
    return (R_HELIX * math.cos(t), R_HELIX * math.sin(t), Z0 + PITCH * t / (2 * math.pi))


def frame(t):
    """Unit tangent, radial (towards the axis, normal to the tangent) and binormal at t."""
    dx, dy, dz = -R_HELIX * math.sin(t), R_HELIX * math.cos(t), PITCH / (2 * math.pi)
    n = math.sqrt(dx * dx + dy * dy + dz * dz)
    tangent = (dx / n, dy / n, dz / n)
    radial = (-math.cos(t), -math.sin(t), 0.0)
    binormal = (tangent[1] * radial[2] - tangent[2] * radial[1],
                tangent[2] * radial[0] - tangent[0] * radial[2],
                tangent[0] * radial[1] - tangent[1] * radial[0])
    return tangent, radial, binormal


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "examples/meshes/helix.obj"
    rings = int(round(N_ALONG_TURN * TURNS))
    t_end = 2 * math.pi * TURNS
    vertices, faces = [], []
    for k in range(rings + 1):
        t = t_end * k / rings
        c = centre(t)
        _, radial, binormal = frame(t)
        for j in range(N_AROUND):
            a = 2 * math.pi * j / N_AROUND
            ca, sa = math.cos(a), math.sin(a)
            vertices.append(tuple(c[i] + R_WIRE * (ca * radial[i] + sa * binormal[i]) for i in range(3)))

    def v(k, j):
        return k * N_AROUND + (j % N_AROUND) + 1   # OBJ indices start at 1

    # The tube: the ring offsets turn from the radial direction towards the binormal, and the
    # binormal is tangent x radial, so (k, j) -> (k, j + 1) -> (k + 1, j) winds outward.
    for k in range(rings):
        for j in range(N_AROUND):
            faces.append((v(k, j), v(k, j + 1), v(k + 1, j)))
            faces.append((v(k, j + 1), v(k + 1, j + 1), v(k + 1, j)))
    # The ends: a fan round each end's centre, facing back along the tangent at the start and
    # along it at the end.
    start = len(vertices) + 1
    vertices.append(centre(0.0))
    end = len(vertices) + 1
    vertices.append(centre(t_end))
    for j in range(N_AROUND):
        faces.append((start, v(0, j + 1), v(0, j)))
        faces.append((end, v(rings, j), v(rings, j + 1)))

    with open(out, "w") as f:
        f.write("# A steel helix (scripts/make_helix.py): wire radius %g m round a helix of radius %g m,\n"
                "# pitch %g m, %g turns, standing on z = 0 (metres)\n" % (R_WIRE, R_HELIX, PITCH, TURNS))
        for p in vertices:
            f.write("v %.7f %.7f %.7f\n" % p)
        for a, b, c in faces:
            f.write("f %d %d %d\n" % (a, b, c))
    print("%s: %d vertices, %d triangles" % (out, len(vertices), len(faces)))


if __name__ == "__main__":
    main()
