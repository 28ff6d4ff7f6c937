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
# surface velocity under it (along the surface; a tip's move is its foot's, where its axis
# meets the surface): mismatch = sum |v - u| / sum |u| over all the steps' tips. Costs are
# ferro-spikes' CPU seconds a frame (user + system). The slide's own heap, with no spikes, is
# measured too (scripts/bench/heap_motion.py): how fast it travels against the fluid under it.
# Writes flow_tips.csv (per shot and response time), flow_tips_steps.csv (per frame step),
# heap_motion.csv and flow-tips.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init flow-tips "$@"
bench_need ferro-sim ferro-surface ferro-spikes ferro-tips

count=10240 taus="0 0.1 0.25 0.5 1 2"
[[ $quick == 1 ]] && count=2560 taus="0 0.5"

# shot SCENE FPS FIRST LAST: simulated and meshed frames 0..LAST of flow_SCENE.toml at $count
# particles and FPS frames a second (the scene's own 30, or more) in $dir (cached).
shot() {
  local scene="$root/scripts/bench/flow_$1.toml" text key
  text="$(sed "s/^fps = 30$/fps = $2/" "$scene")"
  key="$( (echo "$text"; echo "$count") | sha1sum | cut -c1-16)"
  dir="$cache/flow-tips/$1-$key"
  set -- "$1" "$3" "$4"
  # A cache made by a run that simulated fewer frames is not enough.
  if [[ ! -f "$dir/done" || ! -f "$dir/particles/particles_$(printf %04d "$3").ply" ]]; then
    bench_note "simulating and meshing $1 at $count particles (cached in $dir)"
    rm -rf "$dir"; mkdir -p "$dir/surface"
    echo "$text" | sed "s/^count = .*/count = $count/" > "$dir/scene.toml"
    nice -n 5 "$bin/ferro-sim" "$dir/scene.toml" --out "$dir/particles" --max-frames "$3" --quiet
    nice -n 5 "$bin/ferro-surface" "$dir/particles/particles_{:04}.ply" --frames "$2:$3" \
      --out "$dir/surface/surface_{:04}.ply" --scene "$dir/scene.toml" --quiet
    touch "$dir/done"
  fi
}

echo "shot,response_time_s,frame,flow_tips,surface_speed_mm_s,tip_speed_mm_s,flow_mismatch" > "$out/flow_tips_steps.csv"
{
  echo "shot,response_time_s,frames,tip_moves,surface_speed_mm_s,tip_speed_mm_s,mismatch,interior_births_deaths,spikes_cpu_s_per_frame"
  # The slide again at 120 fps: the magnet moves 0.2 of a tip spacing a frame there, so
  # ferro-tips follows the pattern itself (at 30 fps it moves 0.8 and is matched backwards).
  fast_taus="0 1 2"
  [[ $quick == 1 ]] && fast_taus="0"
  for case in "slosh slosh 30 45 60" "slide slide 30 30 48" "slide-120fps slide 120 120 180"; do
    read -r name scene fps first last <<< "$case"
    shot "$scene" "$fps" "$first" "$last"
    cases="$taus"
    [[ $fps != 30 ]] && cases="$fast_taus"
    for tau in $cases; do
      spiky="$work/$name-$tau"
      mkdir -p "$spiky"
      bench_time seconds "$bin/ferro-spikes" "$dir/surface/surface_{:04}.ply" \
        --particles "$dir/particles/particles_{:04}.ply" --frames "$first:$last" --scene "$dir/scene.toml" \
        --set "spikes.response_time=$tau" --out "$spiky/spiky_{:04}.ply" --quiet
      "$bin/ferro-tips" "$spiky/spiky_{:04}.ply" --surface "$dir/surface/surface_{:04}.ply" \
        --frames "$first:$last" > "$work/tips.csv" 2> /dev/null
      awk -F, -v name="$name" -v tau="$tau" 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
        $c["flow_tips"] > 0 { printf "%s,%s,%s,%s,%s,%s,%s\n", name, tau, $c["frame"], $c["flow_tips"],
          $c["surface_speed_mm_s"], $c["tip_speed_mm_s"], $c["flow_mismatch"] }' "$work/tips.csv" >> "$out/flow_tips_steps.csv"
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

# The slide's own heap, no spikes: its apex against the fluid under it while the magnet moves
# (1.0-1.5 s: frames 120-180 of the 120 fps shot, the dir of the last shot() call).
python3 "$root/scripts/bench/heap_motion.py" "$dir/particles" 116 180 --moving 120:180 > "$out/heap_motion.csv"
heap="$(tail -1 "$out/heap_motion.csv" | tr -d '# ')"
IFS=, read -r heap_travel heap_speed heap_fluid heap_ratio <<< "$heap"

{
  echo "## Spikes carried by the flow: \`spikes.response_time\`"
  echo
  echo "What ran: \`scripts/bench/flow-tips.sh\` ($count particles; scenes scripts/bench/flow_slosh.toml, a magnet"
  echo "pulled 1.5 cm down in 0.1 s so the heap collapses and sloshes, and flow_slide.toml, a magnet sliding"
  echo "10 cm/s). Per shot and response time: the matched interior tip moves ferro-tips compared with the"
  echo "surface velocity under them (along the surface; a tip's move is its foot's), their mean speeds, and"
  echo "mismatch = sum |v − u| / sum |u| (0: the tips ride the flow; 1: they stand still on a moving"
  echo "surface, or move as fast again). Response time 0 is the paper: tips laid out anew from the field."
  echo
  table "$out/flow_tips.csv" | sed 's/ | $/ |/'
  echo
  echo "ferro-spikes CPU seconds a frame: $(awk -F, 'NR > 1 { printf "%s%s %s: %s s", sep, $1, $2, $9; sep = "; " }' "$out/flow_tips.csv")."
  echo
  echo "Per frame step, slosh (the magnet moves over frames 45-48; the steps' own mismatch):"
  echo
  awk -F, -v taus="$taus" 'NR > 1 && $1 == "slosh" { v[$2, $3] = $7; if (!($3 in seen)) { seen[$3] = 1; f[++n] = $3 } }
    END { line = "| response_time"; rule = "| ---"
          for (k = 1; k <= n; ++k) { line = line " | " f[k]; rule = rule " | ---" }
          print line " |"; print rule " |"
          m = split(taus, t, " ")
          for (i = 1; i <= m; ++i) { line = "| " t[i]
            for (k = 1; k <= n; ++k) line = line " | " ((t[i], f[k]) in v ? sprintf("%.2f", v[t[i], f[k]]) : "")
            print line " |" } }' "$out/flow_tips_steps.csv"
  echo
  echo "The slide's own heap, no spikes (\`scripts/bench/heap_motion.py\` on the 120 fps shot, 1.0-1.5 s): its"
  echo "apex travels ${heap_travel} mm at ${heap_speed} mm/s while the fluid under it moves ${heap_fluid} mm/s along that way:"
  echo "${heap_ratio} times faster. A spike the field holds on that heap moves with the heap, not with the fluid:"
  echo "against the fluid's velocity its mismatch is ${heap_ratio} - 1, however it is made. Compare the 120 fps rows'"
  echo "tip speed with the heap's ${heap_speed} mm/s. At 30 fps the magnet moves 0.8 of a tip spacing a frame: a lattice"
  echo "moving that fast is matched to the neighbour behind (the wagon wheel), so the 30 fps slide's tip"
  echo "speeds are not the pattern's."
  echo
  echo "Recommended: 0 (default) for the paper's look; 0.25-1 s where spikes should drift on a slosh after"
  echo "their magnet is gone; 1-2 s for a fast magnet whose spikes should lag behind it"
  echo "(docs/physics/spikes.md, \"Carried by the flow\")."
} > "$out/flow-tips.md"
bench_note "wrote $out/flow_tips.csv and $out/flow-tips.md"
