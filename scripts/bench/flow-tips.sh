#!/usr/bin/env bash
# flow-tips.sh: do the spikes ride the fluid under them? (issue 32, `spikes.response_time`)
#
#   scripts/bench/flow-tips.sh [OUT_DIR]   (default tests/bench/report; BENCH_QUICK=1: 2,560
#                                           particles, response times 0 and 0.5 s only)
#
# Two shots at COUNT particles (10,240), simulated and meshed once (cached in
# $cache/flow-tips/<scene>-<hash of the scene text and count>):
#   slosh  scripts/bench/flow_slosh.toml: a strong magnet heaps the layer into spikes, then is
#          pulled away in 0.1 s at 1.5 s; measured over frames 45-60 while the heap collapses
#          and sloshes and the spikes sink (growth_time 0.2 s);
#   slide  scripts/bench/flow_slide.toml: the magnet slides 5 cm in 0.5 s (10 cm/s) from 1 s;
#          measured over frames 30-48.
# Each is spiked at every response time (0 = the paper: laid out anew from the field) and
# tracked by ferro-tips, which compares each matched interior tip's move over a frame with the
# surface velocity under it (along the surface): mismatch = sum |v - u| / sum |u| over all
# the steps' tips. Costs are ferro-spikes' CPU seconds a frame (user + system).
# Writes flow_tips.csv and flow-tips.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init flow-tips "$@"
bench_need ferro-sim ferro-surface ferro-spikes ferro-tips

count=10240 taus="0 0.1 0.25 0.5 1 2"
[[ $quick == 1 ]] && count=2560 taus="0 0.5"

# shot NAME FIRST LAST: simulated and meshed frames 0..LAST of flow_NAME.toml at $count
# particles in $dir (cached).
shot() {
  local scene="$root/scripts/bench/flow_$1.toml" key
  key="$( (cat "$scene"; echo "$count") | sha1sum | cut -c1-16)"
  dir="$cache/flow-tips/$1-$key"
  if [[ ! -f "$dir/done" ]]; then
    bench_note "simulating and meshing $1 at $count particles (cached in $dir)"
    rm -rf "$dir"; mkdir -p "$dir/surface"
    sed "s/^count = .*/count = $count/" "$scene" > "$dir/scene.toml"
    nice -n 5 "$bin/ferro-sim" "$dir/scene.toml" --out "$dir/particles" --max-frames "$3" --quiet
    nice -n 5 "$bin/ferro-surface" "$dir/particles/particles_{:04}.ply" --frames "$2:$3" \
      --out "$dir/surface/surface_{:04}.ply" --scene "$dir/scene.toml" --quiet
    touch "$dir/done"
  fi
}

{
  echo "shot,response_time_s,frames,tip_moves,surface_speed_mm_s,tip_speed_mm_s,mismatch,interior_births_deaths,spikes_cpu_s_per_frame"
  for case in "slosh 45 60" "slide 30 48"; do
    read -r name first last <<< "$case"
    shot "$name" "$first" "$last"
    for tau in $taus; do
      spiky="$work/$name-$tau"
      mkdir -p "$spiky"
      bench_time seconds "$bin/ferro-spikes" "$dir/surface/surface_{:04}.ply" \
        --particles "$dir/particles/particles_{:04}.ply" --frames "$first:$last" --scene "$dir/scene.toml" \
        --set "spikes.response_time=$tau" --out "$spiky/spiky_{:04}.ply" --quiet
      "$bin/ferro-tips" "$spiky/spiky_{:04}.ply" --surface "$dir/surface/surface_{:04}.ply" \
        --frames "$first:$last" > "$work/tips.csv" 2> /dev/null
      # Sums over the steps, weighted by the tips each compared (ferro-tips' own summary).
      awk -F, -v name="$name" -v tau="$tau" -v frames="$first-$last" -v cpu="$seconds" -v n="$((last - first + 1))" '
        NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
        { k = $c["flow_tips"]; tips += k; su += k * $c["surface_speed_mm_s"]; sv += k * $c["tip_speed_mm_s"]
          sd += k * $c["flow_difference_mm_s"]; bd += $c["interior_born"] + $c["interior_died"] }
        END { ms = tips ? su / tips : 0; mv = tips ? sv / tips : 0; mm = su > 0 ? sd / su : 0
              printf "%s,%s,%s,%d,%.3g,%.3g,%.3f,%d,%.3g\n", name, tau, frames, tips, ms, mv, mm, bd, cpu / n }' "$work/tips.csv"
    done
  done
} > "$out/flow_tips.csv"

{
  echo "## Spikes carried by the flow: \`spikes.response_time\`"
  echo
  echo "What ran: \`scripts/bench/flow-tips.sh\` ($count particles; scenes scripts/bench/flow_slosh.toml, a magnet"
  echo "pulled 1.5 cm down in 0.1 s so the heap collapses and sloshes, and flow_slide.toml, a magnet sliding"
  echo "10 cm/s). Per shot and response time: the matched interior tip moves ferro-tips compared with the"
  echo "surface velocity under them (along the surface), their mean speeds, and"
  echo "mismatch = sum |v − u| / sum |u| (0: the tips ride the flow; 1: they stand still on a moving"
  echo "surface, or move as fast again). Response time 0 is the paper: tips laid out anew from the field."
  echo
  table "$out/flow_tips.csv" | sed 's/ | $/ |/'
  echo
  echo "ferro-spikes CPU seconds a frame: $(awk -F, 'NR > 1 { printf "%s%s %s: %s s", sep, $1, $2, $9; sep = "; " }' "$out/flow_tips.csv")."
  echo
  echo "Neither shot reaches a mismatch of 0.2: the lattice's own motion (traced along a heap that flattens,"
  echo "along field lines that move with the magnet) still moves the tips, and the carry adds interior births"
  echo "and deaths. Recommended: 0 (default) for the paper's look; 1-2 s for a fast magnet whose spikes should"
  echo "lag behind it (docs/physics/spikes.md, \"Carried by the flow\")."
} > "$out/flow-tips.md"
bench_note "wrote $out/flow_tips.csv and $out/flow-tips.md"
