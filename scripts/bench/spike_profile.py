#!/usr/bin/env python3
"""How far a spike pattern's shape is from its fundamental Fourier mode (issue 32).

Gollwitzer et al. (J. Fluid Mech. 2007, arXiv nlin/0604009, abstract) measured the surface of
a ferrofluid layer in a uniform field and found that "the fundamental Fourier mode
approximates the shape to within 10 % accuracy for a range of up to 40 % of the bifurcation
parameter": near onset a spike is the sum of three cosines (the paper's eq. 13, Ferro's
`sharpness = 1`); only further up do the harmonics that sharpen the tips and flatten the
troughs matter. This script measures the same thing on a simulated layer in a box with
periodic sides, and on Ferro's procedural profile.

    scripts/bench/spike_profile.py FRAMES_DIR --period LX,LY --window LABEL:T0:T1 [...]
                                   [--cell C] [--profile-csv OUT]
    scripts/bench/spike_profile.py --procedural P1,P2,...

The surface: along vertical lines on a grid of cells C wide (default half a particle
spacing), the height where the particles' colour field sum_j s^3 W(|x - x_j|, s) (cubic spline,
support 2 s, s the spacing; 1 inside the fluid) falls to 0.5. Its box modes (a direct DFT over
the periodic grid) split it in three: the mean, the fundamental (the band of modes with
wavenumbers within 0.75-1.3 of the centre that holds the most power, the centre a mode of
at least two wavelengths across the box: the pattern's wave vectors, which a box of a few
wavelengths only approximately holds), and the rest: longer modes (the box-scale unequal
heights of a few peaks) and shorter ones (the harmonics). Each frame of a window [T0, T1] is measured alone (peaks that wander would blur
an averaged surface) and the window prints the frames' means:
  ptp_mm      the surface's peak-to-trough height
  lambda_mm   the fundamental band's power-weighted wavelength (the median over the frames)
  dev_max     max |surface - (mean + fundamental)| over the box, over ptp: Gollwitzer's "within
              10 %" read as the largest deviation against the spike's height
  dev_rms     the same deviation's RMS over ptp
  below       the share of the surface's variance in modes longer than the band (disorder)
  above       the share in modes shorter than the band (harmonics: the shape)
  band_mm     the fundamental band's RMS amplitude
  move        RMS change of the surface from one frame to the next, over ptp (a standing
              pattern: the column jitter only; peaks that wander: of order 1)
--profile-csv writes one spike's profile per window, from its last frame: a cut from the
highest point through the nearest other peak, the surface and its fundamental against the
distance.

--procedural: dev_max, dev_rms and above on Ferro's hexagonal profile (spikes/SpikePhysics.hpp:
hexProfile sharpened by sharpenedProfile with exponent p) sampled on one periodic cell of the
lattice (tip spacing l by sqrt(3) l).
"""
import argparse
import cmath
import glob
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rosensweig import read_ply  # noqa: E402


def cubic_spline(r, h):
    """The M4 cubic spline kernel in 3D, support 2 h."""
    q = r / h
    if q >= 2.0:
        return 0.0
    sigma = 1.0 / (math.pi * h ** 3)
    if q < 1.0:
        return sigma * (1.0 - 1.5 * q * q + 0.75 * q ** 3)
    return sigma * 0.25 * (2.0 - q) ** 3


class Grid:
    """nx x ny cells over a periodic box LX x LY (corner at the origin)."""

    def __init__(self, lx, ly, cell):
        self.lx, self.ly = lx, ly
        self.nx, self.ny = max(8, round(lx / cell)), max(8, round(ly / cell))

    def centre(self, i, j):
        return ((i + 0.5) * self.lx / self.nx, (j + 0.5) * self.ly / self.ny)


def surface_heights(pts, grid, s):
    """The colour field's 0.5 level along each cell's vertical line [m]."""
    h = s
    reach = 2 * h
    volume = s ** 3
    bins = {}
    bx, by = max(1, int(grid.lx / reach)), max(1, int(grid.ly / reach))
    wx, wy = grid.lx / bx, grid.ly / by
    for x, y, z in pts:
        bins.setdefault((math.floor(x / wx) % bx, math.floor(y / wy) % by), []).append((x, y, z))
    out = [[0.0] * grid.ny for _ in range(grid.nx)]
    for i in range(grid.nx):
        for j in range(grid.ny):
            cx, cy = grid.centre(i, j)
            ci, cj = int(cx / wx), int(cy / wy)
            near = []   # (horizontal distance^2, z) of the particles within reach of the line
            # Each bin once (a box only one or two bins across would visit a bin twice).
            for key in {((ci + a) % bx, (cj + b) % by) for a in (-1, 0, 1) for b in (-1, 0, 1)}:
                for x, y, z in bins.get(key, ()):
                    dx = x - cx - grid.lx * round((x - cx) / grid.lx)
                    dy = y - cy - grid.ly * round((y - cy) / grid.ly)
                    d2 = dx * dx + dy * dy
                    if d2 < reach * reach:
                        near.append((d2, z))
            if not near:
                out[i][j] = float("nan")
                continue

            def colour(zz):
                c = 0.0
                for d2, z in near:
                    dz = z - zz
                    if -reach < dz < reach:
                        c += volume * cubic_spline(math.sqrt(d2 + dz * dz), h)
                return c

            hi = max(z for _, z in near) + reach
            lo = hi - 0.5 * s
            while colour(lo) < 0.5 and lo > hi - 60 * s:
                hi, lo = lo, lo - 0.5 * s
            for _ in range(8):
                mid = 0.5 * (lo + hi)
                if colour(mid) < 0.5:
                    hi = mid
                else:
                    lo = mid
            out[i][j] = 0.5 * (lo + hi)
    # A line with no fluid under it (a gap between towers) takes its neighbours' mean.
    for i in range(grid.nx):
        for j in range(grid.ny):
            if math.isnan(out[i][j]):
                v = [out[(i + a) % grid.nx][(j + b) % grid.ny] for a in (-1, 0, 1) for b in (-1, 0, 1)]
                v = [x for x in v if not math.isnan(x)]
                out[i][j] = sum(v) / len(v) if v else 0.0
    return out


def dft(field, nx, ny):
    """Box modes F[m][n] (m in 0..nx-1, n in 0..ny-1) of a periodic nx x ny field."""
    rows = [[sum(field[i][j] * cmath.exp(-2j * math.pi * m * i / nx) for i in range(nx)) for j in range(ny)]
            for m in range(nx)]
    return [[sum(rows[m][j] * cmath.exp(-2j * math.pi * n * j / ny) for j in range(ny)) for n in range(ny)]
            for m in range(nx)]


def signed(m, n):
    return m - n if m > n // 2 else m


def fundamental(field, lx, ly):
    """(mean, fundamental field, its wavelength [m]) of a periodic field. The fundamental is
    the band of box modes with wavenumbers within 0.75-1.3 of a centre k0, k0 the box mode's
    wavenumber whose band holds the most power (the most favourable band: a few irregular
    peaks in a small box spread their power over several modes near the pattern's wavenumber);
    its wavelength is the band's power-weighted mean."""
    nx, ny = len(field), len(field[0])
    F = dft(field, nx, ny)
    modes = [(math.hypot(signed(m, nx) / lx, signed(n, ny) / ly), abs(F[m][n]) ** 2, m, n)
             for m in range(nx) for n in range(ny) if m or n]
    best = None
    # Band centres: modes of at least two wavelengths across the box in x or y (the box-scale
    # modes (1, 0), (1, 1) are the unequal heights of a few peaks, not a pattern's wavelength).
    centres = set(round(k, 6) for k, _, m, n in modes if max(abs(signed(m, nx)), abs(signed(n, ny))) >= 2)
    for k0 in sorted(centres):
        power = sum(p for k, p, _, _ in modes if 0.75 * k0 <= k <= 1.3 * k0)
        if best is None or power > best[0]:
            best = (power, k0)
    k0 = best[1]
    shell = [(k, p, m, n) for k, p, m, n in modes if 0.75 * k0 <= k <= 1.3 * k0]
    kmean = sum(k * p for k, p, _, _ in shell) / max(sum(p for _, p, _, _ in shell), 1e-300)
    mean = F[0][0].real / (nx * ny)
    fund = [[mean + sum((F[m][n] * cmath.exp(2j * math.pi * (m * i / nx + n * j / ny))).real for _, _, m, n in shell)
             / (nx * ny) for j in range(ny)] for i in range(nx)]
    # The variance below and above the band (Parseval: power / (nx ny)^2 per mode).
    scale = 1.0 / (nx * ny) ** 2
    below = scale * sum(p for k, p, _, _ in modes if k < 0.75 * k0)
    above = scale * sum(p for k, p, _, _ in modes if k > 1.3 * k0)
    band = scale * sum(p for _, p, _, _ in shell)
    return mean, fund, 1.0 / kmean if kmean > 0 else float("nan"), below, band, above


def measures(field, lx, ly):
    nx, ny = len(field), len(field[0])
    mean, fund, lam, below, band, above = fundamental(field, lx, ly)
    values = [v for row in field for v in row]
    ptp = max(values) - min(values)
    dev = [field[i][j] - fund[i][j] for i in range(nx) for j in range(ny)]
    var = sum((v - mean) ** 2 for v in values) / len(values)
    return {
        "ptp": ptp,
        "lambda": lam,
        "dev_max": max(abs(d) for d in dev) / ptp,
        "dev_rms": math.sqrt(sum(d * d for d in dev) / len(dev)) / ptp,
        "below": below / var if var > 0 else 0.0,
        "above": above / var if var > 0 else 0.0,
        "band_rms": math.sqrt(band),
        "fund": fund,
    }


def bilinear(field, grid, x, y):
    u = (x / grid.lx * grid.nx - 0.5) % grid.nx
    v = (y / grid.ly * grid.ny - 0.5) % grid.ny
    i, j = int(u), int(v)
    fu, fv = u - i, v - j
    i, j = i % grid.nx, j % grid.ny   # u % nx can round up to nx itself
    i1, j1 = (i + 1) % grid.nx, (j + 1) % grid.ny
    return ((1 - fu) * (1 - fv) * field[i][j] + fu * (1 - fv) * field[i1][j] +
            (1 - fu) * fv * field[i][j1] + fu * fv * field[i1][j1])


def profile_cut(field, fund, grid):
    """A cut from the highest cell through the nearest other local maximum (7 x 7 cells):
    [(distance [m], surface, fundamental)], from one tip spacing before the tip to two after."""
    nx, ny = grid.nx, grid.ny
    top = max(((i, j) for i in range(nx) for j in range(ny)), key=lambda c: field[c[0]][c[1]])
    mean = sum(v for row in field for v in row) / (nx * ny)
    maxima = []
    for i in range(nx):
        for j in range(ny):
            v = field[i][j]
            if v > mean and all(field[(i + a) % nx][(j + b) % ny] <= v for a in range(-3, 4) for b in range(-3, 4)):
                maxima.append((i, j))
    p = grid.centre(*top)
    best = None
    for c in maxima:
        if c == top:
            continue
        q = grid.centre(*c)
        dx = q[0] - p[0] - grid.lx * round((q[0] - p[0]) / grid.lx)
        dy = q[1] - p[1] - grid.ly * round((q[1] - p[1]) / grid.ly)
        d = math.hypot(dx, dy)
        if d > 0 and (best is None or d < best[0]):
            best = (d, dx / d, dy / d)
    if best is None:
        return []
    d, ux, uy = best
    cut = []
    for k in range(-40, 81):
        t = k * d / 40.0
        x, y = p[0] + t * ux, p[1] + t * uy
        cut.append((t, bilinear(field, grid, x, y), bilinear(fund, grid, x, y)))
    return cut


def hex_profile(a, b):
    return math.cos(2 * math.pi * (a + b)) + math.cos(2 * math.pi * a) + math.cos(2 * math.pi * b)


def sharpened(F, p):
    if p == 1.0:
        return F
    t = min(1.0, max(0.0, (F + 1.5) / 4.5))
    return 4.5 * t ** p - 1.5


def procedural(ps):
    """Ferro's hexagonal spikes on one periodic cell: tip spacing l = 1 along x, sqrt(3) along y
    (two tips per cell: (0, 0) and (1/2, sqrt(3)/2))."""
    nx, ny = 24, 42
    lx, ly = 1.0, math.sqrt(3.0)
    print("p  dev_max  dev_rms  above")
    for p in ps:
        field = []
        for i in range(nx):
            row = []
            for j in range(ny):
                x, y = (i + 0.5) * lx / nx, (j + 0.5) * ly / ny
                # lattice coordinates: x = a + b/2, y = b sqrt(3)/2
                b = y / (math.sqrt(3.0) / 2)
                a = x - b / 2
                row.append(sharpened(hex_profile(a, b), p))
            field.append(row)
        r = measures(field, lx, ly)
        print("%g  %.3f  %.3f  %.3f" % (p, r["dev_max"], r["dev_rms"], r["above"]))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("frames", nargs="?")
    ap.add_argument("--period", help="LX,LY [m] of the box with periodic sides (corner at the origin)")
    ap.add_argument("--window", action="append", default=[], help="LABEL:T0:T1 [s], repeatable")
    ap.add_argument("--cell", type=float, default=0.0, help="grid cell [m]; 0 = half the spacing")
    ap.add_argument("--profile-csv", help="write each window's spike profile here")
    ap.add_argument("--procedural", help="sharpness exponents p, comma-separated")
    a = ap.parse_args()
    if a.procedural:
        try:
            ps = [float(v) for v in a.procedural.split(",")]
        except ValueError:
            sys.exit("spike_profile.py: --procedural takes numbers >= 1, comma-separated (got %r)" % a.procedural)
        if any(not p >= 1 for p in ps):
            sys.exit("spike_profile.py: --procedural takes numbers >= 1")
        procedural(ps)
        return
    if not a.frames or not a.period or not a.window:
        sys.exit("spike_profile.py: give FRAMES_DIR, --period LX,LY and at least one --window LABEL:T0:T1")
    try:
        lx, ly = (float(v) for v in a.period.split(","))
    except ValueError:
        sys.exit("spike_profile.py: --period must be LX,LY in metres (got %r)" % a.period)
    if not (lx > 0 and ly > 0):
        sys.exit("spike_profile.py: --period must be positive (got %r)" % a.period)
    windows = []
    for w in a.window:
        parts = w.split(":")
        try:
            windows.append((parts[0], float(parts[1]), float(parts[2])))
        except (IndexError, ValueError):
            sys.exit("spike_profile.py: --window must be LABEL:T0:T1 (got %r)" % w)
    files = sorted(glob.glob(os.path.join(a.frames, "particles_*.ply")))
    if not files:
        sys.exit("spike_profile.py: no particles_*.ply in %s" % a.frames)
    times = {}
    for path in files:
        with open(path, "rb") as f:
            head = f.read(4000).decode("ascii", "replace")
        for line in head.splitlines():
            if line.startswith("comment time "):
                times[path] = float(line.split()[2])
                break
    print("label  frames  ptp_mm  lambda_mm  dev_max  dev_rms  below  above  band_mm  move")
    cuts = []
    for label, t0, t1 in windows:
        chosen = [p for p in files if t0 - 1e-6 <= times.get(p, -1) <= t1 + 1e-6]
        if not chosen:
            sys.exit("spike_profile.py: no frame in window %s (%g-%g s)" % (label, t0, t1))
        fields, rows = [], []
        for path in chosen:
            header, pts = read_ply(path)
            if "spacing" not in header:
                sys.exit("spike_profile.py: %s has no 'comment spacing' (not a ferro-sim particle file?)" % path)
            s = float(header["spacing"])
            grid = Grid(lx, ly, a.cell if a.cell > 0 else 0.5 * s)
            fields.append(surface_heights(pts, grid, s))
            rows.append(measures(fields[-1], lx, ly))
        nx, ny = grid.nx, grid.ny
        # How far the surface moves between frames, against its height (a standing pattern: the
        # column jitter only; a pattern whose peaks wander: of order 1).
        moves = [math.sqrt(sum((g[i][j] - f[i][j]) ** 2 for i in range(nx) for j in range(ny)) / (nx * ny)) / r["ptp"]
                 for f, g, r in zip(fields, fields[1:], rows[1:])]
        lams = sorted(r["lambda"] for r in rows)

        def mean(key):
            return sum(r[key] for r in rows) / len(rows)

        print("%s  %d  %.2f  %.2f  %.3f  %.3f  %.3f  %.3f  %.4f  %s" % (
            label, len(chosen), 1e3 * mean("ptp"), 1e3 * lams[len(lams) // 2], mean("dev_max"), mean("dev_rms"),
            mean("below"), mean("above"), 1e3 * mean("band_rms"), "%.3f" % (sum(moves) / len(moves)) if moves else "nan"))
        sys.stdout.flush()
        for t, v, f in profile_cut(fields[-1], rows[-1]["fund"], grid):
            cuts.append((label, t, v, f))
    if a.profile_csv:
        with open(a.profile_csv, "w") as out:
            out.write("label,distance_mm,surface_mm,fundamental_mm\n")
            for label, t, v, f in cuts:
                out.write("%s,%.3f,%.3f,%.3f\n" % (label, 1e3 * t, 1e3 * v, 1e3 * f))


if __name__ == "__main__":
    main()
