#!/usr/bin/env bash
# bench.sh: the speed/accuracy report: every stage's knobs measured against converged
# reference runs of the same scene, a peer comparison, and the presets chosen from them.
#
#   scripts/bench.sh [OUT_DIR] [--only AREA[,AREA...]] [--no-build]
#
# OUT_DIR (default tests/bench/report, committed) receives per knob a CSV and a PNG plot, per
# area a Markdown section, and README.md: the sections under a short intro, the guide and the
# presets table (scripts/presets.conf). Reference runs are cached in OUT_DIR/cache (not
# committed) and reused while their inputs are unchanged.
#   --only AREAS   run only these areas (the other sections already in OUT_DIR are kept)
#   --no-build     skip scripts/build.sh (use FERRO_BIN or build/bin as they are)
#   --assemble     run no area: only rewrite OUT_DIR/README.md from the sections in OUT_DIR
# Areas, in order: sim magnetics surface spikes render scene-cost peer (scripts/bench/<area>.sh;
# peer needs FERRO_PEER_SRC=/path/to/SPlisHSPlasH and otherwise prints why it is skipped).
# Environment: BENCH_QUICK=1 (tiny sizes: checks the scripts in minutes, not for the report),
# FERRO_BIN, FERRO_PEER_SRC. Needs gnuplot (scripts/install-deps.sh --with-bench).
# Exit codes: 2 bad arguments, 3 an area failed (the others still run), 4 a missing tool.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
die() { echo "bench.sh: error: $2" >&2; exit "$1"; }
all_areas=(sim magnetics surface spikes render scene-cost peer)

out="" only="" build=1 assemble=0
while [[ $# -gt 0 ]]; do
  case "$1" in
    --only) only="${2:?--only needs AREA[,AREA...]}"; shift 2 ;;
    --no-build) build=0; shift ;;
    --assemble) build=0; assemble=1; shift ;;
    -h|--help) sed -n '2,22s/^# \{0,1\}//p' "$0"; exit 0 ;;
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
  echo "bench.sh: building (scripts/build.sh)" >&2
  "$root/scripts/build.sh" > "$out/cache/build.log" 2>&1 || { tail -n 20 "$out/cache/build.log" >&2; die 3 "the build failed"; }
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
presets="$root/scripts/presets.conf"
{
  cat <<'INTRO'
# Speed against accuracy: the measured trade, per knob

Made by `scripts/bench.sh` (this directory is its default output; `BENCH_QUICK=1` runs tiny
sizes to check the scripts and is not how this report was made). Every error below is
measured against a converged reference run of the same scene (the finest setting of that
knob, named in each CSV's `reference` column), never against a guess. Costs are CPU seconds
or ratios: the machine is shared, so wall times would measure the neighbours too. Each area
is `scripts/bench/<area>.sh OUT_DIR`; each knob has a CSV (one row per setting) and a plot
of cost (log scale) against error (`scripts/bench/plot.sh`).

## The guide: which settings for what

- **Preview** (checking motion, framing, timing): `scripts/shot.sh SCENE OUT --preset preview`.
  The render dominates a frame's cost; a small image without anti-aliasing and coarser
  spikes cut it most. Errors in the sections below say what a preview frame misses.
- **Final frames**: `--preset final` (the defaults of every stage, which the report
  supports: each sits where the error curve flattens).
- **A very large shot** (many frames or particles): `--preset large`: the final look with
  the cheaper settings whose error the report shows to be invisible at frame size.

Any preset key can still be overridden: `scripts/shot.sh SCENE OUT --preset preview --set render.width=480`.

## Presets
INTRO
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
  echo "Run on $(date -u +%Y-%m-%d) at commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown), $(nproc) cores (shared)."
} > "$out/README.md.tmp"
mv -f "$out/README.md.tmp" "$out/README.md"
echo "bench.sh: report in $out/README.md ($((SECONDS - start)) s)" >&2
[[ ${#failed[@]} == 0 ]] || die 3 "areas failed: ${failed[*]}"
