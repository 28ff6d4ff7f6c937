#!/usr/bin/env python3
"""The field sweep's plateaus (scripts/bench/field-sweep.sh): the pattern against the field,
on the way up and down.

    scripts/bench/field_sweep.py SCENE.toml PATTERN.txt CRITICAL_A_M SPACING_M > plateaus.csv
    scripts/bench/field_sweep.py SCENE.toml --windows CRITICAL_A_M

--windows prints each plateau's index and its second half as DIRECTION_FIELD/CRITICAL:T0:T1
(the windows of scripts/bench/spike_profile.py).

SCENE.toml: the swept scene; its first magnet's keys come in pairs, (reached, left) at one
field, after two keys at zero field (the settling). PATTERN.txt: scripts/bench/rosensweig.py
--period's rows for the shot's frames. For each plateau, the frames of its second half (the
pattern after its growth; the first half still grows or sinks) are averaged: the RMS height
about the mean, the peaks, their nearest-neighbour distance, and the pattern's height (the
peaks' mean apex above the mean surface). A plateau "stands" when its peaks are at least one
on average and its RMS height is at least 0.35 spacings (a settled layer with no field reads
0.13-0.17 spacings, one whose pattern has sunk 0.2-0.3). The summary lines, after the CSV (on stderr), bracket the onset
(the first standing plateau on the way up) and the lower threshold (the last standing one on
the way down).
"""
import math
import sys
import tomllib


def plateaus(scene_path):
    with open(scene_path, "rb") as f:
        scene = tomllib.load(f)
    keys = scene["magnets"][0]["keys"]
    if len(keys) < 4 or (len(keys) - 2) % 2:
        sys.exit("field_sweep.py: %s: expected two settling keys, then pairs of keys" % scene_path)
    out = []
    for k in range(2, len(keys), 2):
        a, b = keys[k], keys[k + 1]
        if a["field"] != b["field"]:
            sys.exit("field_sweep.py: %s: keys %d and %d are not a plateau" % (scene_path, k, k + 1))
        out.append((a["time"], b["time"], float(a["field"])))
    return out


def directions(steps):
    """"up" or "down" per plateau: against the plateau before it (the first one is up)."""
    out, previous = [], None
    for _, _, field in steps:
        out.append("up" if previous is None or field > previous else "down")
        previous = field
    return out


def windows(scene, critical):
    steps = plateaus(scene)
    for n, ((reached, left, field), direction) in enumerate(zip(steps, directions(steps))):
        print("%d %s_%.3g:%.4f:%.4f" % (n, direction, field / critical, 0.5 * (reached + left), left))


def main():
    if len(sys.argv) == 4 and sys.argv[2] == "--windows":
        windows(sys.argv[1], float(sys.argv[3]))
        return
    if len(sys.argv) != 5:
        sys.exit("usage: field_sweep.py SCENE.toml PATTERN.txt CRITICAL_A_M SPACING_M | SCENE.toml --windows CRITICAL_A_M")
    scene, pattern, critical, spacing = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4])
    rows = []
    with open(pattern) as f:
        for line in f:
            parts = line.split()
            try:
                rows.append([float(v) for v in parts])
            except ValueError:
                continue  # the header lines
    if not rows:
        sys.exit("field_sweep.py: %s: no frames" % pattern)
    steps = plateaus(scene)
    print("plateau,direction,field_A_m,field_over_critical,frames,rms_h_spacings,peaks,nn_median_mm,height_mm,stands")
    standing = []
    for n, ((reached, left, field), direction) in enumerate(zip(steps, directions(steps))):
        half = 0.5 * (reached + left)
        sel = [r for r in rows if half - 1e-6 <= r[0] <= left + 1e-6]
        if not sel:
            continue
        rms = sum(r[2] for r in sel) / len(sel)
        peaks = sum(r[5] for r in sel) / len(sel)
        nn = [r[6] for r in sel if not math.isnan(r[6])]
        heights = [r[9] - r[1] for r in sel if not math.isnan(r[9])]
        # A frame with no peak has no pattern height: it counts as 0.
        height = sum(heights) / len(sel)
        stands = peaks >= 1 and rms >= 0.35
        standing.append((direction, field, stands))
        print("%d,%s,%.0f,%.3f,%d,%.3f,%.2f,%s,%.2f,%d" % (
            n, direction, field, field / critical, len(sel), rms, peaks,
            "%.2f" % (sum(nn) / len(nn)) if nn else "nan", height, stands))
    ups = [(f, s) for d, f, s in standing if d == "up"]
    downs = [(f, s) for d, f, s in standing if d == "down"]
    onset = next((i for i, (f, s) in enumerate(ups) if s), None)
    if onset is None:
        print("onset: none up to %.3f x critical" % (ups[-1][0] / critical), file=sys.stderr)
    else:
        below = ups[onset - 1][0] / critical if onset > 0 else float("nan")
        print("onset: between %.3f and %.3f x critical" % (below, ups[onset][0] / critical), file=sys.stderr)
    # The lower threshold: the pattern still stands at the last standing plateau of the way
    # down, and is gone at the next.
    last = None
    for i, (f, s) in enumerate(downs):
        if s:
            last = i
        else:
            break
    if last is None:
        print("lower threshold: the pattern is gone at the first plateau down", file=sys.stderr)
    elif last == len(downs) - 1:
        print("lower threshold: below %.3f x critical (still standing at the sweep's end)" % (downs[last][0] / critical),
              file=sys.stderr)
    else:
        print("lower threshold: between %.3f and %.3f x critical" % (downs[last + 1][0] / critical, downs[last][0] / critical),
              file=sys.stderr)


if __name__ == "__main__":
    main()
