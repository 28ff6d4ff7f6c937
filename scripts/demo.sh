#!/usr/bin/env bash
# The main job: installs missing packages, builds, and runs the bundled demo shot
# (examples/paper_fig9_approach.toml: a magnet approaching a dish of ferrofluid, paper
# Fig. 9, 40,960 particles) end to end: simulation, surface, spikes, POV-Ray export and
# render, then a video and a GIF. Output in out/fig9 (or the directory given).
# Usage: scripts/demo.sh [OUTDIR]
set -euo pipefail
# --help prints the comment above (everything before `set -e`).
if [[ "${1:-}" == "--help" || "${1:-}" == "-h" ]]; then sed -n '2,/^set -e/{/^set -e/d;s/^# \{0,1\}//;p}' "$0"; exit 0; fi
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh" --with-video
"$root/scripts/build.sh"
out="${1:-$root/out/fig9}"
start=$(date +%s)
"$root/scripts/shot.sh" "$root/examples/paper_fig9_approach.toml" "$out"
echo "demo: done in $(( $(date +%s) - start )) s: frames in $out/png, video $out/shot.mp4 and $out/shot.gif"
