#!/usr/bin/env python3
"""A flat layer's pattern as it is born after the field jumps above critical, against linear
theory's fastest-growing mode (scripts/bench/field-sweep.sh, the jumps; issue 32).

    scripts/bench/field_jump.py PROFILE.txt --scene SCENE.toml --jump T --ratio R --spacing S

PROFILE.txt: scripts/bench/spike_profile.py's rows for single frames, labelled by their time
(t0.3125, ...). The exponential phase: the first run of at least 3 consecutive frames after
the jump at time T whose peak-to-trough height lies between 0.3 mm (above a settled layer's
0.1-0.2) and 2 mm (before the spikes turn nonlinear), a frame outside restarting the run, ended
where the fundamental's wavelength jumps by more than 10 % between frames (the pattern
re-arranging). Its growth rate is the least-squares slope of ln(the fundamental band's RMS
amplitude) against t, its wavelength the median of the frames' fundamental wavelengths. The
last five frames give the wavelength the pattern coarsens to.

The theory (the same as spikes/SpikePhysics.cpp, written again here as a cross-check): the
applied field R x the critical one gives M inside a flat layer (M = L(H0 - M), the fluid's
Langevin law), M_c from eq. 16; the growth rate s(k) of a deep layer of kinematic viscosity nu,
    (s + 2 nu k^2)^2 + w0^2 = 4 nu^2 k^3 sqrt(k^2 + s / nu),
    rho w0^2 = rho g k + sigma k^3 - 2 sqrt(g rho sigma) (M / M_c)^2 k^2,
and its fastest-growing wavenumber, for three viscosities: the scene's nu; nu_eff, the one the
simulator's step uses (the scene's plus sim.artificial_viscosity x 2 spacings x sqrt(2 g
depth), sim/sph/FluidSimulation.cpp), a prediction; and nu_fit, the one whose fastest rate
equals the simulated rate (SPH has numerical viscosity beyond nu_eff). The fluid comes from
SCENE.toml.
With --spectrum (spike_profile.py --spectrum-csv of the same frames) also the simulated
dispersion relation: every wavelength's growth rate over the exponential phase, and the
wavelength where it peaks (--dispersion-csv writes it beside the theory's rates).
One CSV row: spacing_mm, ratio, M/M_c, frames, rate_sim, lambda_sim_mm, lambda_late_mm,
rate_nu, lambda_nu_mm, nu_eff, rate_eff, lambda_eff_mm, nu_fit, lambda_fit_mm, lambda_disp_mm
(nan without --spectrum).
"""
import argparse
import math
import sys

MU0 = 4e-7 * math.pi


def langevin_m(h, chi, ms):
    xi = 3 * chi * h / ms
    if abs(xi) < 1e-4:
        return chi * h
    return ms * (1 / math.tanh(xi) - 1 / xi)


def langevin_slope(h, chi, ms):
    xi = 3 * chi * h / ms
    if abs(xi) < 1e-4:
        return chi
    return 3 * chi * (1 / xi ** 2 - 1 / math.sinh(xi) ** 2)


def critical(rho, g, sigma, chi, ms):
    """(M_c, applied H_c) of eq. 16 with r0 at M_c."""
    cap = math.sqrt(g * rho * sigma)
    r0 = 1 + chi
    for _ in range(100):
        mc = math.sqrt(2 / MU0 * (1 + 1 / r0) * cap)
        lo, hi = 0.0, mc / chi
        while langevin_m(hi, chi, ms) < mc:
            hi *= 2
        for _ in range(100):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if langevin_m(mid, chi, ms) < mc else (lo, mid)
        h = 0.5 * (lo + hi)
        r = math.sqrt((1 + mc / h) * (1 + langevin_slope(h, chi, ms)))
        if abs(r - r0) < 1e-12 * r:
            break
        r0 = r
    return mc, h + mc


def layer_m(h0, chi, ms):
    lo, hi = 0.0, h0
    for _ in range(200):
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if langevin_m(h0 - m, chi, ms) > m else (lo, m)
    return 0.5 * (lo + hi)


def rate(k, q, rho, g, sigma, nu):
    w02 = (rho * g * k + sigma * k ** 3 - 2 * math.sqrt(g * rho * sigma) * q * k * k) / rho
    if w02 >= 0:
        return 0.0
    s_inv = math.sqrt(-w02)
    if nu <= 0:
        return s_inv
    lo, hi = 0.0, s_inv
    for _ in range(400):
        s = 0.5 * (lo + hi)
        r = math.sqrt(k * k + s / nu)
        f = s * s + 4 * nu * k * k * s * r / (k + r) + w02   # (s + 2 nu k^2)^2 + w0^2 - 4 nu^2 k^3 r
        lo, hi = (s, hi) if f < 0 else (lo, s)
    return 0.5 * (lo + hi)


def fastest(q, rho, g, sigma, nu):
    """(k, s) of the fastest-growing mode."""
    kc = math.sqrt(rho * g / sigma)
    if q <= 1:
        return kc, 0.0
    root = math.sqrt(q * q - 1)
    a, b = kc * (q - root), kc * (q + root)
    for _ in range(200):
        c, d = a + (b - a) / 3, b - (b - a) / 3
        if rate(c, q, rho, g, sigma, nu) < rate(d, q, rho, g, sigma, nu):
            a = c
        else:
            b = d
    k = 0.5 * (a + b)
    return k, rate(k, q, rho, g, sigma, nu)


def scene_fluid(path):
    """(rho, sigma, nu, chi, Ms, layer depth, artificial viscosity alpha) of the scene."""
    import tomllib
    with open(path, "rb") as f:
        sc = tomllib.load(f)
    fl, mg = sc.get("fluid", {}), sc.get("magnetization", {})
    block = fl.get("block", [{}])[0]
    depth = block.get("max", [0, 0, 0.005])[2] - block.get("min", [0, 0, 0])[2]
    return (fl.get("rest_density", 1000.0), fl.get("surface_tension", 0.0), fl.get("viscosity", 1e-6),
            mg.get("susceptibility", 0.0), mg.get("saturation", 0.0), depth,
            sc.get("sim", {}).get("artificial_viscosity", 0.02))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("profile")
    ap.add_argument("--scene", required=True, help="the jump's scene (its fluid, layer and sim.artificial_viscosity)")
    ap.add_argument("--jump", type=float, required=True)
    ap.add_argument("--ratio", type=float, required=True)
    ap.add_argument("--spacing", type=float, required=True)
    ap.add_argument("--g", type=float, default=9.81)
    ap.add_argument("--spectrum", help="spike_profile.py --spectrum-csv of the same frames: the growth rate of every wavelength")
    ap.add_argument("--dispersion-csv", help="with --spectrum: write the simulated and theoretical growth rates here")
    a = ap.parse_args()
    rho, sigma, nu, chi, ms, depth, alpha = scene_fluid(a.scene)
    if not (rho > 0 and sigma > 0 and chi > 0 and ms > 0):
        sys.exit("field_jump.py: %s: needs rest_density, surface_tension, susceptibility and saturation" % a.scene)
    rows = []   # (t, ptp, lambda, band amplitude), mm
    with open(a.profile) as f:
        for line in f:
            p = line.split()
            if len(p) >= 9 and p[0].startswith("t"):
                try:
                    rows.append((float(p[0][1:]), float(p[2]), float(p[3]), float(p[8])))
                except ValueError:
                    continue
    rows.sort()
    # The exponential phase: the first run of at least 3 consecutive frames after the jump with
    # ptp in [0.3, 2] mm (a noisy frame outside restarts the run), ended where the wavelength
    # jumps by more than 10 % from one frame to the next (the pattern re-arranging).
    grow = []
    for r in rows:
        if r[0] <= a.jump:
            continue
        inside = 0.3 <= r[1] <= 2.0
        jumped = bool(grow) and abs(r[2] - grow[-1][2]) > 0.1 * grow[-1][2]
        if inside and not jumped:
            grow.append(r)
        elif len(grow) >= 3:
            break
        else:
            grow = [r] if inside else []
    if len(grow) < 3:
        sys.exit("field_jump.py: %s: fewer than 3 consecutive frames between 0.3 and 2 mm" % a.profile)
    n = len(grow)
    tm = sum(r[0] for r in grow) / n
    ym = sum(math.log(r[3]) for r in grow) / n
    s_sim = sum((r[0] - tm) * (math.log(r[3]) - ym) for r in grow) / sum((r[0] - tm) ** 2 for r in grow)
    lams = sorted(r[2] for r in grow)
    lam_sim = lams[n // 2]
    late = sorted(r[2] for r in rows[-5:])
    lam_late = late[len(late) // 2]
    mc, hc = critical(rho, a.g, sigma, chi, ms)
    q = (layer_m(a.ratio * hc, chi, ms) / mc) ** 2
    k_th, s_th = fastest(q, rho, a.g, sigma, nu)
    # The step's viscosity (sim/sph/FluidSimulation.cpp): the scene's plus alpha h U, h = 2
    # spacings, U = sqrt(2 g depth) for a layer starting at rest.
    nu_eff = nu + alpha * 2 * a.spacing * math.sqrt(2 * a.g * depth)
    k_eff, s_eff = fastest(q, rho, a.g, sigma, nu_eff)
    # nu_fit: the theory's fastest rate falls monotonically with nu; bisect in log nu.
    nu_fit = float("nan")
    if 0 < s_sim < fastest(q, rho, a.g, sigma, 1e-9)[1]:
        lo, hi = math.log(1e-9), math.log(10.0)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if fastest(q, rho, a.g, sigma, math.exp(mid))[1] > s_sim else (lo, mid)
        nu_fit = math.exp(0.5 * (lo + hi))
    lam_fit = 2e3 * math.pi / fastest(q, rho, a.g, sigma, nu_fit)[0] if nu_fit == nu_fit else float("nan")
    lam_disp = float("nan")
    if a.spectrum:
        lam_disp = dispersion(a, grow, q, rho, sigma, nu, nu_eff)
    print("%g,%g,%.3f,%d,%.1f,%.2f,%.2f,%.1f,%.2f,%.2g,%.1f,%.2f,%.2g,%.2f,%.2f" % (
        a.spacing * 1e3, a.ratio, math.sqrt(q), n, s_sim, lam_sim, lam_late, s_th, 2e3 * math.pi / k_th,
        nu_eff, s_eff, 2e3 * math.pi / k_eff, nu_fit, lam_fit, lam_disp))


def dispersion(a, grow, q, rho, sigma, nu, nu_eff):
    """The simulated dispersion relation: per ring of the radial spectrum (spike_profile.py
    --spectrum-csv, one row per frame and ring), the least-squares slope of ln(amplitude)
    against t over the exponential phase's frames; the wavelength [mm] where it peaks (a
    parabola through the fastest ring and its neighbours, in k), among the rings of at least
    4 mm (shorter ones are few particles across). With --dispersion-csv: wavelength_mm,
    rate_sim, rate_nu, rate_eff per ring."""
    times = {round(r[0], 5) for r in grow}
    rings = {}   # ring index (its place among the frame's rows) -> [(t, wavelength_mm, amplitude)]
    counter = {}
    try:
        with open(a.spectrum) as f:
            next(f)
            for line in f:
                label, lam, amp = line.strip().split(",")
                t = float(label[1:])
                i = counter.get(label, 0)
                counter[label] = i + 1
                if round(t, 5) in times and float(amp) > 0:
                    rings.setdefault(i, []).append((t, float(lam), float(amp)))
    except (OSError, ValueError, StopIteration) as e:
        sys.exit("field_jump.py: %s: %s" % (a.spectrum, e))
    table = []
    for i in sorted(rings):
        pts = rings[i]
        if len(pts) < 3:
            continue
        n = len(pts)
        tm = sum(p[0] for p in pts) / n
        ym = sum(math.log(p[2]) for p in pts) / n
        slope = sum((p[0] - tm) * (math.log(p[2]) - ym) for p in pts) / sum((p[0] - tm) ** 2 for p in pts)
        lam = sum(p[1] for p in pts) / n
        k = 2e3 * math.pi / lam
        table.append((lam, slope, rate(k, q, rho, a.g, sigma, nu), rate(k, q, rho, a.g, sigma, nu_eff), i))
    if a.dispersion_csv:
        with open(a.dispersion_csv, "w") as out:
            out.write("wavelength_mm,rate_sim_per_s,rate_nu_per_s,rate_eff_per_s\n")
            for row in table:
                out.write("%.3f,%.2f,%.2f,%.2f\n" % row[:4])
    usable = [j for j, row in enumerate(table) if row[0] >= 4.0]
    if not usable:
        return float("nan")
    j = max(usable, key=lambda j: table[j][1])
    # The table runs from long to short wavelengths: both neighbours must be usable rings, and
    # the rings next to the fastest one.
    if 0 < j < len(table) - 1 and j + 1 in usable and table[j - 1][4] == table[j][4] - 1 == table[j + 1][4] - 2:
        (l0, s0, _, _, _), (l1, s1, _, _, _), (l2, s2, _, _, _) = table[j - 1], table[j], table[j + 1]
        k0, k1, k2 = 1 / l0, 1 / l1, 1 / l2
        den = (k0 - k1) * (k0 - k2) * (k1 - k2)
        A = (k2 * (s1 - s0) + k1 * (s0 - s2) + k0 * (s2 - s1)) / den
        B = (k2 * k2 * (s0 - s1) + k1 * k1 * (s2 - s0) + k0 * k0 * (s1 - s2)) / den
        if A < 0:
            kp = -B / (2 * A)
            if min(k0, k2) <= kp <= max(k0, k2):
                return 1 / kp
    return table[j][0]


if __name__ == "__main__":
    main()
