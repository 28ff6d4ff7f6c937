#!/usr/bin/env python3
"""The pattern on a periodic flat layer (issue 32's accurate end): do peaks form, and at what
spacing? Pure Python, no numpy.

    scripts/bench/layer_pattern.py PARTICLES.ply --period LX,LY [--map]

On one ferro-sim particle file of a layer in a box with periodic sides (container.periodic_sides,
the box's x and y extent LX, LY in metres): the height field h(x, y) is the highest particle
centre in each column (square cells about one particle spacing wide, periodic), empty columns
filled from their neighbours. Printed, as key=value words on one line:

    frame time, mean and RMS height [mm], max - min [mm],
    the dominant wavelength [mm]: of the mode (2 pi (m / LX, n / LY)) with the largest power of
        the height's discrete Fourier transform, and the power-weighted mean over the modes
        within 30 % of its wavenumber (so a hexagon's three modes of one length count once);
    peaks: local maxima of h smoothed over 3 x 3 columns standing above the mean by more than
        half the RMS, their count and the mean distance to the nearest other peak (periodic),
        which for a hexagonal lattice is the tip spacing 2 lambda / sqrt(3), for a square one
        lambda.

--map also prints the height field as rows of digits (0-9 from the lowest to the highest column).
"""
import argparse
import cmath
import math
import struct
import sys


def read_particles(path):
    with open(path, "rb") as f:
        data = f.read()
    try:
        end = data.index(b"end_header\n") + len(b"end_header\n")
    except ValueError:
        sys.exit("layer_pattern.py: %s is not a PLY file" % path)
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
    if any(c not in props for c in ("x", "y", "z")):
        sys.exit("layer_pattern.py: %s has no x, y, z columns" % path)
    if any(t not in ("float", "float32") for t in types):
        sys.exit("layer_pattern.py: %s: only float32 columns are read" % path)
    k = len(props)
    if len(data) < end + 4 * k * count:
        sys.exit("layer_pattern.py: %s is truncated" % path)
    values = struct.unpack("<%df" % (k * count), data[end:end + 4 * k * count])
    cx, cy, cz = (props.index(c) for c in ("x", "y", "z"))
    return header, [(values[i * k + cx], values[i * k + cy], values[i * k + cz]) for i in range(count)]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("particles")
    ap.add_argument("--period", required=True, help="LX,LY: the box's x and y extent [m]")
    ap.add_argument("--map", action="store_true")
    a = ap.parse_args()
    try:
        LX, LY = (float(v) for v in a.period.split(","))
    except ValueError:
        sys.exit("layer_pattern.py: --period must be LX,LY in metres (got %r)" % a.period)
    if not (LX > 0 and LY > 0):
        sys.exit("layer_pattern.py: --period must be positive")
    header, pts = read_particles(a.particles)
    if not pts:
        sys.exit("layer_pattern.py: %s holds no particles" % a.particles)
    s = float(header.get("spacing", "0")) or 1e-3
    nx, ny = max(4, round(LX / s)), max(4, round(LY / s))
    top = [[None] * nx for _ in range(ny)]
    x0 = float(header.get("periodic_min_x", "0"))
    y0 = float(header.get("periodic_min_y", "0"))
    for x, y, z in pts:
        if not (math.isfinite(x) and math.isfinite(y) and math.isfinite(z)):
            sys.exit("layer_pattern.py: %s holds a non-finite position" % a.particles)
        i = int(math.floor((x - x0) / LX * nx)) % nx
        j = int(math.floor((y - y0) / LY * ny)) % ny
        if top[j][i] is None or z > top[j][i]:
            top[j][i] = z
    # Fill empty columns from filled neighbours (a few passes).
    for _ in range(4):
        empty = 0
        for j in range(ny):
            for i in range(nx):
                if top[j][i] is not None:
                    continue
                nb = [top[(j + dj) % ny][(i + di) % nx] for dj in (-1, 0, 1) for di in (-1, 0, 1)]
                nb = [v for v in nb if v is not None]
                if nb:
                    top[j][i] = sum(nb) / len(nb)
                else:
                    empty += 1
        if empty == 0:
            break
    flat = [v for row in top for v in row if v is not None]
    mean = sum(flat) / len(flat)
    h = [[(v if v is not None else mean) - mean for v in row] for row in top]
    rms = math.sqrt(sum(v * v for row in h for v in row) / (nx * ny))
    # Discrete Fourier transform of h over the modes |m| <= nx/4, |n| <= ny/4 (wavelengths of
    # 4 columns and longer), half plane (h is real).
    mx, my = nx // 4, ny // 4
    ex = [[cmath.exp(-2j * math.pi * m * i / nx) for i in range(nx)] for m in range(-mx, mx + 1)]
    ey = [[cmath.exp(-2j * math.pi * n * j / ny) for j in range(ny)] for n in range(0, my + 1)]
    rowsum = []  # rowsum[m][j] = sum_i h[j][i] e^{-2 pi i m i / nx}
    for m in range(2 * mx + 1):
        e = ex[m]
        rowsum.append([sum(h[j][i] * e[i] for i in range(nx)) for j in range(ny)])
    modes = []
    for n in range(0, my + 1):
        for m in range(-mx, mx + 1):
            if n == 0 and m <= 0:
                continue
            c = sum(rowsum[m + mx][j] * ey[n][j] for j in range(ny))
            k = 2 * math.pi * math.hypot(m / LX, n / LY)
            modes.append((abs(c) ** 2, k, m, n))
    modes.sort(reverse=True)
    best = modes[0]
    if not best[0] > 0:  # flat to the last bit: no pattern
        print("file=%s time=%s mean_mm=%.3f rms_mm=0 range_mm=0 wavelength_mm=nan ring_wavelength_mm=nan mode=0,0 "
              "peaks=0 peak_spacing_mm=nan" % (a.particles, header.get("time", "?"), 1e3 * mean))
        return
    ring = [(p, k) for p, k, _, _ in modes if abs(k / best[1] - 1) <= 0.3]
    kmean = sum(p * k for p, k in ring) / sum(p for p, _ in ring)
    # Peaks of the 3 x 3 smoothed field.
    sm = [[sum(h[(j + dj) % ny][(i + di) % nx] for dj in (-1, 0, 1) for di in (-1, 0, 1)) / 9 for i in range(nx)]
          for j in range(ny)]
    peaks = []
    for j in range(ny):
        for i in range(nx):
            v = sm[j][i]
            if v <= 0.5 * rms:
                continue
            if all(v >= sm[(j + dj) % ny][(i + di) % nx] for dj in (-2, -1, 0, 1, 2) for di in (-2, -1, 0, 1, 2)):
                peaks.append(((i + 0.5) * LX / nx, (j + 0.5) * LY / ny))
    nn = []
    for p in peaks:
        best_d = float("inf")
        for q in peaks:
            if q is p:
                continue
            dx = (p[0] - q[0]) - LX * round((p[0] - q[0]) / LX)
            dy = (p[1] - q[1]) - LY * round((p[1] - q[1]) / LY)
            best_d = min(best_d, math.hypot(dx, dy))
        if math.isfinite(best_d):
            nn.append(best_d)
    print("file=%s time=%s mean_mm=%.3f rms_mm=%.3f range_mm=%.3f wavelength_mm=%.2f ring_wavelength_mm=%.2f "
          "mode=%d,%d peaks=%d peak_spacing_mm=%s" % (
              a.particles, header.get("time", "?"), 1e3 * mean, 1e3 * rms,
              1e3 * (max(flat) - min(flat)), 1e3 * 2 * math.pi / best[1], 1e3 * 2 * math.pi / kmean,
              best[2], best[3], len(peaks), ("%.2f" % (1e3 * sum(nn) / len(nn))) if nn else "nan"))
    if a.map:
        lo = min(v for row in h for v in row)
        hi = max(v for row in h for v in row)
        for j in reversed(range(ny)):
            print("".join(str(min(9, int(10 * (v - lo) / (hi - lo + 1e-30)))) for v in h[j]))


if __name__ == "__main__":
    main()
