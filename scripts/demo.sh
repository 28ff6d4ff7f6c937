#!/usr/bin/env bash
# The main job: installs missing packages, builds, and runs the bundled demo shot
# (examples/paper_fig9_approach.toml: a magnet approaching a dish of ferrofluid, paper
# Fig. 9, 40,960 particles) end to end: simulation, surface, spikes, POV-Ray export and
# render, then a video and a GIF. Output in out/fig9 (or the directory given).
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh" --with-video
"$root/scripts/build.sh"
out="${1:-$root/out/fig9}"
start=$(date +%s)
"$root/scripts/shot.sh" "$root/examples/paper_fig9_approach.toml" "$out"
echo "demo: done in $(( $(date +%s) - start )) s: frames in $out/png, video $out/shot.mp4 and $out/shot.gif"
