#!/usr/bin/env bash
# spike-look.sh: the pictures of docs/look-guide.md, "Directing the spikes": one frame of
# examples/magnet_slide.toml (10,240 particles, the look guide's frame) with each of the
# art director's [spikes] keys at two values.
#
#   scripts/docs/spike-look.sh [WORK_DIR]     # default /tmp/ferro-spike-look; ~6 min on 2 cores
#
# The frame is simulated once (WORK_DIR/base); each variant is a copy of that shot run again
# with its --set, so only the spikes, the export and the render are made again (shot.sh's
# stamps). The PNGs go to docs/media/look/spikes_NAME.png. SPIKE_LOOK_ONLY="NAME ..." makes
# only those variants (the base frame is made too, if WORK_DIR lacks it). With gnuplot and NumPy
# it also draws spikes_squareness_plan.png, the planforms from above (scripts/docs/spike_plan.py;
# SPIKE_LOOK_ONLY=plan draws it alone from the variants WORK_DIR holds).
# Exit codes: 2 bad arguments, 3 a stage failed.
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
[[ $# -le 1 ]] || { echo "usage: scripts/docs/spike-look.sh [WORK_DIR]" >&2; exit 2; }
work="${1:-/tmp/ferro-spike-look}"
media="$root/docs/media/look"
mkdir -p "$work" "$media"

# A close view of the heap (2 cm left of the centre, over the magnet) instead of the dish.
common=(--set fluid.block.0.count=10240 --set render.width=480 --set render.height=360
        --set render.antialias=true --set 'render.camera_position=[-0.02,-0.07,0.055]'
        --set 'render.camera_target=[-0.02,0.0,0.01]' --max-frames 1 -j 1 --no-video)
run() { "$root/scripts/shot.sh" "$root/examples/magnet_slide.toml" "$1" "${common[@]}" "${@:2}" 2> "$1.log" ||
          { tail -3 "$1.log" >&2; exit 3; }; }

only="${SPIKE_LOOK_ONLY:-}"
if [[ -z "$only" || ! -f "$work/base/png/frame_0001.png" ]]; then
  echo "spike-look.sh: the base frame (pre-roll and frame 1)" >&2
  run "$work/base"
fi
[[ -n "$only" ]] || cp "$work/base/png/frame_0001.png" "$media/spikes_default.png"

# name, then the --set values of the variant.
variants=(
  "gain_0.5 spikes.height_gain=0.5"
  "gain_2 spikes.height_gain=2.0"
  "sharpness_2 spikes.sharpness=2.0"
  "sharpness_4 spikes.sharpness=4.0"
  "jitter_0.15 spikes.jitter=0.15"
  "jitter_0.3 spikes.jitter=0.3"
  "defects_0.15 spikes.defects=0.15"
  "defects_0.35 spikes.defects=0.35"
  "square spikes.pattern=square"
  "square_sharp spikes.pattern=square spikes.sharpness=3.0"
  "squareness_0.35 spikes.squareness=0.35"
  "squareness_0.7 spikes.squareness=0.7"
  "spacing_physical spikes.spacing=physical"
  "spacing_growth spikes.spacing=growth"
)
for v in "${variants[@]}"; do
  read -r name rest <<< "$v"
  [[ -z "$only" || " $only " == *" $name "* ]] || continue
  sets=()
  for kv in $rest; do sets+=(--set "$kv"); done
  rm -rf "$work/$name"
  cp -a "$work/base" "$work/$name"
  echo "spike-look.sh: $name ($rest)" >&2
  run "$work/$name" "${sets[@]}"
  cp "$work/$name/png/frame_0001.png" "$media/spikes_$name.png"
done
# The planform seen from above (a perspective render hides it behind the spikes' lean): the
# spiky meshes of the squareness variants as height maps, 56 mm around the magnet's foot.
plan=(base squareness_0.35 squareness_0.7 square)
if command -v gnuplot > /dev/null && [[ -z "$only" || " $only " == *" squareness_0.7 "* || " $only " == *" plan "* ]]; then
  panels=""
  for name in "${plan[@]}"; do
    mesh="$work/$name/spiky/spiky_0001.ply"
    [[ -f "$mesh" ]] || { echo "spike-look.sh: no $mesh: no plan view" >&2; panels=""; break; }
    python3 "$root/scripts/docs/spike_plan.py" "$mesh" "$work/plan_$name.dat" --centre=-0.02,0 --half 0.028 || exit 3
    case "$name" in
      base) title="squareness 0 (the default)" ;;
      square) title="squareness 1 (pattern = square)" ;;
      *) title="squareness ${name#squareness_}" ;;
    esac
    panels+="set title '$title'; plot '$work/plan_$name.dat' matrix with image; "
  done
  if [[ -n "$panels" ]]; then
    gnuplot <<PLOT || { echo "spike-look.sh: gnuplot failed" >&2; exit 3; }
set terminal pngcairo size 1200,330
set output '$media/spikes_squareness_plan.png'
set multiplot layout 1,4
unset key; unset colorbox; unset xtics; unset ytics; set size ratio -1
set palette grey; set cbrange [7:15]
$panels
unset multiplot
PLOT
  fi
fi
echo "spike-look.sh: wrote $media/spikes_*.png" >&2
