#!/usr/bin/env bash
# scene-cost.sh: "model only what a scene requires", measured: each claim with the cost with
# and without the thing the scene does not need, and whether the code keeps the claim.
#
#   scripts/bench/scene-cost.sh [OUT_DIR]      (default tests/bench/report; BENCH_QUICK=1: tiny)
#
#   1. No magnets, no magnetics cost: ferro-sim CPU per step on examples/dish.toml (10,240
#      particles, 2 frames) without magnets, with a magnet and a non-magnetic fluid, and with a
#      magnet and the magnetic fluid of paper_fig9_approach.toml (magnet 8 cm below: weak).
#   2. Fluid far below the critical magnetization, no spike work and no remeshing: ferro-spikes
#      on frame 0 of paper_fig9_approach.toml (magnet 8 cm below) against the settled frame of
#      surface.sh (magnet 2 cm below, supercritical); input and output meshes compared.
#   3. Frames where nothing moved, no re-meshing: scripts/bench/still-frames.sh (its own area,
#      assembled right after this section).
#   4. `auto` says what it chose: ferro-sim's progress lines for magnetization.solver = "auto"
#      and fluid.viscosity_method = "auto".
# Writes scene_cost.csv (one row per case) and scene-cost.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init scene-cost "$@"
bench_need ferro-sim ferro-surface ferro-spikes ferro-pov bench-compare-mesh

count=10240 preroll=2.0 frames=2
if [[ $quick == 1 ]]; then count=2560 preroll=0.2 frames=1; fi
csv="$out/scene_cost.csv"
echo "case,setting,cpu_seconds,steps_or_triangles,cpu_ms_per_step,holds,reference" > "$csv"

# ---- 1. magnetics ---------------------------------------------------------------------------
magnet_block='
[[magnets]]
kind = "dipole"
position = [0.0, 0.0, -0.08]
direction = [0.0, 0.0, 1.0]
moment = 3.0
softening = 0.002'
cp "$root/examples/dish.toml" "$work/no_magnets.toml"
{ cat "$root/examples/dish.toml"; echo "$magnet_block"; } > "$work/magnet_not_magnetic.toml"
{ cat "$root/examples/dish.toml"; echo "$magnet_block"
  printf '\n[magnetization]\nsusceptibility = 1.5\nsaturation = 35000\nsolver = "auto"\nresolve_every = 10\n'; } > "$work/magnet_magnetic.toml"
declare -A sim_ms sim_log
for case in no_magnets magnet_not_magnetic magnet_magnetic; do
  rm -rf "$work/sim_$case"
  bench_time seconds "$bin/ferro-sim" "$work/$case.toml" --set "fluid.block.0.count=$count" --out "$work/sim_$case" --max-frames "$frames"
  cp "$work/last.log" "$work/sim_$case.log"
  steps="$(sed -n 's/^ferro-sim: done, \([0-9]*\) steps.*/\1/p' "$work/sim_$case.log")"
  sim_ms[$case]="$(calc "1000 * $seconds / $steps")"
  sim_log[$case]="$(grep -m1 '^ferro-sim: [0-9]* particles' "$work/sim_$case.log")"
  holds=""
  if [[ $case == no_magnets ]]; then
    # no magnetics object at all: no magnet summary, no magnetization line on any frame
    if grep -q "magnet\|M solves" "$work/sim_$case.log"; then holds=no; else holds=yes; fi
  fi
  echo "magnetics,${case//_/ },$seconds,$steps,${sim_ms[$case]},$holds,dish.toml $count particles $frames frames" >> "$csv"
done

# ---- 2. subcritical spikes --------------------------------------------------------------------
bench_settled_frame settled "$root/examples/magnet_slide.toml" --set "fluid.block.0.count=$count" --set "shot.preroll=$preroll"
rm -rf "$work/fig9"
"$bin/ferro-sim" "$root/examples/paper_fig9_approach.toml" --set "fluid.block.0.count=$count" --set shot.preroll=0 --out "$work/fig9" --max-frames 0 --quiet
declare -A spike_line spike_cpu
for case in subcritical supercritical disabled; do
  case $case in
    subcritical) frame="$work/fig9/particles_0000.ply" scene="$root/examples/paper_fig9_approach.toml" extra=() ;;
    supercritical) frame="$settled" scene="$root/examples/magnet_slide.toml" extra=(--set "shot.preroll=$preroll") ;;
    disabled) frame="$settled" scene="$root/examples/magnet_slide.toml" extra=(--set "shot.preroll=$preroll" --set spikes.enabled=false) ;;
  esac
  "$bin/ferro-surface" "$frame" --out "$work/surface_$case.ply" --quiet
  bench_best seconds 2 "$bin/ferro-spikes" "$work/surface_$case.ply" --particles "$frame" --scene "$scene" \
    --set "fluid.block.0.count=$count" "${extra[@]}" --out "$work/spiky_$case.ply"
  spike_cpu[$case]="$seconds"
  spike_line[$case]="$(grep -m1 '^ferro-spikes' "$work/last.log" | sed 's/ -> .*//' || true)"
  cmp_line="$("$bin/bench-compare-mesh" "$work/spiky_$case.ply" "$work/surface_$case.ply")"
  tri_in="$(kv triangles_b "$cmp_line")" tri_out="$(kv triangles_a "$cmp_line")" dmax="$(kv max_m "$cmp_line")"
  holds=""
  if [[ $case == subcritical ]]; then
    if [[ $tri_in == "$tri_out" && $(calc "$dmax == 0") == 1 ]]; then holds=yes; else holds=no; fi
  fi
  echo "spikes,$case ($tri_in -> $tri_out triangles; max move $dmax m),$seconds,$tri_out,,$holds,ferro-spikes on one frame ($count particles)" >> "$csv"
done

# ---- 4. auto ------------------------------------------------------------------------------------
mag_frame="$(grep -m1 'M solves' "$work/sim_magnet_magnetic.log" || true)"
chosen="$(sed -n 's/.*M solves [0-9]*\/[0-9]* (\([a-z]*\),.*/\1/p' <<< "$mag_frame")"
if [[ -n $chosen && $chosen != auto ]]; then mag_auto=yes; else mag_auto=no; fi
echo "auto,magnetization.solver auto -> ${chosen:-not printed},,,,$mag_auto,ferro-sim frame line" >> "$csv"
visc_header="${sim_log[no_magnets]}"
if grep -q "viscosity" <<< "$visc_header"; then visc_auto=yes; else visc_auto=no; fi
echo "auto,fluid.viscosity_method auto (explicit chosen for this fluid),,,,$visc_auto,ferro-sim header line" >> "$csv"

r3() { printf '%.3g' "$1"; }

# ---- the Markdown section -------------------------------------------------------------------------
{
  echo "## Model only what a scene requires"
  echo
  echo "What ran: \`scripts/bench/scene-cost.sh\` ($count particles). CPU seconds: user + system, all threads."
  echo
  echo "| case | setting | CPU s | steps / triangles | CPU ms per step | holds |"
  echo "| --- | --- | --- | --- | --- | --- |"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6 }' "$csv"
  echo
  echo "Findings:"
  echo
  echo "- No magnets: $(r3 "${sim_ms[no_magnets]}") CPU ms per step, and no magnetics in the log (\`${sim_log[no_magnets]#ferro-sim: }\`);"
  echo "  a magnet with a non-magnetic fluid $(r3 "${sim_ms[magnet_not_magnetic]}") ms, a magnet with the magnetic fluid"
  echo "  $(r3 "${sim_ms[magnet_magnetic]}") ms per step ($(r3 "$(calc "${sim_ms[magnet_magnetic]} / ${sim_ms[no_magnets]}")")x; the particles' field re-solved every 10th step)."
  echo "- Subcritical fluid: ferro-spikes takes ${spike_cpu[subcritical]} CPU s and returns the surface unchanged"
  echo "  (\`${spike_line[subcritical]}\`); a supercritical frame ${spike_cpu[supercritical]} CPU s; spikes disabled (a copy) ${spike_cpu[disabled]} CPU s."
  echo "- Frames where nothing moved: the next subsection (\`scripts/bench/still-frames.sh\`)."
  echo "- \`auto\`: magnetization.solver prints its choice on every frame line ($(sed 's/.*M solves/M solves/; s/ ETA.*//' <<< "$mag_frame"));"
  echo "  fluid.viscosity_method $([[ $visc_auto == yes ]] && echo "names the method in the header line" || echo "says only when it chose implicit (the header line names nothing when it chose explicit)")."
} > "$out/scene-cost.md"
bench_note "wrote $out/scene-cost.md, scene_cost.csv"
