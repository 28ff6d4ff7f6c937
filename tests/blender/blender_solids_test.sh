#!/usr/bin/env bash
# A shot with a steel solid in Debian's Blender 3.4, headless (issue 51): frames 0..1 of a
# small pool with a cone standing in it (tests/data/small_solid_pool.toml) are made with
# scripts/shot.sh and imported with scripts/blender/import_shot.py --check, which checks each
# frame's "FerroSolids" mesh (vertex count and positions) against the frame's magnets include;
# the vertex count is also read here from the include's mesh2 itself. Frame 1 is rendered with
# Cycles at 4 samples: not one flat colour. Then the same shot's includes are exported again
# with keys that move the cone, and the import must give each frame its own solids mesh, also
# after the saved .blend is opened again (the frame-change handler rides in it).
# Usage: blender_solids_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR. Fails (never skips) when
# Blender is missing: scripts/install-deps.sh --with-blender installs it.
set -euo pipefail
src="$1" bin="$2" scratch="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v blender > /dev/null || fail "blender is not installed (scripts/install-deps.sh --with-blender)"
rm -rf "$scratch"
mkdir -p "$scratch"
export FERRO_BIN="$bin"
import="$src/scripts/blender/import_shot.py"

# The vertex count of a magnets include's solids, from its mesh2 blocks' vertex_vectors.
include_vertices() {
  grep -o 'vertex_vectors { [0-9]*' "$1" | awk '{ n += $3 } END { print n + 0 }'
}

"$src/scripts/shot.sh" "$src/tests/data/small_solid_pool.toml" "$scratch/shot" --max-frames 1 --no-video \
  --set render.width=64 --set render.height=48 > "$scratch/shot.log" 2>&1 ||
  { tail -20 "$scratch/shot.log"; fail "shot.sh failed"; }
for f in 0000 0001; do
  grep -q '^#declare FerroSolidCount = 1;' "$scratch/shot/shot/magnets_$f.inc" || fail "magnets_$f.inc declares no solid"
done

blender -b --python-exit-code 1 --python "$import" -- "$scratch/shot" --check \
  --render 1 "$scratch/blender_0001.png" --samples 4 --save "$scratch/shot.blend" > "$scratch/blender.log" 2>&1 ||
  { grep -v '^Fra:' "$scratch/blender.log" | tail -20; fail "the Blender import or render failed"; }
grep '^import_shot: frame' "$scratch/blender.log"
for f in 0 1; do
  n=$(include_vertices "$scratch/shot/shot/magnets_$(printf %04d $f).inc")
  (( n > 0 )) || fail "frame $f: no vertices in the include's mesh2"
  grep -q "^import_shot: frame $f solids: $n vertices match (mesh ferro_solids)$" "$scratch/blender.log" ||
    fail "frame $f: FerroSolids does not show the include's $n vertices as the one static mesh"
done
grep -q '^import_shot: frame 1: .* velocity attribute matches' "$scratch/blender.log" || fail "the fluid was not checked"
python3 "$src/tests/tools/pngcheck.py" varied "$scratch/blender_0001.png" || fail "the Blender render is one flat colour"

# Keys that move the cone 4 mm along x over the first frame: ferro-pov places it at each
# frame's time (ferro-sim keeps solids still, so only the export sees the keys).
cp -r "$scratch/shot" "$scratch/moving"
{ cat "$src/tests/data/small_solid_pool.toml"
  printf '[[solids.keys]]\ntime = 0.0\nposition = [0.0, 0.0, 0.0]\n[[solids.keys]]\ntime = 0.0333333333\nposition = [0.004, 0.0, 0.0]\n'
} > "$scratch/moving.toml"
mesh='spiky/spiky_{:04}.ply'
[[ -s "$scratch/moving/spiky/spiky_0000.ply" ]] || mesh='surface/surface_{:04}.ply'
"$bin/ferro-pov" "$scratch/moving/$mesh" --frames 0:1 --scene "$scratch/moving.toml" --out "$scratch/moving/shot" \
  --no-shot --quiet || fail "ferro-pov with the moving cone failed"
cmp -s "$scratch/shot/shot/magnets_0001.inc" "$scratch/moving/shot/magnets_0001.inc" && fail "the keys did not move the cone"
blender -b --python-exit-code 1 --python "$import" -- "$scratch/moving" --check --save "$scratch/moving.blend" \
  > "$scratch/moving.log" 2>&1 || { tail -20 "$scratch/moving.log"; fail "the Blender import of the moving cone failed"; }
for f in 0 1; do
  n=$(include_vertices "$scratch/moving/shot/magnets_$(printf %04d $f).inc")
  grep "^import_shot: frame $f solids: $n vertices match (mesh ferro_solids_$(printf %04d $f))$" "$scratch/moving.log" ||
    fail "frame $f: FerroSolids does not show the frame's own mesh of the moving cone"
done
# The saved file swaps the solids' mesh by itself (-y: its handler text block runs on load).
cat > "$scratch/reopen.py" <<'PY'
import sys
import bpy
for f in (0, 1):
    bpy.context.scene.frame_set(f)
    me = bpy.data.objects["FerroSolids"].data
    xs = [v.co.x for v in me.vertices]
    print("reopened: frame %d: %s, %d vertices, centre x %.4f m" % (f, me.name, len(me.vertices), (min(xs) + max(xs)) / 2))
    if me.name != "ferro_solids_%04d" % f:
        sys.exit(1)
PY
blender -b -y "$scratch/moving.blend" --python-exit-code 1 --python "$scratch/reopen.py" > "$scratch/reopen.log" 2>&1 ||
  { tail -20 "$scratch/reopen.log"; fail "the saved .blend does not swap the solids' mesh"; }
grep '^reopened:' "$scratch/reopen.log"
echo "blender solids test: passed"
