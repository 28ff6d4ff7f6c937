#!/usr/bin/env bash
# still-frames.sh: "frames where nothing moved, no re-meshing", measured (issue 16; part of the
# report's "model only what a scene requires", beside scene-cost.sh).
#
#   scripts/bench/still-frames.sh [OUT_DIR]   (default tests/bench/report; BENCH_QUICK=1: tiny)
#
# A shot directory made by scripts/shot.sh (scripts/shot.mk) on the heap pool
# (scripts/bench/heap_pool.toml, COUNT particles, 10 fps, 0.4 s: frames 0-4, surface and spikes
# per frame) is made once, then re-simulated three ways; after each re-simulation make builds
# the same surface and spike targets, and shot.mk's line `frames unchanged: K of N` and the
# recipes make ran say what was kept:
#   rerun     the simulation forced again with nothing changed (its scene stamp touched);
#   longer    [shot] duration 0.4 -> 0.6 s (frames 5 and 6 are new);
#   sim edit  [sim] max_dt 1e-3 -> 5e-4 s (the motion changes from the first step on).
# Costs are CPU seconds (user + system, all threads) of the simulation and of the meshing make
# separately; "saved" is the mesh targets make skipped times the mean CPU seconds of a mesh
# target in the first make (an estimate from that measurement, not a second timing).
# Writes still_frames.csv and still-frames.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init still-frames "$@"
bench_need ferro-sim ferro-surface ferro-spikes ferro-pov

count=2560
[[ $quick == 1 ]] && count=640
scene="$work/pool.toml"
sed -e "s/^count = .*/count = $count/" -e 's/^fps = .*/fps = 10/' -e 's/^duration = .*/duration = 0.4/' \
  "$root/scripts/bench/heap_pool.toml" > "$scene"
shot="$work/shot"
FERRO_BIN="$bin" "$root/scripts/shot.sh" "$scene" "$shot" --no-run > /dev/null 2>&1 ||
  bench_die 3 "shot.sh --no-run failed"
grep -q '^SPIKES := 1' "$shot/Makefile" || bench_die 3 "shot.sh did not turn ferro-spikes on for the heap pool"

csv="$out/still_frames.csv"
echo "case,frames,frames_unchanged,mesh_targets_run,mesh_targets_skipped,sim_cpu_s,mesh_cpu_s,mesh_cpu_saved_s,holds" > "$csv"
mean_target=""
# step NAME LAST_FRAME EXPECTED_UNCHANGED: simulate (make particles/.complete), then make the
# surface and spike targets of frames 0..LAST; one CSV row. EXPECTED_UNCHANGED: the frames
# that must be kept ("-": the first make, nothing to keep).
step() {
  local name="$1" last="$2" expect="$3" targets=() f
  for ((f = 0; f <= last; f++)); do targets+=("$(printf 'spiky/spiky_%04d.ply' "$f")"); done
  bench_time sim_s nice -n 5 make -C "$shot" --no-print-directory particles/.complete
  local kept
  kept="$(sed -n 's/.*frames unchanged: \([0-9]*\) of .*/\1/p' "$work/last.log" | tail -n1)"
  bench_time mesh_s nice -n 5 make -C "$shot" --no-print-directory "${targets[@]}"
  local ran all=$((2 * (last + 1)))
  ran=$(( $(grep -c 'ferro-surface particles/' "$work/last.log" || true) + $(grep -c 'ferro-spikes surface/' "$work/last.log" || true) ))
  [[ -n $mean_target ]] || mean_target="$(calc "$mesh_s / $ran")"
  local skipped=$((all - ran)) holds
  # Holds: make kept exactly the unchanged frames (2 targets each) and made the rest.
  if [[ $expect == - ]]; then holds=$([[ $ran == "$all" ]] && echo yes || echo no)
  else holds=$([[ $kept == "$expect" && $skipped == $((2 * expect)) ]] && echo yes || echo no); fi
  make -C "$shot" --no-print-directory -q "${targets[@]}" || holds=no
  echo "$name,$((last + 1)),${kept:-0},$ran,$skipped,$sim_s,$mesh_s,$(printf "%.3g" "$(calc "$skipped * $mean_target")"),$holds" >> "$csv"
  bench_note "$name: frames unchanged ${kept:-0} of $((last + 1)), mesh targets run $ran of $all, sim $sim_s s, meshing $mesh_s s"
}

step "first make" 4 -
sleep 1; touch "$shot/.scene/sim.toml"
step "rerun (nothing changed)" 4 5
sleep 1; sed -i 's/^duration = .*/duration = 0.6/' "$scene"
step "longer shot (0.4 -> 0.6 s)" 6 5
sleep 1; sed -i '/^\[sim\]$/a max_dt = 0.0005' "$scene"
step "[sim] max_dt 1e-3 -> 5e-4" 6 1

r3() { printf '%.3g' "$1"; }
g() { awk -F, -v c="$1" -v k="$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == k) j = i; next } $1 == c { print $j }' "$csv"; }
{
  echo "### Frames where nothing moved, no re-meshing (\`still_frames.csv\`)"
  echo
  echo "What ran: \`scripts/bench/still-frames.sh\`: a shot of the heap pool ($count particles, 10 fps, frames"
  echo "0-4, surface and spikes per frame) made with \`scripts/shot.sh\`, then simulated again three"
  echo "ways; after each run make builds the same surface and spike targets. After a"
  echo "re-simulation, \`scripts/shot.mk\` keeps the time of every frame file that holds the same frame"
  echo "as before (\`scripts/frame-unchanged.sh\`: every particle value and header line bit for bit,"
  echo "except the scene's name and hash), so make keeps that frame's meshes. CPU seconds; \"saved\" is"
  echo "the skipped targets times the mean mesh target of the first make ($(r3 "$mean_target") s)."
  echo
  echo "| case | frames | unchanged | mesh targets run | skipped | sim CPU s | meshing CPU s | meshing saved (CPU s) | holds |"
  echo "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9 }' "$csv"
  echo
  echo "- A re-simulation with nothing changed keeps all $(g "rerun (nothing changed)" frames_unchanged) frames: $(g "rerun (nothing changed)" mesh_targets_run) mesh targets"
  echo "  run, $(g "rerun (nothing changed)" mesh_targets_skipped) skipped (about $(r3 "$(g "rerun (nothing changed)" mesh_cpu_saved_s)") CPU s of meshing saved; the simulation itself is redone)."
  echo "- A longer shot keeps the $(g "longer shot (0.4 -> 0.6 s)" frames_unchanged) frames it had and meshes only the new ones"
  echo "  ($(g "longer shot (0.4 -> 0.6 s)" mesh_targets_run) targets run, $(g "longer shot (0.4 -> 0.6 s)" mesh_targets_skipped) skipped): ferro-sim is deterministic, so the same steps give"
  echo "  the same bytes."
  echo "- An edit that changes the motion re-meshes every frame after the fill: $(g "[sim] max_dt 1e-3 -> 5e-4" frames_unchanged) of"
  echo "  $(g "[sim] max_dt 1e-3 -> 5e-4" frames) kept (frame 0, the initial fill, which a solver setting does not move)."
  echo "- Not done: frames N and N-1 of one run are never the same in SPH (a settled pool keeps"
  echo "  moving at 0.6-2 mm/s RMS, the sim section's rms_speed_mm_s), so reusing frame N-1's"
  echo "  meshes would need a tolerance on how far particles may move; make here keeps only"
  echo "  frames that are exactly the same as the previous run's."
} > "$out/still-frames.md"
bench_note "wrote $out/still-frames.md, still_frames.csv"
