#!/usr/bin/env bash
# bench.sh: the speed/accuracy report: every stage's knobs measured against converged
# reference runs of the same scene, a peer comparison, and the presets chosen from them.
#
#   scripts/bench.sh [OUT_DIR] [--only AREA[,AREA...]] [--no-build] [--assemble]
#
# OUT_DIR (default tests/bench/report, committed) receives per knob a CSV and a PNG plot, per
# area a Markdown section, and README.md: the sections under a short intro, the guide and the
# presets table (scripts/presets.conf). Reference runs are cached in OUT_DIR/cache (not
# committed) and reused while their inputs are unchanged.
#   --only AREAS   run only these areas (the other sections already in OUT_DIR are kept)
#   --no-build     skip scripts/build.sh (use FERRO_BIN or build/bin as they are)
#   --assemble     run no area: only rewrite OUT_DIR/README.md from the sections in OUT_DIR
# Areas, in order: sim scaling magnetics surface spikes flow-tips periodic-layer field-sweep render scene-cost still-frames peer million
# slurm (scripts/bench/<area>.sh; million takes ~30 min, slurm needs --with-slurm;
# peer needs FERRO_PEER_SRC=/path/to/SPlisHSPlasH and otherwise prints why it is skipped).
# Environment: BENCH_QUICK=1 (tiny sizes: checks the scripts in minutes, not for the report),
# FERRO_BIN, FERRO_PEER_SRC. Needs gnuplot (scripts/install-deps.sh --with-bench).
# Exit codes: 2 bad arguments, 3 an area failed (the others still run), 4 a missing tool.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
die() { echo "bench.sh: error: $2" >&2; exit "$1"; }
all_areas=(sim scaling magnetics surface spikes flow-tips periodic-layer field-sweep render scene-cost still-frames peer million slurm)

out="" only="" build=1 assemble=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --only) only="${2:?--only needs AREA[,AREA...]}"; shift 2 ;;
    --no-build) build=0; shift ;;
    --assemble) build=0; assemble=1; shift ;;
    -h|--help) sed -n '2,23s/^# \{0,1\}//p' "$0"; exit 0 ;;
    -*) die 2 "unknown option $1 (see --help)" ;;
    *) [[ -z "$out" ]] || die 2 "unexpected argument $1"; out="$1"; shift ;;
  esac
done
out="${out:-$root/tests/bench/report}"
areas=("${all_areas[@]}")
if [[ $assemble == 1 ]]; then
  areas=()
elif [[ -n "$only" ]]; then
  IFS=, read -r -a areas <<< "$only"
  for a in "${areas[@]}"; do
    [[ " ${all_areas[*]} " == *" $a "* ]] || die 2 "--only: no area '$a' (areas: ${all_areas[*]})"
  done
fi
[[ $assemble == 1 ]] || command -v gnuplot > /dev/null || die 4 "gnuplot is not installed (scripts/install-deps.sh --with-bench)"
mkdir -p "$out/cache" || die 4 "$out: cannot create the output directory"
out="$(cd "$out" && pwd)"

if [[ $build == 1 ]]; then
  echo "bench.sh: building (scripts/build.sh --with-benchmarks)" >&2
  "$root/scripts/build.sh" --with-benchmarks > "$out/cache/build.log" 2>&1 || { tail -n 20 "$out/cache/build.log" >&2; die 3 "the build failed"; }
fi

start=$SECONDS failed=()
declare -A took
for a in "${areas[@]+"${areas[@]}"}"; do
  script="$root/scripts/bench/$a.sh"
  if [[ ! -x "$script" ]]; then
    echo "bench.sh: $a: scripts/bench/$a.sh is not there: skipped" >&2
    continue
  fi
  t0=$SECONDS
  echo "bench.sh: $a ..." >&2
  if ! "$script" "$out"; then failed+=("$a"); echo "bench.sh: $a FAILED (its section is left as it was)" >&2; fi
  took[$a]=$((SECONDS - t0))
  echo "bench.sh: $a: ${took[$a]} s" >&2
done

# ---- OUT_DIR/README.md ----
# val CSV SETTING COLUMN: one cell of an area's CSV (empty when the area did not run).
val() {
  [[ -f "$out/$1" ]] || return 0
  awk -F, -v s="$2" -v c="$3" 'NR == 1 { for (i = 1; i <= NF; ++i) if ($i == c) k = i; next } $1 == s && k { print $k }' "$out/$1"
}
num() { awk -v x="$1" 'BEGIN { if (x == "") print "?"; else printf "%.2g", x }'; }
mm() { awk -v x="$1" 'BEGIN { if (x == "") print "?"; else printf "%.2g mm", 1000 * x }'; }
# The guide, with the figures of this run's CSVs (CPU seconds per frame of the report's frame).
guide() {
  local aa_def aa_off aa_r2 rm_def rm_off rm_r2 sp_final sp_prev sp_large tp_final tp_prev tp_large sf
  aa_def="$(val render_antialias.csv +A0.3+R3 cpu_seconds)" rm_def="$(val render_antialias.csv +A0.3+R3 rmse)"
  aa_off="$(val render_antialias.csv -A cpu_seconds)" rm_off="$(val render_antialias.csv -A rmse)"
  aa_r2="$(val render_antialias.csv +A0.3+R2 cpu_seconds)" rm_r2="$(val render_antialias.csv +A0.3+R2 rmse)"
  sp_final="$(val spikes_presets.csv "final (16 / 3)" cpu_seconds)" tp_final="$(val spikes_presets.csv "final (16 / 3)" tip_mean_distance_m)"
  sp_prev="$(val spikes_presets.csv "preview (8 / 1)" cpu_seconds)" tp_prev="$(val spikes_presets.csv "preview (8 / 1)" tip_mean_distance_m)"
  sp_large="$(val spikes_presets.csv "large (12 / 1)" cpu_seconds)" tp_large="$(val spikes_presets.csv "large (12 / 1)" tip_mean_distance_m)"
  sf="$(val surface_voxel.csv "0.5 spacing" cpu_seconds)"
  local x16 x4
  x16="$(awk -v a="$aa_def" 'BEGIN { if (a == "") print ""; else print 16 * a }')"
  x4="$(awk -v a="$aa_off" 'BEGIN { if (a == "") print ""; else print 4 * a }')"
  cat <<GUIDE
## The guide: which settings for what

Where a frame's time goes, at the report's frame (10,240 particles; CPU seconds): the surface
$(num "$sf") s, the spikes $(num "$sp_final") s at the defaults, the render about $(num "$x16") s at 640x480 with the
defaults ($(num "$aa_def") s measured at 160x120, times 16 pixels). The render dominates; the simulation's
cost per frame is in the sim section: the particle spacing sets the heap's accuracy, the
pressure solver's tolerance mostly how still a resting pool stands (preview relaxes it).

- **Preview** (motion, framing, timing): \`scripts/shot.sh SCENE OUT --preset preview\`. 320x240,
  +Q8, no anti-aliasing: about $(num "$x4") CPU s a frame ($(num "$aa_off") s at 160x120, times 4), image RMSE
  $(num "$rm_off") against the reference instead of $(num "$rm_def") (jagged edges, same reflections: +Q8 renders
  this look exactly as +Q9 does, +Q5 loses the reflections); spikes at resolution 8 with one
  remeshing round, $(num "$sp_prev") s, tips $(mm "$tp_prev") from the finest mesh.
- **Final frames**: \`--preset final\`, the stages' defaults: 640x480, +Q9 +A0.3 +R3, spikes 16 / 3
  rounds (tips $(mm "$tp_final") from the finest), surface anisotropic at spacing/2.
- **A very large shot** (many frames or particles): \`--preset large\`: the final image with
  anti-aliasing depth 2 ($(num "$aa_r2") s instead of $(num "$aa_def") s at 160x120, RMSE $(num "$rm_r2") instead of
  $(num "$rm_def")) and spikes at resolution 12 with one round ($(num "$sp_large") s instead of $(num "$sp_final") s, tips
  $(mm "$tp_large") from the finest: a tenth of a pixel at 640x480).

Any key can still be overridden: \`scripts/shot.sh SCENE OUT --preset preview --set render.width=480\`.

GUIDE
}
presets="$root/scripts/presets.conf"
{
  cat <<'INTRO'
# Speed against accuracy: the measured trade, per knob

Made by `scripts/bench.sh` (this directory is its default output; `BENCH_QUICK=1` runs tiny
sizes to check the scripts and is not how this report was made). Every error below is
measured against a converged reference run of the same scene (the finest setting of that
knob, named in each CSV's `reference` column), never against a guess. Costs are CPU seconds
or ratios: the machine is shared, so wall times would measure the neighbours too. Even CPU
seconds vary by up to about 25 % between two runs of one setting here (the same setting
appears in two tables of a section now and then: compare them), so read ratios between
settings an order of magnitude apart, not the second digit. Each area
is `scripts/bench/<area>.sh OUT_DIR`; each knob has a CSV (one row per setting) and a plot
of cost (log scale) against error (`scripts/bench/plot.sh`).

INTRO

  guide
  echo "## Presets"
  echo
  if [[ -f "$presets" ]]; then
    echo "From \`scripts/presets.conf\` (what \`scripts/shot.sh --preset NAME\` passes to the stages as"
    echo "\`--set key=value\`; a key a preset does not name keeps the scene's value):"
    echo
    awk '/^[a-z]/ { split($2, kv, "="); v[$1, kv[1]] = kv[2]; if (!(kv[1] in seen)) { seen[kv[1]] = 1; keys[++n] = kv[1] }; names[$1] = 1 }
         /^# *PLACEHOLDER/ { ph[++m] = $0 }
         END {
           printf "| key | preview | final | large |\n| --- | --- | --- | --- |\n"
           for (i = 1; i <= n; ++i) {
             k = keys[i]
             printf "| `%s` | %s | %s | %s |\n", k, ((("preview", k) in v) ? v["preview", k] : "scene"), \
                    ((("final", k) in v) ? v["final", k] : "scene"), ((("large", k) in v) ? v["large", k] : "scene")
           }
           if (m) { print ""; print "Still to be filled in from the sim and magnetics sections:"; print "" }
           for (i = 1; i <= m; ++i) { s = ph[i]; sub(/^# */, "", s); print "- " s }
         }' "$presets"
  else
    echo "(scripts/presets.conf is missing)"
  fi
  echo
  for a in "${all_areas[@]}"; do
    if [[ -f "$out/$a.md" ]]; then cat "$out/$a.md"; echo
    else echo "## ${a^}"; echo; echo "Not measured in this run (scripts/bench/$a.sh missing, skipped or failed)."; echo; fi
  done
  echo "---"
  if [[ $assemble == 1 ]]; then
    # Only the page was rewritten: each section is from its area's last run (the sections
    # that name a commit say which), not from this commit.
    echo "Assembled on $(date -u +%Y-%m-%d) at commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown) from the sections in this directory, each from its area's last run; $(nproc) cores (shared)."
  else
    echo "Run on $(date -u +%Y-%m-%d) at commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores (shared)."
  fi
} > "$out/README.md.tmp"
mv -f "$out/README.md.tmp" "$out/README.md"
echo "bench.sh: report in $out/README.md ($((SECONDS - start)) s)" >&2
[[ ${#failed[@]} == 0 ]] || die 3 "areas failed: ${failed[*]}"
