#!/usr/bin/env bash
# spikes.sh: the spike refinement trade: ferro-spikes' `resolution` (mesh edges per tip
# spacing) and `remesh_iterations` on one settled, supercritical frame: triangles, time, and the
# tip shape against the finest setting of the same frame.
#
#   scripts/bench/spikes.sh [OUT_DIR]      (default tests/bench/report; BENCH_QUICK=1: tiny)
#
# The frame: examples/magnet_slide.toml at 10,240 particles after its pre-roll (the same cached
# frame as surface.sh), meshed by ferro-surface at its defaults. The reference: resolution 32,
# remesh_iterations 5. Tip shape (bench-compare-mesh --above Z, Z = the top of the unspiked
# surface): mean and max distance between the two spiky meshes over the vertices above Z (the
# spikes), and the tallest tip's height.
# Writes spikes_resolution.csv/.png, spikes_remesh_iterations.csv/.png, spikes_presets.csv/.png
# (the settings of scripts/presets.conf), spikes.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init spikes "$@"
bench_need ferro-surface ferro-spikes bench-compare-mesh

count=10240 preroll=2.0 resolutions="4 8 12 16 24" iterations="0 1 2 3" ref_res=32 ref_it=5 repeats=2
if [[ $quick == 1 ]]; then count=2560 preroll=0.2 resolutions="4 16" iterations="0 3" ref_res=16 ref_it=4 repeats=1; fi
scene="$root/examples/magnet_slide.toml"
sets=(--set "fluid.block.0.count=$count" --set "shot.preroll=$preroll")
bench_settled_frame frame "$scene" "${sets[@]}"
"$bin/ferro-surface" "$frame" --out "$work/surface.ply" --quiet
top="$("$bin/bench-compare-mesh" "$work/surface.ply" "$work/surface.ply")"
top="$(kv top_a_m "$top")"

# spiky NAME RESOLUTION ITERATIONS: $work/NAME.ply, best wall time in $seconds.
spiky() {
  bench_best seconds "$repeats" "$bin/ferro-spikes" "$work/surface.ply" --particles "$frame" --scene "$scene" \
    "${sets[@]}" --set "spikes.resolution=$2" --set "spikes.remesh_iterations=$3" --out "$work/$1.ply"
}
repeats=1 spiky reference "$ref_res" "$ref_it"
ref_seconds="$seconds"
tips="$(sed -n 's/^ferro-spikes: \([0-9]*\) tips.*/\1/p' "$work/last.log")"
ref_label="resolution $ref_res iterations $ref_it"
header="setting,resolution,remesh_iterations,cpu_seconds,triangles,tip_mean_distance_m,tip_max_distance_m,tip_height_m,tip_height_error_m,mean_distance_m,reference"
row() { # SETTING RES IT: $work/current.ply against the reference
  local line; line="$("$bin/bench-compare-mesh" "$work/current.ply" "$work/reference.ply" --above "$top")"
  local ha hb; ha="$(calc "$(kv top_a_m "$line") - $top")" hb="$(calc "$(kv top_b_m "$line") - $top")"
  echo "$1,$2,$3,$seconds,$(kv triangles_a "$line"),$(kv mean_above_m "$line"),$(kv max_above_m "$line"),$ha,$(calc "$ha - $hb"),$(kv mean_m "$line"),$ref_label"
}
reference_row() { cp "$work/reference.ply" "$work/current.ply"; seconds="$ref_seconds"; row "$ref_res/$ref_it (ref)" "$ref_res" "$ref_it"; }

{
  echo "$header"
  for r in $resolutions; do spiky current "$r" 3; row "resolution $r" "$r" 3; done
  reference_row
} > "$out/spikes_resolution.csv"
bench_plot "$out/spikes_resolution.csv" cpu_seconds tip_mean_distance_m spikes_resolution "ferro-spikes resolution (remesh_iterations 3): tip distance to the finest"
{
  echo "$header"
  for i in $iterations; do spiky current 16 "$i"; row "iterations $i" 16 "$i"; done
  reference_row
} > "$out/spikes_remesh_iterations.csv"
bench_plot "$out/spikes_remesh_iterations.csv" cpu_seconds tip_mean_distance_m spikes_remesh_iterations "ferro-spikes remesh_iterations (resolution 16): tip distance to the finest"

# The presets' settings (scripts/presets.conf) measured as they are used.
{
  echo "$header"
  for p in "preview 8 1" "final 16 3" "large 12 1"; do
    read -r name r i <<< "$p"
    [[ $quick == 1 && $name != final ]] && continue
    spiky current "$r" "$i"; row "$name ($r / $i)" "$r" "$i"
  done
  reference_row
} > "$out/spikes_presets.csv"
bench_plot "$out/spikes_presets.csv" cpu_seconds tip_mean_distance_m spikes_presets "ferro-spikes at the presets' resolution / remesh_iterations"

r1="$out/spikes_resolution.csv" i1="$out/spikes_remesh_iterations.csv"
{
  echo "## Spikes: refinement"
  echo
  echo "What ran: \`scripts/bench/spikes.sh\`. The settled frame of surface.sh (examples/magnet_slide.toml,"
  echo "$count particles, $tips tips) meshed by ferro-surface at its defaults, then ferro-spikes at each"
  echo "setting; the reference is the finest setting ($ref_label, $ref_seconds s). Tip columns"
  echo "(\`bench-compare-mesh --above\`): distances between the two spiky meshes over the vertices above"
  echo "the unspiked surface's top ($top m), i.e. the spikes; tip height = tallest tip above that top."
  echo "CPU seconds (user + system of all threads): the least of $repeats runs of ferro-spikes (read, spikes, remesh, write)."
  echo
  echo "Resolution (edges per tip spacing; remesh_iterations 3): ![](spikes_resolution.png)"
  echo
  table "$r1"
  echo
  echo "Remeshing rounds (resolution 16): ![](spikes_remesh_iterations.png)"
  echo
  table "$i1"
  echo
  echo "The presets' settings (resolution / rounds): ![](spikes_presets.png)"
  echo
  table "$out/spikes_presets.csv"
  echo
  echo "Findings:"
  echo
  echo "- Default (resolution 16, 3 rounds): $(col "$r1" "resolution 16" 5) triangles in $(r3 "$(col "$r1" "resolution 16" 4)") s, tips"
  echo "  $(mm "$(col "$r1" "resolution 16" 6)") (mean) from the finest mesh, tallest tip off by $(mm "$(col "$r1" "resolution 16" 9)")."
  echo "- Resolution 8: $(col "$r1" "resolution 8" 5) triangles in $(r3 "$(col "$r1" "resolution 8" 4)") s, tips $(mm "$(col "$r1" "resolution 8" 6)") (mean),"
  echo "  tallest tip off by $(mm "$(col "$r1" "resolution 8" 9)"); resolution 4: tips $(mm "$(col "$r1" "resolution 4" 6)"), tallest off by $(mm "$(col "$r1" "resolution 4" 9)")."
  echo "- No remeshing (0 rounds): tips $(mm "$(col "$i1" "iterations 0" 6)") (mean), tallest off by $(mm "$(col "$i1" "iterations 0" 9)"), in $(r3 "$(col "$i1" "iterations 0" 4)") s;"
  echo "  1 round $(mm "$(col "$i1" "iterations 1" 6)") in $(r3 "$(col "$i1" "iterations 1" 4)") s, 3 rounds (default) $(mm "$(col "$i1" "iterations 3" 6)") in $(r3 "$(col "$i1" "iterations 3" 4)") s:"
  echo "  after the first round more rounds buy no tip accuracy (they even out the triangles, which this does not measure)."
  echo
  echo "For scale: at 640x480 the default camera sees the 10 cm dish at about 0.2 mm per pixel, so tip errors"
  echo "below 0.05 mm are a quarter pixel. Recommended: preview resolution 8, 1 round; final the defaults"
  echo "(16, 3 rounds); a large shot resolution 12, 1 round."
} > "$out/spikes.md"
bench_note "wrote $out/spikes.md, spikes_resolution.csv/.png, spikes_remesh_iterations.csv/.png"
