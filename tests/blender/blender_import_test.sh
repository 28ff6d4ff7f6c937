#!/usr/bin/env bash
# A shot in Debian's Blender 3.4, headless (issue 30): a three-frame shot of a small pool is
# made with scripts/shot.sh, imported with scripts/blender/import_shot.py, which checks every
# frame's vertex count and "velocity" attribute against the PLY files and the frame rate
# against the shot, and one frame is rendered with Cycles on the CPU at 4 samples (motion
# blur on). The render must show the fluid: not one flat colour.
# Usage: blender_import_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR. Fails (never skips) when
# Blender is missing: scripts/install-deps.sh --with-blender installs it, and CI runs this.
set -euo pipefail
src="$1" bin="$2" scratch="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
command -v blender > /dev/null || fail "blender is not installed (scripts/install-deps.sh --with-blender)"
rm -rf "$scratch"
mkdir -p "$scratch"
export FERRO_BIN="$bin"

# 2,000 particles poured into a dish, frames 0..2 (the pour moves: velocities are not zero).
"$src/scripts/shot.sh" "$src/tests/data/small_pool.toml" "$scratch/shot" --max-frames 2 --no-video \
  --set shot.preroll=0 --set render.width=64 --set render.height=48 > "$scratch/shot.log" 2>&1 ||
  { tail -20 "$scratch/shot.log"; fail "shot.sh failed"; }
for f in 0000 0001 0002; do [[ -s "$scratch/shot/surface/surface_$f.ply" ]] || fail "no surface_$f.ply"; done

blender -b --python-exit-code 1 --python "$src/scripts/blender/import_shot.py" -- "$scratch/shot" --check \
  --render 2 "$scratch/blender_0002.png" --samples 4 --save "$scratch/shot.blend" > "$scratch/blender.log" 2>&1 ||
  { grep -v '^Fra:' "$scratch/blender.log" | tail -20; fail "the Blender import or render failed"; }
grep '^import_shot: frame' "$scratch/blender.log"
[[ $(grep -c '^import_shot: frame .* velocity attribute matches' "$scratch/blender.log") == 3 ]] ||
  fail "not every frame was checked"
[[ -s "$scratch/shot.blend" ]] || fail "no .blend saved"

# The render shows something: its pixels are not all one value.
python3 "$src/tests/tools/pngcheck.py" varied "$scratch/blender_0002.png" || fail "the Blender render is one flat colour"
echo "blender import test: passed"
