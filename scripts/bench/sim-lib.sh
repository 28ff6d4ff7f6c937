# Shared by scripts/bench/sim.sh and scripts/bench/magnetics.sh (sourced, not run): cached
# ferro-sim runs of the heap pool (scripts/bench/heap_pool.toml) and their cost.
#
# A run is named; its directory OUT_DIR/cache/sim/NAME holds the particle files, `key` (the
# hash of its inputs: the scene file, the --set overrides, the settle time and ferro-sim's
# sources under sim/) and `cost` (wall_s cpu_s steps). A run whose key is unchanged is not
# run again, so the references (the expensive finest runs) are simulated once.
#
# Runs go BENCH_JOBS (default 2) at a time, each on one thread (--threads 1): the CPU time of
# a one-thread run is its cost on an idle core, whatever else the machine is doing; wall
# time is kept too but depends on the load.

bench_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
bench_bin="${FERRO_BIN:-$bench_root/build/bin}"
bench_scene="$bench_root/scripts/bench/heap_pool.toml"
bench_jobs="${BENCH_JOBS:-2}"

# sim_build_default EXE: with the default build/bin (no FERRO_BIN), (re)builds EXE: the
# benchmarks are not in the default build, and an old one would measure old code.
sim_build_default() {
    [[ -z "${FERRO_BIN:-}" && -f "$bench_root/build/CMakeCache.txt" ]] || return 0
    cmake --build "$bench_root/build" --target "$1" > /dev/null 2>&1
}

# The hash of ferro-sim's sources (committed state plus uncommitted edits), or of the binary.
sim_sources_hash() {
    if git -C "$bench_root" rev-parse --git-dir >/dev/null 2>&1; then
        (cd "$bench_root" && git ls-files -s sim && git diff HEAD -- sim) | sha1sum | cut -c1-16
    else
        sha1sum "$bench_bin/ferro-sim" | cut -c1-16
    fi
}

# The key of a run: the scene without its comments, the settle time, the overrides, the sources.
sim_run_key() {
    (sed 's/#.*//' "$bench_scene" | grep -v '^[[:space:]]*$'; echo "$*"; echo "$sources_hash") | sha1sum | cut -c1-16
}

# sim_run CACHE NAME SETTLE_S [--set KEY=VALUE ...]: runs (or reuses) one simulation of
# SETTLE_S simulated seconds. Call it in the background and `wait`; see sim_batch.
sim_run() {
    local cache="$1" name="$2" settle="$3"
    shift 3
    local dir="$cache/sim/$name"
    local key
    key="$(sim_run_key "$settle" "$@")"
    if [[ -f "$dir/key" && "$(cat "$dir/key")" == "$key" && -f "$dir/cost" ]]; then
        echo "  $name: cached"
        return 0
    fi
    rm -rf "$dir"
    mkdir -p "$dir"
    local sets=()
    for s in "$@"; do sets+=(--set "$s"); done
    local t0 t1
    t0=$(date +%s.%N)
    if ! /usr/bin/time -f "%U %S" -o "$dir/time" nice -n 5 "$bench_bin/ferro-sim" "$bench_scene" --out "$dir/frames" \
        --threads 1 --set shot.duration="$settle" --set shot.fps=2 "${sets[@]}" 2>"$dir/log"; then
        echo "  $name: ferro-sim failed: $(tail -1 "$dir/log")" >&2
        return 3
    fi
    t1=$(date +%s.%N)
    local steps cpu
    steps=$(sed -n 's/.*done, \([0-9]*\) steps.*/\1/p' "$dir/log" | tail -1)
    cpu=$(awk '{print $1 + $2}' "$dir/time")
    echo "$(echo "$t1 - $t0" | bc) $cpu $steps" >"$dir/cost"
    echo "$key" >"$dir/key"
    echo "  $name: $(cat "$dir/cost") (wall s, cpu s, steps)"
}

# The last frame of a run: the settled state.
sim_last_frame() {
    ls "$1/sim/$2/frames"/particles_*.ply | sort | tail -1
}

# sim_batch CACHE SETTLE_S < lines "NAME [KEY=VALUE ...]": runs them BENCH_JOBS at a time.
sim_batch() {
    local cache="$1" settle="$2" failed=0
    local name rest
    while read -r name rest; do
        [[ -z "$name" ]] && continue
        while (($(jobs -rp | wc -l) >= bench_jobs)); do wait -n || failed=1; done
        # shellcheck disable=SC2086
        sim_run "$cache" "$name" "$settle" $rest &
    done
    while (($(jobs -rp | wc -l) > 0)); do wait -n || failed=1; done
    # A failed run: exit code 3 (run failed) for the area script.
    return $((failed ? 3 : 0))
}

# One row's numbers from bench-heap-profile --summary: value of KEY in the line.
kv() { tr ' ' '\n' <<<"$1" | sed -n "s/^$2=//p"; }

sources_hash="$(sim_sources_hash)"

# csv_md CSV COLUMN...: a Markdown table of the named columns of CSV (all columns without names).
csv_md() {
    local csv="$1"
    shift
    awk -F, -v want="$*" '
        NR == 1 { n = split(want, w, " "); if (n == 0) { n = NF; for (i = 1; i <= NF; i++) w[i] = $i }
                  for (i = 1; i <= NF; i++) idx[$i] = i
                  line = "|"; sep = "|"
                  for (k = 1; k <= n; k++) { line = line " " w[k] " |"; sep = sep "---|" }
                  print line; print sep; next }
        { line = "|"; for (k = 1; k <= n; k++) line = line " " $(idx[w[k]]) " |"; print line }' "$csv"
}

# csv_get CSV SETTING COLUMN: one cell, by the row's first column and the column's name.
csv_get() {
    awk -F, -v s="$2" -v c="$3" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == c) k = i; next }
        $1 == s { print $k; exit }' "$1"
}
