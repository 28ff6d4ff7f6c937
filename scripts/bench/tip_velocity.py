#!/usr/bin/env python3
# The spiky meshes' vertex velocity (vx vy vz) at the tips against the tips' frame-to-frame
# motion found by ferro-tips (--tips): does a motion-blurred or retimed spike move the way the
# frames do? Tips of consecutive frames are paired as mutual nearest neighbours within 0.3 tip
# spacings; each pair's motion over the frame interval is compared with the mean of the mesh
# velocity at the two apexes (the nearest mesh vertex). Pure Python, a few minutes.
#   python3 scripts/bench/tip_velocity.py tips.csv 'spiky/spiky_%04d.ply' FPS FIRST LAST
# Measured on examples/magnet_slide.toml (docs/physics/spikes.md, "Velocity").
import bisect, csv, math, struct, sys
tips_csv, pattern, fps, first, last = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), int(sys.argv[5])
def read_ply(path):
    d = open(path, 'rb').read(); h = d.index(b'end_header\n') + 11
    props, nv, cur = [], 0, None
    for l in d[:h].decode().split('\n'):
        w = l.split()
        if w[:2] == ['element', 'vertex']: nv, cur = int(w[2]), 'v'
        elif w[:1] == ['element']: cur = 'o'
        elif w[:1] == ['property'] and cur == 'v': props.append(w[2])
    rows = struct.iter_unpack('<%df' % len(props), d[h:h + 4 * len(props) * nv])
    ix = [props.index(c) for c in ('x', 'y', 'z', 'vx', 'vy', 'vz')]
    return [tuple(r[i] for i in ix) for r in rows]
tips = {}
for row in csv.DictReader(open(tips_csv)):
    tips.setdefault(int(row['frame']), []).append((float(row['x']), float(row['y']), float(row['z'])))
def nearest(verts, p):
    best, bd = None, 1e9
    for v in verts:
        d = (v[0]-p[0])**2 + (v[1]-p[1])**2 + (v[2]-p[2])**2
        if d < bd: bd, best = d, v
    return best
def dist(a, b): return math.sqrt(sum((x-y)**2 for x, y in zip(a, b)))
rel, sum_m, sum_v, n = [], [0, 0, 0], [0, 0, 0], 0
meshes = {}
for f in range(first, last):
    if f not in tips or f + 1 not in tips: continue
    for f2 in (f, f + 1):
        if f2 not in meshes:
            verts = read_ply(pattern % f2)
            # only vertices near a tip, to keep the nearest search short
            meshes[f2] = [v for v in verts if any(dist(v, t) < 1e-3 for t in tips[f2])]
    spacing = 4.5e-3
    for a in tips[f]:
        b = min(tips[f + 1], key=lambda t: dist(a, t))
        if dist(a, b) > 0.3 * spacing: continue
        if min(dist(b, t) for t in tips[f]) < dist(a, b): continue   # not mutual
        m = [(b[i] - a[i]) * fps for i in range(3)]
        va, vb = nearest(meshes[f], a), nearest(meshes[f + 1], b)
        v = [(va[3 + i] + vb[3 + i]) / 2 for i in range(3)]
        mm = math.sqrt(sum(x * x for x in m))
        if mm > 0: rel.append(math.sqrt(sum((v[i] - m[i]) ** 2 for i in range(3))) / mm)
        for i in range(3): sum_m[i] += m[i]; sum_v[i] += v[i]
        n += 1
mean_m = [x / n for x in sum_m]; mean_v = [x / n for x in sum_v]
rel.sort()
dm = math.sqrt(sum((mean_v[i] - mean_m[i]) ** 2 for i in range(3))) / math.sqrt(sum(x * x for x in mean_m))
print("matched tip steps: %d" % n)
print("mean tip motion  [mm/s]: %s" % ", ".join("%.2f" % (1e3 * x) for x in mean_m))
print("mean mesh velocity at the tips [mm/s]: %s" % ", ".join("%.2f" % (1e3 * x) for x in mean_v))
print("mean vectors differ by %.1f %% of the tips' mean motion" % (100 * dm))
print("per tip |v - motion| / |motion|: median %.2f, 75th percentile %.2f" % (rel[len(rel) // 2], rel[3 * len(rel) // 4]))
