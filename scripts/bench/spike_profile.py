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
                                   [--cell C] [--profile-csv OUT] [--spike-csv OUT]
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
  shape_dev   one spike's shape against the fundamental's: the mean spike (mean_spike: the
              surface's azimuthal mean around each peak, over the peak's height above the mean
              level, averaged over the peaks and frames, in r / lambda) against J0(2 pi r /
              lambda), the fundamental's own profile about a tip; the largest difference out
              to half a wavelength. Peaks of unequal height do not enter it (each is scaled by
              its own height), so it measures shape, not disorder
  peaks       the peaks averaged (all frames)
--spike-csv writes each window's mean spike against J0. --spectrum-csv writes the radial spectrum
of each window's last frame (rings of box modes 1 / L wide: wavelength, RMS amplitude), from
which field_jump.py --spectrum measures the growth rate of every wavelength. --profile-csv writes one spike's profile per window, from its last frame: a cut from the
highest point through the nearest other peak, the surface and its fundamental against the
distance.

Needs NumPy (python3-numpy; scripts/install-deps.sh --with-bench).

--procedural: dev_max, dev_rms, above and shape_dev on Ferro's hexagonal profile (spikes/SpikePhysics.hpp:
hexProfile sharpened by sharpenedProfile with exponent p) sampled on one periodic cell of the
lattice (tip spacing l by sqrt(3) l); shape_dev on 4 x 4 cells (--spike-csv: their mean spikes).
"""
import argparse
import cmath
import glob
import math
import os
import sys

try:
    import numpy as np
except ImportError:
    sys.exit("spike_profile.py: needs NumPy (apt install python3-numpy, or scripts/install-deps.sh --with-bench)")

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rosensweig import read_ply  # noqa: E402


def cubic_spline(q, h):
    """The M4 cubic spline kernel in 3D, support 2 h, at q = r / h (an array)."""
    sigma = 1.0 / (math.pi * h ** 3)
    return sigma * np.where(q < 1.0, 1.0 - 1.5 * q * q + 0.75 * q ** 3,
                            np.where(q < 2.0, 0.25 * (2.0 - np.minimum(q, 2.0)) ** 3, 0.0))


class Grid:
    """nx x ny cells over a periodic box LX x LY (corner at the origin)."""

    def __init__(self, lx, ly, cell):
        self.lx, self.ly = lx, ly
        self.nx, self.ny = max(8, round(lx / cell)), max(8, round(ly / cell))

    def centre(self, i, j):
        return ((i + 0.5) * self.lx / self.nx, (j + 0.5) * self.ly / self.ny)


def surface_heights(pts, grid, s):
    """The colour field's 0.5 level along each cell's vertical line [m], an nx x ny array.
    Every (particle, line) pair within 2 s horizontally (periodic) is listed once; the level
    is bracketed from above in steps of s / 2 and bisected 8 times, all lines at once."""
    h = s
    reach = 2 * h
    volume = s ** 3
    nx, ny = grid.nx, grid.ny
    cx, cy = grid.lx / nx, grid.ly / ny
    p = np.asarray(pts, dtype=float).reshape(-1, 3)
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    ci, cj = np.floor(x / cx).astype(np.int64), np.floor(y / cy).astype(np.int64)
    ri, rj = int(math.ceil(reach / cx)) + 1, int(math.ceil(reach / cy)) + 1
    lines, d2s, zs, ids = [], [], [], []
    index = np.arange(len(x))
    for a in range(-ri, ri + 1):
        for b in range(-rj, rj + 1):
            li, lj = (ci + a) % nx, (cj + b) % ny
            dx = x - (li + 0.5) * cx
            dy = y - (lj + 0.5) * cy
            dx -= grid.lx * np.round(dx / grid.lx)
            dy -= grid.ly * np.round(dy / grid.ly)
            d2 = dx * dx + dy * dy
            keep = d2 < reach * reach
            lines.append((li * ny + lj)[keep])
            d2s.append(d2[keep])
            zs.append(z[keep])
            ids.append(index[keep])
    line = np.concatenate(lines)
    d2 = np.concatenate(d2s)
    zp = np.concatenate(zs)
    if 2 * ri + 1 > nx or 2 * rj + 1 > ny:
        # A box only a few cells across reaches a line twice through the wrap: each pair once.
        _, first = np.unique(line * len(x) + np.concatenate(ids), return_index=True)
        line, d2, zp = line[first], d2[first], zp[first]
    n = nx * ny
    has = np.bincount(line, minlength=n) > 0
    top = np.full(n, -np.inf)
    np.maximum.at(top, line, zp)

    def colour(zz):
        dz = zz[line] - zp
        w = np.where(np.abs(dz) < reach, volume * cubic_spline(np.sqrt(d2 + dz * dz) / h, h), 0.0)
        return np.bincount(line, weights=w, minlength=n)

    hi = np.where(has, top + reach, 0.0)
    lo = hi - 0.5 * s
    # Down in steps of s / 2 to the first level inside the fluid; a line whose particles never
    # make the colour 0.5 (a stray droplet) within 60 s is a gap.
    floor = hi - 60 * s
    while True:
        step = has & (colour(lo) < 0.5) & (lo > floor)
        if not step.any():
            break
        hi = np.where(step, lo, hi)
        lo = np.where(step, lo - 0.5 * s, lo)
    has &= lo > floor
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        below = colour(mid) < 0.5
        hi = np.where(below, mid, hi)
        lo = np.where(below, lo, mid)
    out = np.where(has, 0.5 * (lo + hi), np.nan).reshape(nx, ny)
    # A line with no fluid under it (a gap between towers) takes its neighbours' mean, in row
    # order, a filled line counting for the ones after it (a wide gap fills from its edge).
    for i, j in np.argwhere(np.isnan(out)):
        v = [out[(i + a) % nx, (j + b) % ny] for a in (-1, 0, 1) for b in (-1, 0, 1)]
        v = [w for w in v if not math.isnan(w)]
        out[i, j] = sum(v) / len(v) if v else 0.0
    return out


def mode_numbers(nx, ny):
    """Signed box mode numbers (m, n) of an nx x ny DFT, as arrays of its shape."""
    m = np.arange(nx)
    n = np.arange(ny)
    sm = np.where(m > nx // 2, m - nx, m)
    sn = np.where(n > ny // 2, n - ny, n)
    return np.meshgrid(sm, sn, indexing="ij")


def fundamental(field, lx, ly):
    """(mean, fundamental field, its wavelength [m], and the variance below, in and above the
    band) of a periodic field. The fundamental is the band of box modes with wavenumbers within
    0.75-1.3 of a centre k0, k0 the box mode's wavenumber whose band holds the most power (the
    most favourable band: a few irregular peaks in a small box spread their power over several
    modes near the pattern's wavenumber); its wavelength is the band's power-weighted mean."""
    field = np.asarray(field, dtype=float)
    nx, ny = field.shape
    F = np.fft.fft2(field)
    sm, sn = mode_numbers(nx, ny)
    k = np.hypot(sm / lx, sn / ly)
    power = np.abs(F) ** 2
    nonzero = k > 0
    kk, pp = k[nonzero], power[nonzero]
    order = np.argsort(kk, kind="stable")
    ks, cum = kk[order], np.concatenate(([0.0], np.cumsum(pp[order])))
    # Band centres: modes of at least two wavelengths across the box in x or y (the box-scale
    # modes (1, 0), (1, 1) are the unequal heights of a few peaks, not a pattern's wavelength).
    wide = nonzero & (np.maximum(np.abs(sm), np.abs(sn)) >= 2)
    centres = np.unique(np.round(k[wide], 6))
    band_power = (cum[np.searchsorted(ks, 1.3 * centres, side="right")] -
                  cum[np.searchsorted(ks, 0.75 * centres, side="left")])
    k0 = centres[int(np.argmax(band_power))]
    shell = nonzero & (k >= 0.75 * k0) & (k <= 1.3 * k0)
    kmean = float((k[shell] * power[shell]).sum() / max(power[shell].sum(), 1e-300))
    mean = F[0, 0].real / (nx * ny)
    fund = mean + np.fft.ifft2(np.where(shell, F, 0.0)).real
    # The variance below and above the band (Parseval: power / (nx ny)^2 per mode).
    scale = 1.0 / (nx * ny) ** 2
    below = scale * power[nonzero & (k < 0.75 * k0)].sum()
    above = scale * power[k > 1.3 * k0].sum()
    band = scale * power[shell].sum()
    return mean, fund, 1.0 / kmean if kmean > 0 else float("nan"), below, band, above


def measures(field, lx, ly):
    field = np.asarray(field, dtype=float)
    mean, fund, lam, below, band, above = fundamental(field, lx, ly)
    ptp = float(field.max() - field.min())
    dev = field - fund
    var = float(((field - mean) ** 2).mean())
    return {
        "ptp": ptp,
        "lambda": lam,
        "dev_max": float(np.abs(dev).max()) / ptp,
        "dev_rms": math.sqrt(float((dev * dev).mean())) / ptp,
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


def bessel_j0(x):
    """J0(x) = (1/pi) int_0^pi cos(x sin t) dt (Simpson, 200 intervals: 1e-9 for x < 10)."""
    n = 200
    t = np.linspace(0.0, math.pi, n + 1)
    w = np.ones(n + 1)
    w[1:-1:2], w[2:-1:2] = 4.0, 2.0
    x = np.asarray(x, dtype=float)
    return (np.cos(np.multiply.outer(x, np.sin(t))) * w).sum(axis=-1) * (math.pi / n) / 3.0 / math.pi


def mean_spike(field, lx, ly, lam):
    """One spike's profile, averaged over the peaks: around each local maximum (the highest point
    within 0.3 lambda, above the mean by a quarter of the highest peak's height) the surface's
    azimuthal mean out to 0.6 lambda, in rings one cell wide, minus the field's mean, over the
    peak's height above it. Returns (r / lambda per ring, the mean profile, peaks). The
    fundamental's own profile about a tip is J0(2 pi r / lambda) for hexagons and squares alike
    (every wave vector has length 2 pi / lambda): the reference."""
    field = np.asarray(field, dtype=float)
    nx, ny = field.shape
    cx, cy = lx / nx, ly / ny
    mean = field.mean()
    top = field.max()
    w = max(1, int(round(0.3 * lam / min(cx, cy))))
    local = field.copy()
    for a in range(-w, w + 1):
        for b in range(-w, w + 1):
            if a * a * cx * cx + b * b * cy * cy <= (0.3 * lam) ** 2:
                local = np.maximum(local, np.roll(np.roll(field, a, axis=0), b, axis=1))
    peaks = np.argwhere((field >= local) & (field > mean + 0.25 * (top - mean)))
    R = 0.6 * lam
    ri, rj = int(math.ceil(R / cx)), int(math.ceil(R / cy))
    di, dj = np.meshgrid(np.arange(-ri, ri + 1), np.arange(-rj, rj + 1), indexing="ij")
    r = np.hypot(di * cx, dj * cy)
    ring = np.floor(r / min(cx, cy) + 0.5).astype(int)
    inside = r <= R
    di, dj, r, ring = di[inside], dj[inside], r[inside], ring[inside]
    rings = ring.max() + 1
    count = np.bincount(ring, minlength=rings)
    r_mean = np.bincount(ring, weights=r, minlength=rings) / np.maximum(count, 1)
    total = np.zeros(rings)
    for i, j in peaks:
        h0 = field[i, j] - mean
        if not h0 > 0:
            continue
        v = field[(i + di) % nx, (j + dj) % ny] - mean
        total += np.bincount(ring, weights=v, minlength=rings) / np.maximum(count, 1) / h0
    return r_mean / lam, total / max(len(peaks), 1), len(peaks)


def radial_spectrum(field, lx, ly):
    """The surface's RMS amplitude [m] in rings of box modes one 1 / max(lx, ly) wide in the
    spatial frequency |k| / 2 pi (the mean left out): [(wavelength [m] at the ring's mean
    frequency, amplitude)], out to the grid's Nyquist frequency."""
    field = np.asarray(field, dtype=float)
    nx, ny = field.shape
    F = np.fft.fft2(field)
    sm, sn = mode_numbers(nx, ny)
    f = np.hypot(sm / lx, sn / ly)
    df = 1.0 / max(lx, ly)
    ring = np.floor(f / df + 0.5).astype(int)
    power = np.abs(F) ** 2 / (nx * ny) ** 2
    top = int(min(nx / (2 * lx), ny / (2 * ly)) / df)
    out = []
    for r in range(1, top + 1):
        sel = ring == r
        if sel.any():
            out.append((1.0 / f[sel].mean(), math.sqrt(power[sel].sum())))
    return out


def shape_deviation(rl, profile):
    """The largest |profile - J0(2 pi r / lambda)| out to half a wavelength."""
    near = rl <= 0.5
    return float(np.abs(profile[near] - bessel_j0(2 * math.pi * rl[near])).max())


def procedural(ps, spike_csv=None):
    """Ferro's hexagonal spikes: the Fourier measures on one periodic cell (tip spacing l = 1
    along x, sqrt(3) along y: two tips per cell, (0, 0) and (1/2, sqrt(3)/2)), and the mean
    spike's departure from J0 on 4 x 4 such cells (lambda = sqrt(3) / 2 l)."""
    def field(cells, nx, ny, p, centred):
        lx, ly = float(cells), cells * math.sqrt(3.0)
        i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
        x, y = (i + 0.5) * lx / nx, (j + 0.5) * ly / ny
        # lattice coordinates: x = a + b/2, y = b sqrt(3)/2; `centred` puts a tip on a cell
        # centre (the mean spike starts from a grid cell).
        x0, y0 = (0.5 * lx / nx, 0.5 * ly / ny) if centred else (0.0, 0.0)
        b = (y - y0) / (math.sqrt(3.0) / 2)
        a = (x - x0) - b / 2
        F = np.cos(2 * math.pi * (a + b)) + np.cos(2 * math.pi * a) + np.cos(2 * math.pi * b)
        if p != 1.0:
            F = 4.5 * np.clip((F + 1.5) / 4.5, 0.0, 1.0) ** p - 1.5
        return F, lx, ly

    print("p  dev_max  dev_rms  above  shape_dev")
    curves = []
    grid_rl = np.linspace(0.0, 0.6, 31)
    for p in ps:
        F, lx, ly = field(1, 24, 42, p, False)
        r = measures(F, lx, ly)
        F4, lx4, ly4 = field(4, 160, 277, p, True)
        rl, prof, _ = mean_spike(F4, lx4, ly4, math.sqrt(3.0) / 2)
        curves.append(("p%g" % p, np.interp(grid_rl, rl, prof)))
        print("%g  %.3f  %.3f  %.3f  %.3f" % (p, r["dev_max"], r["dev_rms"], r["above"], shape_deviation(rl, prof)))
    if spike_csv:
        write_spikes(spike_csv, grid_rl, curves)


def write_spikes(path, grid_rl, spikes):
    """label,r_over_lambda,mean_spike,j0 rows of each (label, profile on grid_rl)."""
    j0 = bessel_j0(2 * math.pi * grid_rl)
    with open(path, "w") as out:
        out.write("label,r_over_lambda,mean_spike,j0\n")
        for label, spike in spikes:
            for x, v, b in zip(grid_rl, spike, j0):
                out.write("%s,%.3f,%.4f,%.4f\n" % (label, x, v, b))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("frames", nargs="?")
    ap.add_argument("--period", help="LX,LY [m] of the box with periodic sides (corner at the origin)")
    ap.add_argument("--window", action="append", default=[], help="LABEL:T0:T1 [s], repeatable")
    ap.add_argument("--cell", type=float, default=0.0, help="grid cell [m]; 0 = half the spacing")
    ap.add_argument("--profile-csv", help="write each window's spike profile here")
    ap.add_argument("--spike-csv", help="write each window's mean spike (r / lambda, profile, J0) here")
    ap.add_argument("--spectrum-csv", help="write each window's last frame's radial spectrum here")
    ap.add_argument("--procedural", help="sharpness exponents p, comma-separated")
    a = ap.parse_args()
    if a.procedural:
        try:
            ps = [float(v) for v in a.procedural.split(",")]
        except ValueError:
            sys.exit("spike_profile.py: --procedural takes numbers >= 1, comma-separated (got %r)" % a.procedural)
        if any(not p >= 1 for p in ps):
            sys.exit("spike_profile.py: --procedural takes numbers >= 1")
        procedural(ps, a.spike_csv)
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
    print("label  frames  ptp_mm  lambda_mm  dev_max  dev_rms  below  above  band_mm  move  shape_dev  peaks")
    cuts, spikes, spectra = [], [], []
    grid_rl = np.linspace(0.0, 0.6, 31)   # r / lambda of the window's mean spike
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
        # How far the surface moves between frames, against its height (a standing pattern: the
        # column jitter only; a pattern whose peaks wander: of order 1).
        moves = [math.sqrt(float(((g - f) ** 2).mean())) / r["ptp"] for f, g, r in zip(fields, fields[1:], rows[1:])]
        lams = sorted(r["lambda"] for r in rows)

        def mean(key):
            return sum(r[key] for r in rows) / len(rows)

        # The mean spike: each frame's (in its own r / lambda), averaged over the frames.
        profiles, peaks = [], 0
        for f, r in zip(fields, rows):
            rl, prof, n = mean_spike(f, lx, ly, r["lambda"])
            if n:
                profiles.append(np.interp(grid_rl, rl, prof))
                peaks += n
        spike = np.mean(profiles, axis=0) if profiles else None
        if spike is not None:
            spikes.append((label, spike))
        print("%s  %d  %.2f  %.2f  %.3f  %.3f  %.3f  %.3f  %.4f  %s  %s  %d" % (
            label, len(chosen), 1e3 * mean("ptp"), 1e3 * lams[len(lams) // 2], mean("dev_max"), mean("dev_rms"),
            mean("below"), mean("above"), 1e3 * mean("band_rms"), "%.3f" % (sum(moves) / len(moves)) if moves else "nan",
            "%.3f" % shape_deviation(grid_rl, spike) if spike is not None else "nan", peaks))
        sys.stdout.flush()
        if a.spectrum_csv:
            spectra += [(label, lam, amp) for lam, amp in radial_spectrum(fields[-1], lx, ly)]
        for t, v, f in profile_cut(fields[-1], rows[-1]["fund"], grid):
            cuts.append((label, t, v, f))
    if a.spike_csv:
        write_spikes(a.spike_csv, grid_rl, spikes)
    if a.spectrum_csv:
        with open(a.spectrum_csv, "w") as out:
            out.write("label,wavelength_mm,amplitude_mm\n")
            for label, lam, amp in spectra:
                out.write("%s,%.4f,%.6g\n" % (label, 1e3 * lam, 1e3 * amp))
    if a.profile_csv:
        with open(a.profile_csv, "w") as out:
            out.write("label,distance_mm,surface_mm,fundamental_mm\n")
            for label, t, v, f in cuts:
                out.write("%s,%.3f,%.3f,%.3f\n" % (label, 1e3 * t, 1e3 * v, 1e3 * f))


if __name__ == "__main__":
    main()
