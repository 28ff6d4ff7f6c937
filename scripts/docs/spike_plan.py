#!/usr/bin/env python3
"""The plan view of a spiky mesh: its highest surface over a square window, as a matrix of
heights [mm] that gnuplot draws with `matrix with image` (docs/look-guide.md shows the
lattice's planform this way: a perspective render hides it behind the spikes' lean).

    scripts/docs/spike_plan.py SPIKY.ply OUT.dat --centre=X,Y --half H [--cells N]

X, Y, H in metres (the window is [X - H, X + H] x [Y - H, Y + H]); N cells a side (200).
Cells no vertex falls in take their neighbours' mean. Needs NumPy (python3-numpy).
"""
import argparse
import sys

try:
    import numpy as np
except ImportError:
    sys.exit("spike_plan.py: needs NumPy (apt install python3-numpy, or scripts/install-deps.sh --with-bench)")


def read_vertices(path):
    """x, y, z of the upward-facing vertices of a binary little-endian PLY whose vertex
    properties are all float32."""
    try:
        with open(path, "rb") as f:
            props, count, element = [], 0, None
            while True:
                line = f.readline()
                if not line:
                    sys.exit("spike_plan.py: %s: no end_header" % path)
                words = line.decode("ascii", "replace").split()
                if words[:1] == ["element"]:
                    element = words[1]
                    if element == "vertex":
                        count = int(words[2])
                elif words[:1] == ["property"] and element == "vertex":
                    if words[1] != "float":
                        sys.exit("spike_plan.py: %s: vertex property %s is not float" % (path, words[-1]))
                    props.append(words[-1])
                elif words == ["end_header"]:
                    break
            data = np.frombuffer(f.read(4 * len(props) * count), dtype="<f4")
    except OSError as e:
        sys.exit("spike_plan.py: %s" % e)
    if data.size != len(props) * count or not {"x", "y", "z"} <= set(props):
        sys.exit("spike_plan.py: %s: not a binary PLY with float x, y, z" % path)
    v = data.reshape(count, len(props))
    # The upper surface only (outward normal up, where the mesh has normals): the floor's
    # underside under a cell would otherwise stand in for a top no vertex fell on.
    up = v[:, props.index("nz")] > 0 if "nz" in props else np.ones(count, dtype=bool)
    return v[up, props.index("x")], v[up, props.index("y")], v[up, props.index("z")]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("mesh")
    ap.add_argument("out")
    ap.add_argument("--centre", required=True, help="X,Y [m]")
    ap.add_argument("--half", type=float, required=True, help="half the window's side [m]")
    ap.add_argument("--cells", type=int, default=200)
    a = ap.parse_args()
    try:
        cx, cy = (float(w) for w in a.centre.split(","))
    except ValueError:
        sys.exit("spike_plan.py: --centre must be X,Y in metres (got %r)" % a.centre)
    if not (a.half > 0 and a.cells >= 8):
        sys.exit("spike_plan.py: --half must be > 0 and --cells >= 8")
    x, y, z = read_vertices(a.mesh)
    n = a.cells
    inside = (np.abs(x - cx) < a.half) & (np.abs(y - cy) < a.half)
    if not inside.any():
        sys.exit("spike_plan.py: %s: no vertex inside the window" % a.mesh)
    i = np.clip(((x[inside] - cx + a.half) / (2 * a.half) * n).astype(int), 0, n - 1)
    j = np.clip(((y[inside] - cy + a.half) / (2 * a.half) * n).astype(int), 0, n - 1)
    top = np.full((n, n), -np.inf)
    np.maximum.at(top, (j, i), 1e3 * z[inside].astype(float))
    top[~np.isfinite(top)] = np.nan
    for _ in range(4):
        empty = np.isnan(top)
        if not empty.any():
            break
        pad = np.pad(top, 1, constant_values=np.nan)
        ring = np.stack([pad[p:p + n, q:q + n] for p in range(3) for q in range(3)])
        count = np.sum(~np.isnan(ring), axis=0)
        mean = np.where(count > 0, np.nansum(ring, axis=0) / np.maximum(count, 1), np.nan)
        top[empty] = mean[empty]
    np.savetxt(a.out, np.nan_to_num(top, nan=float(np.nanmin(top))), fmt="%.4f")


if __name__ == "__main__":
    main()
