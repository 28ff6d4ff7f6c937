#!/usr/bin/env python3
"""Writes the hand-made seed inputs of tests/fuzz/corpus/ (run once; the fuzzer adds the rest).

Scene seeds: the examples plus small scenes with `%%` and --set lines; particle and mesh
seeds: valid and broken PLY (ascii, binary little and big endian, truncated headers, huge
counts, missing properties), OBJ and STL. Usage: make_seeds.py [ROOT] (default: the repo)."""
import os
import struct
import sys

root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "..")
corpus = os.path.join(root, "tests", "fuzz", "corpus")


def put(target, name, data):
    d = os.path.join(corpus, target)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


# --- scene -------------------------------------------------------------------------------
ex = os.path.join(root, "examples")
for n in sorted(os.listdir(ex)):
    if n.endswith(".toml"):
        with open(os.path.join(ex, n), "rb") as f:
            put("scene", n, f.read())

block = "[[fluid.block]]\nmin = [0, 0, 0]\nmax = [0.01, 0.01, 0.01]\ncount = 1000\n"
minimal = "[fluid]\n" + block
put("scene", "minimal.toml", minimal)
put("scene", "empty.toml", "")
put("scene", "overrides.toml", minimal + "%%\nshot.fps=60\nfluid.block.0.count=10\ncontainer.type=dish\n"
    "container.radius=0.05\ncontainer.height=0.02\nmagnets.0.kind=bar\n")
put("scene", "override-array.toml", minimal + "[[magnets]]\nkind = \"dipole\"\nmoment = 1.0\n"
    "[[magnets.keys]]\ntime = 0\n[[magnets.keys]]\ntime = 1\nposition = [0, 0, 0.1]\n"
    "%%\nmagnets.0.keys.1.moment=2\nmagnets.0.direction=[1,0,0]\nsim.gravity=[0, 0, -1e308]\n")
put("scene", "only-overrides.toml", "%%\nfluid.spacing=0.001\nfluid.block=[{min=[0,0,0],max=[1,1,1]}]\n"
    "surface.method=isotropic\nrender.width=64\nspikes.enabled=false\n")
put("scene", "bad-overrides.toml", minimal + "%%\nnoequals\n=1\na..b=1\nfluid.block.99.count=1\n"
    "fluid.rest_density.x=1\nfluid.block.x=1\nshot.fps=nan\nshot.fps=\"\n")
put("scene", "sections.toml", minimal + "[surface]\nmethod = \"isotropic\"\nk_r = 4\nsmoothing = 2\n"
    "[spikes]\nenabled = true\nspacing = \"physical\"\norigin = [0, 0, 0]\n"
    "[render]\ncamera_position = [0, -1, 0.5]\ncamera_target = [0, 0, 0]\nwidth = 320\n")
put("scene", "nonfinite.toml", minimal + "[shot]\nfps = inf\n[sim]\ngravity = [nan, 0, 0]\n"
    "[render]\ncamera_position = [1e308, 0, 0]\ncamera_target = [-1e308, 0, 0]\n")
put("scene", "types.toml", "shot = 1\n[fluid]\nblock = 3\n[sim]\nmax_iterations = 9223372036854775807\n"
    "threads = -1\nsolver = 2021-01-01T00:00:00Z\n[container]\ntype = \"mesh\"\nfile = \"/\"\n")
put("scene", "cylinder.toml", "[fluid]\nspacing = 0.001\n[[fluid.block]]\nshape = \"cylinder\"\n"
    "center = [0, 0, 0]\nradius = 0.01\nheight = 0.01\nvelocity = [0, 0, 1]\n"
    "[container]\ntype = \"box\"\nmin = [-1, -1, -1]\nmax = [1, 1, 1]\nclosed_top = true\n"
    "[magnetization]\nsusceptibility = 1\nsolver = \"tree\"\nopening_angle = 0.9\n")

# --- PLY helpers ---------------------------------------------------------------------------
fmt = {"char": "b", "uchar": "B", "short": "h", "ushort": "H", "int": "i", "uint": "I",
       "float": "f", "double": "d"}


def header(form, elements, comments=()):
    h = "ply\nformat %s 1.0\n" % form
    for c in comments:
        h += "comment %s\n" % c
    for name, count, props in elements:
        h += "element %s %d\n" % (name, count)
        for p in props:
            h += "property %s\n" % p
    return h + "end_header\n"


def binary(order, rows, types):
    out = b""
    for r in rows:
        for v, t in zip(r, types):
            out += struct.pack(order + fmt[t], v)
    return out


xyz = ["float x", "float y", "float z"]
pts = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)]

# --- particles -----------------------------------------------------------------------------
props7 = ["float " + n for n in "x y z vx vy vz density".split()]
rows7 = [p + (0.1, 0.2, 0.3, 1000.0) for p in pts]
put("particles", "ferro.ply", header("binary_little_endian", [("vertex", 4, props7)],
                                     ["frame 12", "time 0.4", "spacing 0.001"]).encode()
    + binary("<", rows7, ["float"] * 7))
put("particles", "magnets.ply", header("binary_little_endian", [("vertex", 1, xyz)],
                                      ["frame 2", "magnet_count 4",
                                       "magnet dipole 0 0 0.05 0 0 1 0.5 0 0 0.002",
                                       "magnet bar -0.1 0 0 1 0 0 100 0.05 0 0",
                                       "magnet uniform 0 0 0 0 0 1 20000 0 0 0",
                                       "magnet loop 0 0 -0.02 0 0 1 1000 0 0.03 0.001",
                                       "susceptibility 1.5", "saturation 30000"]).encode()
    + binary("<", pts[:1], ["float"] * 3))
put("particles", "big-endian-all-types.ply",
    header("binary_big_endian", [("vertex", 2, ["char a", "uchar b", "short c", "ushort d", "int e",
                                                "uint f", "float x", "double y", "float z"])]).encode()
    + binary(">", [(-1, 255, -300, 60000, -70000, 4000000000, 1.5, 2.5e300, -0.0)] * 2,
             ["char", "uchar", "short", "ushort", "int", "uint", "float", "double", "float"]))
put("particles", "ascii.ply", header("ascii", [("vertex", 3, ["float x", "double y", "int z"]),
                                               ("face", 1, ["list uchar int vertex_indices"])],
                                     ["frame 3"]) + "0 0 0\n1e40 -2.5 3\n+1 nan inf\n3 0 1 2\n")
put("particles", "obj-info-crlf.ply", "ply\r\nformat ascii 1.0\r\nobj_info made by hand\r\n"
    "element vertex 1\r\nproperty int8 x\r\nproperty uint16 y\r\nproperty float64 z\r\nend_header\r\n1 2 3\r\n")
put("particles", "truncated-header.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty fl")
put("particles", "end-header-no-break.ply", "ply\nformat ascii 1.0\nelement vertex 0\nend_header")
put("particles", "huge-count.ply", header("binary_little_endian", [("vertex", 18446744073709551615, xyz)]))
put("particles", "huge-count-ascii.ply", header("ascii", [("vertex", 4611686018427387904, xyz)]) + "1 2 3\n")
put("particles", "truncated-data.ply", header("binary_little_endian", [("vertex", 4, xyz)]).encode()
    + binary("<", pts[:3], ["float"] * 3) + b"\x00\x00")
put("particles", "no-properties.ply", header("binary_little_endian", [("vertex", 5, [])]))
put("particles", "list-in-vertex.ply", header("ascii", [("vertex", 1, ["list uchar float x"])]) + "1 2\n")
put("particles", "face-first.ply", header("ascii", [("face", 1, ["list uchar int vertex_indices"]),
                                                    ("vertex", 1, xyz)]) + "3 0 0 0\n0 0 0\n")
put("particles", "bad-ascii.ply", header("ascii", [("vertex", 2, xyz)]) + "1 2 3\n4 x 6\n")
put("particles", "not-ply.ply", "OFF\n3 1 0\n")
put("particles", "two-formats.ply", "ply\nformat ascii 1.0\nformat ascii 1.0\nend_header\n")
put("particles", "unknown-type.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n1\n")
put("particles", "empty.ply", "")

# --- mesh (first byte: 0 ply, 1 obj, 2 stl) ----------------------------------------------------
PLY, OBJ, STL = b"\x00", b"\x01", b"\x02"
tris = [(0, 2, 1), (0, 1, 3), (0, 3, 2), (1, 2, 3)]


def faces(order, count_t, index_t, faces_):
    out = b""
    for f in faces_:
        out += struct.pack(order + fmt[count_t], len(f))
        for i in f:
            out += struct.pack(order + fmt[index_t], i)
    return out


own = header("binary_little_endian", [("vertex", 4, xyz), ("face", 4, ["list uchar uint vertex_indices"])],
             ["frame 7", "time 0.25"]).encode() + binary("<", pts, ["float"] * 3) + faces("<", "uchar", "uint", tris)
put("mesh", "own.ply", PLY + own)
nrm = header("binary_little_endian", [("vertex", 4, xyz + ["float nx", "float ny", "float nz"]),
                                      ("face", 1, ["list uchar int vertex_indices"])]).encode() \
    + binary("<", [p + (0.0, 0.0, 1.0) for p in pts], ["float"] * 6) + faces("<", "uchar", "int", [(0, 1, 2, 3)])
put("mesh", "own-normals-quad.ply", PLY + nrm)
put("mesh", "own-bad-index.ply", PLY + header("binary_little_endian", [("vertex", 3, xyz),
                                                                       ("face", 1, ["list uchar uint vertex_indices"])]).encode()
    + binary("<", pts[:3], ["float"] * 3) + faces("<", "uchar", "uint", [(0, 1, 7)]))
put("mesh", "own-huge-faces.ply", PLY + header("binary_little_endian", [("vertex", 3, xyz),
                                                                        ("face", 4294967295, ["list uchar uint vertex_indices"])]).encode()
    + binary("<", pts[:3], ["float"] * 3))
put("mesh", "ascii.ply", PLY + (header("ascii", [("vertex", 4, xyz), ("face", 4, ["list uchar int vertex_indices"])])
                                + "".join("%g %g %g\n" % p for p in pts) + "".join("3 %d %d %d\n" % t for t in tris)).encode())
put("mesh", "big-endian.ply", PLY + header("binary_big_endian", [("vertex", 4, ["double x", "double y", "double z"]),
                                                                 ("face", 4, ["list uchar ushort vertex_indices"])]).encode()
    + binary(">", pts, ["double"] * 3) + faces(">", "uchar", "ushort", tris))
put("mesh", "ascii-bad-index.ply", PLY + (header("ascii", [("vertex", 3, xyz), ("face", 1, ["list uchar int vertex_indices"])])
                                          + "0 0 0\n1 0 0\n0 1 0\n3 0 1 -5\n").encode())
put("mesh", "truncated-header.ply", PLY + b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nend_header")
put("mesh", "huge-count-header-only.ply", PLY + header("binary_little_endian", [("vertex", 99999999999, xyz)]).encode())
put("mesh", "no-faces.ply", PLY + header("ascii", [("vertex", 2, xyz)]).encode() + b"0 0 0\n1 1 1\n")
put("mesh", "tetra.obj", OBJ + ("".join("v %g %g %g\n" % p for p in pts)
                                + "".join("f %d %d %d\n" % (a + 1, b + 1, c + 1) for a, b, c in tris)).encode())
put("mesh", "obj-bad-index.obj", OBJ + b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\nf -1 -2 -3\n")
put("mesh", "obj-normals-quads.obj", OBJ + b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\n")
with open(os.path.join(root, "examples", "meshes", "vessel.obj"), "rb") as f:
    put("mesh", "vessel.obj", OBJ + f.read())
stl = "solid t\n" + "".join(
    "facet normal 0 0 0\nouter loop\n" + "".join("vertex %g %g %g\n" % pts[i] for i in t) + "endloop\nendfacet\n"
    for t in tris) + "endsolid t\n"
put("mesh", "ascii.stl", STL + stl.encode())
bstl = b"\x00" * 80 + struct.pack("<I", 4) + b"".join(
    struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *pts[i]) for i in t) + b"\x00\x00" for t in tris)
put("mesh", "binary.stl", STL + bstl)
put("mesh", "binary-stl-huge-count.stl", STL + b"\x00" * 80 + struct.pack("<I", 0xFFFFFFFF) + bstl[84:134])
put("mesh", "empty.obj", OBJ)
