#!/usr/bin/env python3
"""Does the fluid's own heap move with the fluid under it? (issue 32, the reference for
"tips carried by the flow"). Pure Python, ~1 s a 10,240-particle frame.

    scripts/bench/heap_motion.py FRAMES_DIR FIRST LAST [--moving A:B] [--radius MM]

On ferro-sim particle files (positions and velocities), with no procedural spikes at all:
the height field h(x, y) is the highest particle centre in each column (square cells one
particle spacing wide), averaged over the 5 x 5 columns around (the heap, not single
particles). The heap's apex is the centroid of (h - median h)^2 over the columns within 8
cells of the highest one; the fluid under it is the mean velocity of the column tops (the
surface particles) within RADIUS (6 mm) of the apex.

A surface feature moves as a shape: its motion is not the fluid's material velocity (a wave
crest travels at the phase speed while the water under it barely moves). A heap dragged by a
sliding magnet is such a feature, and a spike standing on it is another. Per frame it prints
the apex, its horizontal velocity (centred difference) and the fluid's horizontal velocity
under it; over the frames of --moving (default all) the summary line

    apex_travel_mm,apex_speed_mm_s,fluid_speed_mm_s,ratio

gives the apex's net travel over that time, its mean speed, the mean speed along that
direction of the fluid under it, and their ratio.
"""
import argparse
import math
import struct
import sys


def read_particles(path):
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    props, types, count, header = [], [], 0, {}
    for line in data[:end].decode("ascii", "replace").split("\n"):
        w = line.split()
        if w[:2] == ["element", "vertex"]:
            count = int(w[2])
        elif w[:1] == ["property"]:
            props.append(w[-1])
            types.append(w[1])
        elif w[:1] == ["comment"] and len(w) >= 3:
            header.setdefault(w[1], w[2])
    missing = [c for c in ("x", "y", "z", "vx", "vy", "vz") if c not in props]
    if missing:
        sys.exit("heap_motion.py: %s has no %s column" % (path, ", ".join(missing)))
    if any(t not in ("float", "float32") for t in types):
        sys.exit("heap_motion.py: %s: only float32 columns are read (a compact cache? write full particle files)" % path)
    k = len(props)
    values = struct.unpack("<%df" % (k * count), data[end:end + 4 * k * count])
    cols = [props.index(c) for c in ("x", "y", "z", "vx", "vy", "vz")]
    return header, [tuple(values[i * k + c] for c in cols) for i in range(count)]


def apex(path, radius):
    header, particles = read_particles(path)
    c = float(header["spacing"])
    t = float(header["time"])
    top = {}
    for p in particles:
        key = (math.floor(p[0] / c), math.floor(p[1] / c))
        if key not in top or p[2] > top[key][2]:
            top[key] = p
    smooth = {}
    for (i, j) in top:
        zs = [top[(i + a, j + b)][2] for a in range(-2, 3) for b in range(-2, 3) if (i + a, j + b) in top]
        if len(zs) >= 20:  # the full 5 x 5 block but a few columns: not at the rim
            smooth[(i, j)] = sum(zs) / len(zs)
    levels = sorted(smooth.values())
    base = levels[len(levels) // 2]
    peak = max(smooth, key=smooth.get)
    sw = sx = sy = 0.0
    for (i, j), h in smooth.items():
        if (i - peak[0]) ** 2 + (j - peak[1]) ** 2 <= 64 and h > base:
            w = (h - base) ** 2
            sw += w
            sx += w * (i + 0.5) * c
            sy += w * (j + 0.5) * c
    if sw == 0:
        sys.exit("heap_motion.py: %s: no heap (the surface is flat)" % path)
    ax, ay = sx / sw, sy / sw
    under = [q for q in top.values() if (q[0] - ax) ** 2 + (q[1] - ay) ** 2 < radius * radius]
    if not under:
        sys.exit("heap_motion.py: %s: no surface particle within --radius of the apex" % path)
    ux = sum(q[3] for q in under) / len(under)
    uy = sum(q[4] for q in under) / len(under)
    return t, ax, ay, smooth[peak] - base, ux, uy


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("frames_dir")
    ap.add_argument("first", type=int)
    ap.add_argument("last", type=int)
    ap.add_argument("--moving", default=None, help="A:B, the frames the summary covers (default all)")
    ap.add_argument("--radius", type=float, default=6.0, help="fluid under the apex within this [mm]")
    a = ap.parse_args()
    rows = [apex("%s/particles_%04d.ply" % (a.frames_dir, f), a.radius * 1e-3) for f in range(a.first, a.last + 1)]
    print("frame,time_s,apex_x_mm,apex_y_mm,heap_mm,apex_vx_mm_s,apex_vy_mm_s,fluid_vx_mm_s,fluid_vy_mm_s")
    for k, (t, x, y, h, ux, uy) in enumerate(rows):
        lo, hi = max(k - 1, 0), min(k + 1, len(rows) - 1)
        dt = rows[hi][0] - rows[lo][0]
        vx = (rows[hi][1] - rows[lo][1]) / dt if dt > 0 else 0.0
        vy = (rows[hi][2] - rows[lo][2]) / dt if dt > 0 else 0.0
        print("%d,%.4f,%.2f,%.2f,%.2f,%.1f,%.1f,%.1f,%.1f" %
              (a.first + k, t, x * 1e3, y * 1e3, h * 1e3, vx * 1e3, vy * 1e3, ux * 1e3, uy * 1e3))
    s0, s1 = (int(v) - a.first for v in a.moving.split(":")) if a.moving else (0, len(rows) - 1)
    first, last = rows[s0], rows[s1]
    dx, dy = last[1] - first[1], last[2] - first[2]
    travel = math.hypot(dx, dy)
    e = (dx / travel, dy / travel) if travel > 0 else (1.0, 0.0)
    # The fluid's speed along the apex's travel, averaged over the frames (trapezoid in time).
    along = [r[4] * e[0] + r[5] * e[1] for r in rows[s0:s1 + 1]]
    times = [r[0] for r in rows[s0:s1 + 1]]
    span = times[-1] - times[0]
    fluid = sum(0.5 * (along[i] + along[i + 1]) * (times[i + 1] - times[i]) for i in range(len(along) - 1)) / span
    speed = travel / span
    print("# apex_travel_mm,apex_speed_mm_s,fluid_speed_mm_s,ratio")
    print("# %.1f,%.1f,%.1f,%.2f" % (travel * 1e3, speed * 1e3, fluid * 1e3, speed / fluid if fluid else float("inf")))


if __name__ == "__main__":
    main()
