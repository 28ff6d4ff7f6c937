#!/usr/bin/env bash
# surface.sh: the surface knobs' trade: method and voxel size of ferro-surface on one settled
# frame, each mesh against a fine-voxel reference surface of the same frame; and OpenVDB's own
# particle surfacer beside ferro-surface (bench-surface).
#
#   scripts/bench/surface.sh [OUT_DIR]      (default tests/bench/report; BENCH_QUICK=1: tiny)
#
# The frame: examples/magnet_slide.toml at 10,240 particles after its pre-roll (a heap over
# the magnet; cached in OUT_DIR/cache). The reference: method anisotropic at voxel = spacing/8.
# Distances (bench-compare-mesh): every vertex of each mesh to the other's triangles.
# Writes surface_voxel.csv/.png, surface_method.csv/.png, surface_openvdb.csv, surface.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init surface "$@"
bench_need ferro-surface bench-compare-mesh

count=10240 preroll=2.0 factors="1 0.75 0.5 0.35 0.25" ref_factor=0.125 repeats=2
if [[ $quick == 1 ]]; then count=2560 preroll=0.2 factors="1 0.5" ref_factor=0.25 repeats=1; fi
bench_settled_frame frame "$root/examples/magnet_slide.toml" --set "fluid.block.0.count=$count" --set "shot.preroll=$preroll"
spacing="$(sed -n 's/^comment spacing //p' "$frame" | head -n 1)"
[[ -n "$spacing" ]] || bench_die 3 "$frame: no 'comment spacing' line"

# mesh NAME METHOD VOXEL: $work/NAME.ply, its best wall time in $seconds.
mesh() {
  bench_best seconds "$repeats" "$bin/ferro-surface" "$frame" --out "$work/$1.ply" --method "$2" --voxel-size "$3" --quiet
}
ref_voxel="$(calc "$spacing * $ref_factor")"
bench_note "reference: anisotropic, voxel $ref_voxel m (spacing $spacing m / $(calc "1 / $ref_factor"))"
repeats=1 mesh reference anisotropic "$ref_voxel"
ref_seconds="$seconds"
ref_label="anisotropic voxel=spacing/$(calc "1 / $ref_factor")"

# row SETTING VOXEL: one CSV row of the mesh $work/current.ply against the reference.
header="setting,voxel_m,cpu_seconds,triangles,mean_distance_m,max_distance_m,volume_m3,volume_error_pct,reference"
row() {
  local line; line="$("$bin/bench-compare-mesh" "$work/current.ply" "$work/reference.ply")"
  local va vb; va="$(kv volume_a_m3 "$line")" vb="$(kv volume_b_m3 "$line")"
  echo "$1,$2,$seconds,$(kv triangles_a "$line"),$(kv mean_m "$line"),$(kv max_m "$line"),$va,$(calc "100 * ($va - $vb) / $vb"),$ref_label"
}

{
  echo "$header"
  for f in $factors; do
    voxel="$(calc "$spacing * $f")"
    mesh current anisotropic "$voxel"
    row "$f spacing" "$voxel"
  done
  # the reference against itself: its cost, zero error (anchors the plot)
  cp "$work/reference.ply" "$work/current.ply"; seconds="$ref_seconds"
  row "$ref_factor spacing (ref)" "$ref_voxel"
} > "$out/surface_voxel.csv"
bench_plot "$out/surface_voxel.csv" cpu_seconds mean_distance_m surface_voxel "ferro-surface anisotropic: voxel size (setting = voxel edge in particle spacings)"

default_voxel="$(calc "$spacing * 0.5")"
{
  echo "$header"
  for m in anisotropic isotropic openvdb; do
    mesh current "$m" "$default_voxel"
    row "$m" "$default_voxel"
  done
} > "$out/surface_method.csv"
bench_plot "$out/surface_method.csv" cpu_seconds mean_distance_m surface_method "ferro-surface method at voxel = spacing/2"

# OpenVDB's own particle surfacer beside ferro-surface's methods (bench-surface, 40,960 particles).
peer_note="bench-surface is not built: OpenVDB comparison skipped"
echo "method,seconds,ratio_to_openvdb,reference" > "$out/surface_openvdb.csv"
if [[ -x "$bin/bench-surface" && $quick != 1 ]]; then
  "$bin/bench-surface" --small-only --threads 2 > "$work/bench-surface.txt"
  awk '$1 ~ /^[0-9]+$/ {
         # "40960  OpenVDB ParticlesToLevelSet+v2m  0.123 ..." / "40960  ferro-surface anisotropic  0.456 ..."
         t = $4
         if ($2 == "OpenVDB") { name = "OpenVDB ParticlesToLevelSet+volumeToMesh"; ref = t } else name = $2 " " $3
         printf "%s,%s,%.2f,OpenVDB ParticlesToLevelSet+volumeToMesh\n", name, t, t / ref }' \
    "$work/bench-surface.txt" >> "$out/surface_openvdb.csv"
  peer_note="$(head -n 1 "$work/bench-surface.txt")"
elif [[ $quick == 1 ]]; then
  peer_note="skipped with BENCH_QUICK=1"
fi

# ---- the Markdown section ----
v1="$out/surface_voxel.csv" m1="$out/surface_method.csv"
{
  echo "## Surface: method and voxel size"
  echo
  echo "What ran: \`scripts/bench/surface.sh\`. One settled frame (examples/magnet_slide.toml,"
  echo "$count particles, spacing $(calc "$spacing * 1000") mm, after its pre-roll: a heap over the magnet) meshed"
  echo "by ferro-surface at several settings; each mesh is compared with a reference mesh of the"
  echo "same frame ($ref_label, $ref_seconds s) by \`bench-compare-mesh\`: distance from every vertex of"
  echo "each mesh to the other's triangles (mean over both, max of both), enclosed volumes."
  echo "CPU seconds (user + system of all threads): the least of $repeats runs of ferro-surface (read, mesh, write)."
  echo
  echo "Voxel size (anisotropic; setting = voxel edge in particle spacings): ![](surface_voxel.png)"
  echo
  table "$v1"
  echo
  echo "Method at the default voxel (spacing/2): ![](surface_method.png)"
  echo
  table "$m1"
  echo
  echo "OpenVDB's own particle surfacer (\`bench-surface --small-only\`: $peer_note):"
  echo
  table "$out/surface_openvdb.csv"
  echo
  echo "Findings:"
  echo
  echo "- Voxel = spacing/2 (the default) lies $(mm "$(col "$v1" "0.5 spacing" 5)") from the reference on average"
  echo "  (max $(mm "$(col "$v1" "0.5 spacing" 6)")), in $(r3 "$(col "$v1" "0.5 spacing" 3)") s; voxel = spacing: $(mm "$(col "$v1" "1 spacing" 5)") mean, $(r3 "$(col "$v1" "1 spacing" 3)") s;"
  echo "  voxel = spacing/4: $(mm "$(col "$v1" "0.25 spacing" 5)") mean, $(r3 "$(col "$v1" "0.25 spacing" 3)") s."
  echo "- Enclosed volume against the reference: $(col "$v1" "1 spacing" 8) % at voxel = spacing, $(col "$v1" "0.5 spacing" 8) % at spacing/2."
  echo "- Method at spacing/2: anisotropic $(mm "$(col "$m1" anisotropic 5)") mean in $(r3 "$(col "$m1" anisotropic 3)") s, isotropic"
  echo "  $(mm "$(col "$m1" isotropic 5)") in $(r3 "$(col "$m1" isotropic 3)") s, openvdb $(mm "$(col "$m1" openvdb 5)") in $(r3 "$(col "$m1" openvdb 3)") s."
  echo
  echo "Recommended, all presets: \`surface.method = anisotropic\`, \`surface.voxel_size = 0\` (spacing/2, the"
  echo "defaults). The surface is the cheapest stage per frame (compare spikes.md and render.md), so a"
  echo "preview gains little from a coarser voxel and would pay in volume; finer than spacing/2 costs"
  echo "about 2-4x per halving for an error already a small fraction of the spacing."
} > "$out/surface.md"
bench_note "wrote $out/surface.md, surface_voxel.csv/.png, surface_method.csv/.png, surface_openvdb.csv"
