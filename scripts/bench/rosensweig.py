#!/usr/bin/env python3
"""Surface of a flat ferrofluid layer in ferro-sim particle files (issue 13, the Rosensweig
instability). Pure Python (no numpy on the machine); a 10,240-particle frame takes ~1 s,
--spectrum ~1 min.

    scripts/bench/rosensweig.py FRAMES_DIR (--dish RADIUS | --period LX,LY) [--every K]
                                [--margin SPACINGS] [--detrend] [--smooth] [--spectrum]
                                [--sigma S --rho R --g G] [--first T]

The height field h(x, y): the highest particle centre in each column (square cells one
spacing wide, centred on the seed lattice's columns), columns within `margin` spacings of
the dish wall (RADIUS) left out: the meniscus. With --detrend each ring's mean height
(rings one spacing wide) is subtracted first: the axisymmetric part, which the field's
concentration at the dish's edge drives, is not a pattern of peaks. For each frame
(every K-th) it prints:
  t; mean h; RMS of h about its mean (the perturbation amplitude; single column tops
  jitter by ~0.3-0.5 spacing on a disordered surface with no force at all); the change of
  the surface's shape against frame 0 (h averaged over 3 x 3 column blocks, RMS of the
  change about its mean: the mean change is the seed lattice's top layer settling);
  particles with no other particle within the SPH support radius (detached); peaks (local
  maxima of h over the 5 x 5 columns around them, at least one spacing above the mean; with
  --smooth of the 3 x 3-column average over the 7 x 7 columns around, at least half a
  spacing above the mean) and their median nearest-neighbour distance; with --spectrum the wavelength where the
  radially averaged power spectrum of h peaks (4-30 spacings); both against
  lambda_c = 2 pi sqrt(sigma / (rho g)); last, the peaks' mean apex height above the floor
  (the highest column top within 2 columns of each peak).
--period LX,LY: a layer in a box with periodic sides (container.periodic_sides, its x and y
extent in metres, the box's corner at the origin): columns over the whole box, wrapped (no
margin, no detrend), distances to the nearest periodic image, and the spectrum over the box's
own modes 2 pi (m / LX, n / LY) (the dominant one's wavelength). --first T skips frames
before time T.
"""
import argparse
import glob
import math
import os
import struct
import sys


def read_ply(path):
    with open(path, "rb") as f:
        header = {}
        props = []
        count = 0
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            if line.startswith("comment "):
                parts = line.split()
                if len(parts) >= 3:
                    header.setdefault(parts[1], parts[2])
            elif line.startswith("element vertex"):
                count = int(line.split()[2])
            elif line.startswith("property"):
                props.append(line.split()[-1])
            elif line == "end_header":
                break
        data = f.read(4 * len(props) * count)
    values = struct.unpack("<%df" % (len(props) * count), data)
    k = len(props)
    ix, iy, iz = props.index("x"), props.index("y"), props.index("z")
    pts = [(values[i * k + ix], values[i * k + iy], values[i * k + iz]) for i in range(count)]
    return header, pts


def detached(pts, reach):
    cells = {}
    for i, (x, y, z) in enumerate(pts):
        cells.setdefault((math.floor(x / reach), math.floor(y / reach), math.floor(z / reach)), []).append(i)
    lonely = 0
    r2 = reach * reach
    for i, (x, y, z) in enumerate(pts):
        cx, cy, cz = math.floor(x / reach), math.floor(y / reach), math.floor(z / reach)
        found = False
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for dz in (-1, 0, 1):
                    for j in cells.get((cx + dx, cy + dy, cz + dz), ()):
                        if j != i:
                            px, py, pz = pts[j]
                            if (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2 < r2:
                                found = True
                                break
                    if found:
                        break
                if found:
                    break
            if found:
                break
        if not found:
            lonely += 1
    return lonely


def height_field(pts, s, radius):
    h = {}
    for x, y, z in pts:
        if math.hypot(x, y) > radius:
            continue
        key = (math.floor(x / s + 0.5), math.floor(y / s + 0.5))   # cells centred on the seed's columns
        if key not in h or z > h[key]:
            h[key] = z
    return h


class Periodic:
    """The box's columns (nx x ny, about one spacing wide) with wrapped indices."""

    def __init__(self, lx, ly, s):
        self.lx, self.ly = lx, ly
        self.nx, self.ny = max(4, round(lx / s)), max(4, round(ly / s))

    def key(self, i, j):
        return (i % self.nx, j % self.ny)

    def height_field(self, pts):
        h = {}
        for x, y, z in pts:
            key = self.key(math.floor(x / self.lx * self.nx), math.floor(y / self.ly * self.ny))
            if key not in h or z > h[key]:
                h[key] = z
        # A column no particle top fell in (the packing is not a lattice) takes its neighbours' mean.
        for _ in range(4):
            missing = [(i, j) for i in range(self.nx) for j in range(self.ny) if (i, j) not in h]
            if not missing:
                break
            for i, j in missing:
                v = [h[self.key(i + a, j + b)] for a in (-1, 0, 1) for b in (-1, 0, 1) if self.key(i + a, j + b) in h]
                if v:
                    h[(i, j)] = sum(v) / len(v)
        return h

    def position(self, i, j):
        return ((i + 0.5) * self.lx / self.nx, (j + 0.5) * self.ly / self.ny)

    def distance(self, p, q):
        dx = (p[0] - q[0]) - self.lx * round((p[0] - q[0]) / self.lx)
        dy = (p[1] - q[1]) - self.ly * round((p[1] - q[1]) / self.ly)
        return math.hypot(dx, dy)

    def spectrum_peak(self, h, mean):
        """Wavelength [m] of the box mode (m, n) with the largest power of h - mean (modes of
        four columns and longer)."""
        mx, my = self.nx // 4, self.ny // 4
        rows = {}
        for m in range(-mx, mx + 1):
            for j in range(self.ny):
                rows[(m, j)] = sum((h[(i, j)] - mean) * complex(math.cos(2 * math.pi * m * i / self.nx),
                                                                -math.sin(2 * math.pi * m * i / self.nx))
                                   for i in range(self.nx))
        best = (0.0, float("nan"))
        for n in range(0, my + 1):
            for m in range(-mx, mx + 1):
                if n == 0 and m <= 0:
                    continue
                c = sum(rows[(m, j)] * complex(math.cos(2 * math.pi * n * j / self.ny), -math.sin(2 * math.pi * n * j / self.ny))
                        for j in range(self.ny))
                if abs(c) ** 2 > best[0]:
                    best = (abs(c) ** 2, 1 / math.hypot(m / self.lx, n / self.ly))
        return best[1]


def blocks(h):
    """Mean column top over blocks of 3 x 3 columns (at least 8 present): single column tops
    jitter by ~0.45 spacing on a disordered surface at rest."""
    out = {}
    for (i, j), z in h.items():
        out.setdefault((math.floor(i / 3 + 0.5), math.floor(j / 3 + 0.5)), []).append(z)
    return {k: sum(v) / len(v) for k, v in out.items() if len(v) >= 8}


def same(i, j):
    return (i, j)


def smoothed(h, key=same):
    """h averaged over the 3 x 3 columns around each column (those present)."""
    out = {}
    for (i, j) in h:
        v = [h[key(i + a, j + b)] for a in (-1, 0, 1) for b in (-1, 0, 1) if key(i + a, j + b) in h]
        out[(i, j)] = sum(v) / len(v)
    return out


def peaks(h, mean, s, height=1.0, reach=2, key=same, position=None):
    out = []
    for (i, j), z in h.items():
        if z < mean + height * s:
            continue
        best = True
        for di in range(-reach, reach + 1):
            for dj in range(-reach, reach + 1):
                if (di or dj) and h.get(key(i + di, j + dj), -1e9) > z:
                    best = False
        if best:
            out.append(position(i, j) if position else (i * s, j * s))
    return out


def spectrum_peak(h, mean, s):
    """Wavelength [m] of the largest radially averaged power of h - mean (direct DFT)."""
    pts = [(i * s, j * s, z - mean) for (i, j), z in h.items()]
    best = (0.0, 0.0)
    for lam_s in [x * 0.5 for x in range(8, 61)]:   # 4 to 30 spacings
        k = 2 * math.pi / (lam_s * s)
        power = 0.0
        for a in range(12):
            c, d = math.cos(math.pi * a / 12), math.sin(math.pi * a / 12)
            re = im = 0.0
            for x, y, dz in pts:
                ph = k * (c * x + d * y)
                re += dz * math.cos(ph)
                im += dz * math.sin(ph)
            power += re * re + im * im
        if power > best[0]:
            best = (power, lam_s * s)
    return best[1]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("frames")
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--margin", type=float, default=4.0)
    ap.add_argument("--dish", type=float, help="dish radius [m]")
    ap.add_argument("--period", help="LX,LY [m]: a box with periodic sides instead of a dish")
    ap.add_argument("--first", type=float, default=-1.0, help="skip frames before this time [s]")
    ap.add_argument("--sigma", type=float, default=0.025)
    ap.add_argument("--rho", type=float, default=1200.0)
    ap.add_argument("--g", type=float, default=9.81)
    ap.add_argument("--spectrum", action="store_true")
    ap.add_argument("--smooth", action="store_true", help="peaks on the 3x3-column average")
    ap.add_argument("--detrend", action="store_true", help="subtract the ring-mean height (axisymmetric part)")
    a = ap.parse_args()
    box = None
    if (a.dish is None) == (a.period is None):
        sys.exit("rosensweig.py: give either --dish RADIUS or --period LX,LY")
    if a.period is not None:
        try:
            lx, ly = (float(v) for v in a.period.split(","))
        except ValueError:
            sys.exit("rosensweig.py: --period must be LX,LY in metres (got %r)" % a.period)
        if not (lx > 0 and ly > 0):
            sys.exit("rosensweig.py: --period must be positive")
    lam_c = 2 * math.pi * math.sqrt(a.sigma / (a.rho * a.g))
    files = sorted(glob.glob(os.path.join(a.frames, "particles_*.ply")))[:: a.every]
    h0 = None
    print("lambda_c = %.2f mm" % (1e3 * lam_c))
    print("t[s]  mean_h[mm]  rms_h[s]  shape_change_vs_0[s]  detached  peaks  nn_median[mm]  nn/lambda_c  spectrum_peak[mm]"
          "  apex[mm]")
    if not files:
        sys.exit("rosensweig.py: no particles_*.ply in %s" % a.frames)
    for path in files:
        header, pts = read_ply(path)
        if float(header.get("time", "0")) < a.first:
            continue
        s = float(header["spacing"])
        reach = float(header.get("support_radius", 2 * s))
        if a.period is not None:
            box = Periodic(lx, ly, s)
            h = box.height_field(pts)
        else:
            h = height_field(pts, s, a.dish - a.margin * s)
        mean = sum(h.values()) / len(h)
        if a.detrend and box is None:
            # Take out the axisymmetric part (ring means, rings one spacing wide): what
            # the dish's edge does to the whole layer, not a pattern of peaks.
            rings = {}
            for (i, j), z in h.items():
                rings.setdefault(int(math.hypot(i, j)), []).append(z)
            ring_mean = {k: sum(v) / len(v) for k, v in rings.items()}
            h = {(i, j): z - ring_mean[int(math.hypot(i, j))] + mean for (i, j), z in h.items()}
        rms = math.sqrt(sum((z - mean) ** 2 for z in h.values()) / len(h))
        if h0 is None:
            h0 = h
        b, b0 = blocks(h), blocks(h0)
        common = [k for k in b if k in b0]
        d = [b[k] - b0[k] for k in common]
        dmean = sum(d) / max(len(d), 1)
        dh = math.sqrt(sum((x - dmean) ** 2 for x in d) / max(len(d), 1))
        # Peaks: on single column tops (at least one spacing above the mean, highest of the
        # 5 x 5 columns around), or with --smooth on the 3 x 3 column average (at least half a
        # spacing above the mean, highest of the 7 x 7 columns around: crests closer than
        # 3 columns = lambda_c / 2.5 at the example's spacing merge), which column-top jitter
        # hardly reaches.
        key = box.key if box else same
        position = box.position if box else None
        pk = peaks(smoothed(h, key), mean, s, 0.5, 3, key, position) if a.smooth else peaks(h, mean, s, key=key, position=position)
        # Each peak's apex: the highest column top within 2 columns of it.
        cols = peaks(smoothed(h, key), mean, s, 0.5, 3, key, lambda i, j: (i, j)) if a.smooth else \
            peaks(h, mean, s, key=key, position=lambda i, j: (i, j))
        tops = [max(h[key(i + di, j + dj)] for di in range(-2, 3) for dj in range(-2, 3) if key(i + di, j + dj) in h)
                for i, j in cols]
        apex = sum(tops) / len(tops) if tops else float("nan")
        distance = box.distance if box else (lambda p, q: math.hypot(p[0] - q[0], p[1] - q[1]))
        nn = []
        for p in pk:
            d = min((distance(p, q) for q in pk if q is not p), default=None)
            if d is not None:
                nn.append(d)
        nn.sort()
        med = nn[len(nn) // 2] if nn else float("nan")
        spec = float("nan")
        if a.spectrum:
            spec = box.spectrum_peak(h, mean) if box else spectrum_peak(h, mean, s)
        print("%.3f  %.3f  %.3f  %.3f  %d  %d  %.2f  %.2f  %.2f  %.2f" % (
            float(header.get("time", "nan")), 1e3 * mean, rms / s, dh / s, detached(pts, reach), len(pk),
            1e3 * med, med / lam_c, 1e3 * spec, 1e3 * apex))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
