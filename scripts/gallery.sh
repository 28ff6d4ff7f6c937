#!/usr/bin/env bash
# gallery.sh [OUTDIR] [--only NAME]...: a still and a one-line description of every
# examples/*.toml, written to docs/gallery.md with the stills in docs/media/gallery/NAME.png.
#
# Each example runs through scripts/shot.sh at --preset preview (320x240, no anti-aliasing,
# coarse spikes), simulated only up to the frame of its still and rendering that frame alone
# (--max-frames N --frames N:N). To keep the whole gallery to a few minutes on two cores,
# the dish scenes run at 10,240 particles instead of their 40,960 (million_dish.toml: instead
# of 1,000,000), pre-rolls are cut to 0.3 s, and scenes the default camera does not frame
# get their own camera; every still's row in the page says what was changed. The
# description is the first sentence of the scene file's opening comment.
#
# Containers: look.inc draws only dishes, so before the render the script adds to the shot's
# look.inc the glass tank of a "box" scene, and the vessel of a "mesh" scene (its file made a
# mesh2 by ferro-pov, the floor lowered to its bottom): docs/look-guide.md, "Containers the
# template does not draw".
#
#   OUTDIR       the shots' working directories, OUTDIR/NAME (default: out/gallery); a second
#                run reuses them (pre-roll caches, make's bookkeeping)
#   --only NAME  redo only this example (repeatable); the page is rewritten from every
#                still made so far in OUTDIR
# Environment: FERRO_BIN (default build/bin), passed on to shot.sh.
# Exit: 0 done, 2 bad arguments, 3 a shot failed (its error above).
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
die() { echo "gallery.sh: error: $*" >&2; exit 2; }

out="" only=()
while (($#)); do
  case "$1" in
    --only) only+=("${2:?--only needs a name}"); shift 2 ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    -*) die "unknown option $1" ;;
    *) [[ -z "$out" ]] || die "one OUTDIR only"; out="$1"; shift ;;
  esac
done
out="${out:-$root/out/gallery}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
media="$root/docs/media/gallery"
page="$root/docs/gallery.md"
mkdir -p "$media"

# The plan of each example: the frame of its still, the overrides after --preset preview,
# and a note for the page on what differs from the scene file. DISH is the particle count
# of the reduced dish scenes; CAM_* are cameras for scenes the default one does not frame.
DISH=10240
PREROLL="shot.preroll=0.3"
dish="$(sed -E ':a; s/([0-9])([0-9]{3})($|,)/\1,\2\3/; ta' <<< "$DISH")"   # 10,240
plan() {
  frame=0 sets=() note=""
  case "$1" in
    annotated)           frame=60; sets=(fluid.block.0.count=$DISH); note="$dish particles (scene: 40,960)" ;;
    dam_break)           frame=20
                         sets=("render.camera_position=[0.2,-0.6,0.17]" "render.camera_target=[0.2,0.006,0.045]")
                         note="camera on its tank" ;;
    dish)                frame=30; sets=(fluid.block.0.count=$DISH); note="$dish particles (scene: 40,960)" ;;
    ferrohydrostatic_pool) frame=4; sets=("render.camera_position=[0,-0.095,0.065]" "render.camera_target=[0,0,0.004]")
                         note="camera moved in to its 5 cm dish" ;;
    hydrostatic)         frame=3
                         sets=("render.camera_position=[0.025,-0.16,0.12]" "render.camera_target=[0.025,0.025,0.035]")
                         note="camera on its tank" ;;
    magnet_slide)        frame=30; sets=(fluid.block.0.count=$DISH "$PREROLL"); note="$dish particles (scene: 40,960), pre-roll 0.3 s (scene: 2 s)" ;;
    million_dish)        frame=36; sets=(fluid.block.0.count=$DISH); note="$dish particles (scene: 1,000,000)" ;;
    helix_climb)         frame=29; note="as the scene, the coil just at 2 A" ;;
    morpho_tower)        frame=48; sets=(fluid.block.0.count=5120); note="5,120 particles (scene: 20,480), the coil held at 2.5 A" ;;
    paper_fig10_release) frame=30; sets=(fluid.block.0.count=$DISH)
                         note="$dish particles (scene: 40,960); the heap before the release, no spikes at this count" ;;
    paper_fig11_two_magnets) frame=60; sets=(fluid.block.0.count=$DISH)
                         note="$dish particles (scene: 40,960); two heaps, no spikes at this count" ;;
    paper_fig9_approach) frame=36; sets=(fluid.block.0.count=$DISH "$PREROLL"); note="$dish particles (scene: 40,960), pre-roll 0.3 s (scene: 1.5 s)" ;;
    rosensweig_uniform)  frame=9;  sets=(fluid.block.0.count=$DISH); note="$dish particles (scene: 40,960)" ;;
    two_magnets_merge)   frame=39; sets=(fluid.block.0.count=$DISH "$PREROLL"); note="$dish particles (scene: 40,960), pre-roll 0.3 s (scene: 1.5 s)" ;;
    vessel_pour)         frame=15
                         sets=("render.camera_position=[0,-0.11,0.08]" "render.camera_target=[0,0,0.012]")
                         note="camera on its cup" ;;
    *)                   frame=10; note="as the scene (no plan in gallery.sh: frame 10)" ;;
  esac
}

# The tank of a "box" container, appended to the shot's look.inc (docs/look-guide.md).
box_tank='
// ---- Added by scripts/gallery.sh: a glass tank for "box" containers (docs/look-guide.md) ----
#if (strcmp(FerroContainerType, "box") = 0)
  difference {
    box { FerroBoxMin - <LookWall, LookWall, LookWall>, FerroBoxMax + <LookWall, 0, LookWall> }
    box { FerroBoxMin - y * 0.01, FerroBoxMax + y * 1 }
    material { LookGlass }
    no_shadow
  }
#end'

# The vessel of a "mesh" container: ferro-pov turns its file into a mesh2 (as it does a frame's
# surface), renamed LookVessel, in SHOTDIR/vessel.inc. The floor goes down to the vessel's
# bottom (shot.pov puts it under the fluid's starting block, which a falling fluid leaves) and
# the vessel is drawn in the dish's glass. Only for a file without scale or translate.
vessel_include() { # SCENE SHOTDIR
  local file
  file="$(awk '/^\[/ { in_c = ($0 ~ /^\[container\]/) } in_c && /^(scale|translate)[ =]/ { print "-"; exit }
               in_c && /^file *=/ { sub(/^file *= *"/, ""); sub(/".*/, ""); print; exit }' "$1")"
  [[ -n "$file" && "$file" != "-" ]] || return 1
  [[ "$file" == /* ]] || file="$(dirname "$1")/$file"
  local tmp="$2/.vessel"
  "$bin/ferro-pov" "$file" --scene "$1" --frame 0 --out "$tmp" --no-shot --quiet
  sed -n 's/FerroMeshMin/LookVesselMin/; s/FerroMeshMax/LookVesselMax/; s/#declare FerroMesh = /#declare LookVessel = /; /^\/\/\|FerroMeshVertices\|FerroMeshTriangles/!p' \
    "$tmp/mesh_0000.inc" > "$2/vessel.inc"
  rm -rf "$tmp"
}
vessel_floor='// ---- Added by scripts/gallery.sh: the vessel of a "mesh" container (docs/look-guide.md) ----
#include "vessel.inc"   // LookVessel, LookVesselMin, LookVesselMax: the container, by ferro-pov
#declare FerroFloorLevel = min(FerroFloorLevel, LookVesselMin.y);'
vessel_object='
// ---- Added by scripts/gallery.sh: the vessel, in the glass of the dish ----
object { LookVessel material { LookGlass } no_shadow }'

# The first sentence of the scene's opening comment, on one line.
describe() {
  awk 'NR == 1 && !/^#/ { exit } /^#/ { sub(/^# ?/, ""); printf "%s ", $0; next } { exit }' "$1" |
    sed -E 's/  +/ /g; s/^(([^.]|\.[^ ]|\. [^A-Z(])*\.)( [A-Z(].*)?$/\1/; s/ +$//'
}

bin="${FERRO_BIN:-$root/build/bin}"
start_all=$SECONDS
for scene in "$root"/examples/*.toml; do
  name="$(basename "$scene" .toml)"
  if ((${#only[@]})); then
    skip=1
    for o in "${only[@]}"; do [[ "$o" == "$name" ]] && skip=0; done
    ((skip)) && continue
  fi
  plan "$name"
  dir="$out/$name"
  set_args=()
  for s in "${sets[@]}"; do set_args+=(--set "$s"); done
  start=$SECONDS
  # The look template first (ferro-pov writes it only when missing), so a box scene's tank
  # is in look.inc before the first render.
  mkdir -p "$dir/shot"
  "$bin/ferro-pov" --scene "$scene" --out "$dir/shot" --quiet "${set_args[@]}" >/dev/null
  if ! grep -q 'Added by scripts/gallery.sh' "$dir/shot/look.inc"; then
    if grep -q '^#declare FerroContainerType = "box"' "$dir/shot/shot.pov"; then
      printf '%s\n' "$box_tank" >> "$dir/shot/look.inc"
    elif grep -q '^#declare FerroContainerType = "mesh"' "$dir/shot/shot.pov" && vessel_include "$scene" "$dir/shot"; then
      { printf '%s\n' "$vessel_floor"; cat "$dir/shot/look.inc"; printf '%s\n' "$vessel_object"; } > "$dir/shot/look.inc.new"
      mv -f "$dir/shot/look.inc.new" "$dir/shot/look.inc"
    fi
  fi
  echo "gallery.sh: $name: frame $frame${sets:+, ${sets[*]}}" >&2
  if ! "$root/scripts/shot.sh" "$scene" "$dir" --preset preview "${set_args[@]}" \
       --max-frames "$frame" --frames "$frame:$frame" -j 1 --no-video > "$dir/gallery.log" 2>&1; then
    tail -n 20 "$dir/gallery.log" >&2
    echo "gallery.sh: error: $name failed (log: $dir/gallery.log)" >&2
    exit 3
  fi
  png="$dir/png/frame_$(printf %04d "$frame").png"
  cp "$png" "$media/$name.png"
  fps="$(sed -n 's/^#declare FerroFps = \(.*\);/\1/p' "$dir/shot/shot.pov")"
  time_s="$(awk -v f="$frame" -v fps="$fps" 'BEGIN { printf "%g", f / fps }')"
  secs=$((SECONDS - start))
  printf '| ![%s](media/gallery/%s.png) | [%s](../examples/%s.toml) | %s | t = %s s (frame %d); %s; %d s |\n' \
    "$name" "$name" "$name.toml" "$name" "$(describe "$scene")" "$time_s" "$frame" "$note" "$secs" > "$dir/row.md"
  echo "gallery.sh: $name: done in $secs s" >&2
done
total=$((SECONDS - start_all))

{
  cat <<EOF
# Gallery of the examples

One still of each scene in [examples/](../examples/), made by \`scripts/gallery.sh\` with the
default look (\`look.inc\` as ferro-pov writes it, see the [look guide](look-guide.md)). Each
scene ran at \`--preset preview\` (320×240, no anti-aliasing, coarse spikes), simulated only up
to the frame shown, and only that frame was rendered. These are previews, not the scenes'
final look: **the dish scenes ran at $dish particles** instead of their 40,960 (and
million_dish.toml at $dish instead of 1,000,000), so their surfaces and spikes are coarser than a real
run's, and the scenes with a pre-roll settled for 0.3 s instead of 1.5-2 s. The last column
says, for each still, what was changed from the scene file and how long it took (wall
seconds on two cores, simulation to render).

The template draws only dishes: the glass tanks of dam_break and hydrostatic and the cup of
vessel_pour are a few lines the script adds to their \`look.inc\` (the look guide's
"Containers the template does not draw"). With fewer particles, the weaker magnets of
paper_fig10_release (1.5 A m²) and paper_fig11_two_magnets (1.5 and 1.0 A m²) raise heaps but
no spikes (ferro-spikes: 0 tips on the frames shown); the full scenes
were not run for this page.

Remake: \`scripts/gallery.sh\` (shots in \`out/gallery/\`; \`--only NAME\` redoes one).

| still | scene | what it is | still at; changed; time |
| --- | --- | --- | --- |
EOF
  for scene in "$root"/examples/*.toml; do
    row="$out/$(basename "$scene" .toml)/row.md"
    [[ -f "$row" ]] && cat "$row"
  done
  echo
  if ((${#only[@]} == 0)); then
    echo "The whole gallery took $total s (wall, on two cores shared with other work) on its last full run."
  fi
} > "$page.tmp"
# Keep the last full run's total when only some scenes were redone.
if ((${#only[@]})) && [[ -f "$page" ]]; then
  grep '^The whole gallery took' "$page" >> "$page.tmp" || true
fi
mv -f "$page.tmp" "$page"
echo "gallery.sh: wrote $page ($total s)" >&2
