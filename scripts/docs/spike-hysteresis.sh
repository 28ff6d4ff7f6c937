#!/usr/bin/env bash
# spike-hysteresis.sh: the pictures of docs/look-guide.md, "Spikes that persist as the field
# falls": a dish (10,240 particles) over a strong magnet that is lowered slowly from 2 cm to 5 cm
# under the floor between 1.0 s and 2.5 s, made with spikes.height_curve = "fade" (the default)
# and "bifurcation" (lower_threshold 0.85), frames 36-63, and the frames' tip counts.
#
#   scripts/docs/spike-hysteresis.sh [WORK_DIR]   # default /tmp/ferro-spike-hysteresis
#
# The shot is simulated once (WORK_DIR/fade); the bifurcation variant is a copy run again with
# its --set, so only the spikes, the export and the render are made again. ~15 min on 2 cores. Writes
# docs/media/look/hysteresis_{fade,bifurcation}_NNNN.png for the frames named in FRAMES and
# prints "frame fade_tips bifurcation_tips" for every frame.
# Exit codes: 2 bad arguments, 3 a stage failed.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
[[ $# -le 1 ]] || { echo "usage: scripts/docs/spike-hysteresis.sh [WORK_DIR]" >&2; exit 2; }
work="${1:-/tmp/ferro-spike-hysteresis}"
media="$root/docs/media/look"
frames="${FRAMES:-45 51}"
mkdir -p "$work" "$media"
scene="$work/lowered.toml"
cat > "$scene" <<'TOML'
# A strong magnet under a dish heaps the fluid into spikes, then is lowered slowly.
[shot]
fps = 30
duration = 2.5
preroll = 0.5
[fluid]
rest_density = 1200.0
viscosity = 5e-6
surface_tension = 0.025
[[fluid.block]]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.05
height = 0.01
count = 10240
[container]
type = "dish"
center = [0.0, 0.0, 0.0]
radius = 0.05
height = 0.03
[sim]
solver = "dfsph"
[[magnets]]
kind = "dipole"
position = [0.0, 0.0, -0.02]
direction = [0.0, 0.0, 1.0]
moment = 3.0
softening = 0.002
[[magnets.keys]]
time = 1.0
position = [0.0, 0.0, -0.02]
[[magnets.keys]]
time = 2.5
position = [0.0, 0.0, -0.05]
[magnetization]
susceptibility = 1.5
saturation = 35000
TOML

common=(--set render.width=480 --set render.height=360
        --set render.antialias=true --set 'render.camera_position=[0.0,-0.09,0.06]'
        --set 'render.camera_target=[0.0,0.0,0.01]' --max-frames 75 --frames 36:63 -j 2 --no-video)
run() { "$root/scripts/shot.sh" "$scene" "$1" "${common[@]}" "${@:2}" 2> "$1.log" ||
          { tail -3 "$1.log" >&2; exit 3; }; }

echo "spike-hysteresis.sh: fade (the default), simulating frames 0-75" >&2
# The simulation is kept; the spikes and everything after them are made again (make would
# otherwise keep the frames' mesh includes of an earlier ferro-spikes: its meshes are
# secondary files, and a missing one does not make the include out of date).
rm -rf "$work/fade/spiky" "$work/fade/png" "$work/fade/shot"/mesh_*.inc
run "$work/fade"
rm -rf "$work/bifurcation"
cp -a "$work/fade" "$work/bifurcation"
echo "spike-hysteresis.sh: bifurcation (lower_threshold 0.85)" >&2
run "$work/bifurcation" --set spikes.height_curve=bifurcation --set spikes.lower_threshold=0.85
tips() { head -c 4000 "$1" | strings | sed -n 's/^comment spike_tips //p'; }
echo "frame fade_tips bifurcation_tips"
for f in $(seq 36 3 63); do
  tag=$(printf '%04d' "$f")
  echo "$f $(tips "$work/fade/spiky/spiky_$tag.ply") $(tips "$work/bifurcation/spiky/spiky_$tag.ply")"
done
for f in $frames; do
  tag=$(printf '%04d' "$f")
  cp "$work/fade/png/frame_$tag.png" "$media/hysteresis_fade_$tag.png"
  cp "$work/bifurcation/png/frame_$tag.png" "$media/hysteresis_bifurcation_$tag.png"
done
echo "spike-hysteresis.sh: wrote $media/hysteresis_*.png" >&2
