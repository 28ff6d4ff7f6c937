#!/usr/bin/env bash
# The main job: installs missing packages, builds, and runs the bundled example shot
# (examples/dish.toml) into out/dish. Grows with each pipeline stage.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh"
"$root/scripts/build.sh"
out="${1:-$root/out/dish}"
"$root/build/bin/ferro-sim" "$root/examples/dish.toml" --out "$out/particles" --overwrite
echo "demo: particle frames in $out/particles"
