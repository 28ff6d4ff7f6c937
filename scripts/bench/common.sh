# common.sh: shared helpers of the area scripts in scripts/bench/ (sourced, not run).
#
#   source "$(dirname "$0")/common.sh"; bench_init AREA "$@"
#
# After bench_init: $root (checkout), $out (OUT_DIR, absolute), $cache ($out/cache, not
# committed), $bin (FERRO_BIN or build/bin), $quick (1 with BENCH_QUICK=1), $work (a scratch
# directory removed on exit), $area. Bad arguments: one line on stderr, exit 2.

bench_die() { echo "$area.sh: error: $2" >&2; exit "$1"; }
bench_note() { echo "$area.sh: $*" >&2; }

bench_init() {
  area="$1"; shift
  root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
  [[ $# -le 1 ]] || bench_die 2 "usage: scripts/bench/$area.sh [OUT_DIR] (default tests/bench/report)"
  out="${1:-$root/tests/bench/report}"
  mkdir -p "$out/cache" || bench_die 4 "$out: cannot create the output directory"
  out="$(cd "$out" && pwd)"
  cache="$out/cache"
  quick="${BENCH_QUICK:-0}"
  bin="${FERRO_BIN:-$root/build/bin}"
  bin="$(cd "$bin" 2>/dev/null && pwd)" || bench_die 4 "no Ferro executables in ${FERRO_BIN:-$root/build/bin} (run scripts/build.sh)"
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
}

# bench_need EXE...: every executable must be in $bin (exit 4 naming the first missing one).
# With the default build/bin, each is (re)built first: benchmarks are not in the default
# build, so one left from an older build would otherwise measure old code.
bench_need() {
  local e
  for e in "$@"; do
    if [[ -z "${FERRO_BIN:-}" && -f "$root/build/CMakeCache.txt" ]]; then
      cmake --build "$root/build" --target "$e" > "$work/build-$e.log" 2>&1 ||
        bench_die 3 "building $e failed: $(tail -n 1 "$work/build-$e.log")"
    fi
    [[ -x "$bin/$e" ]] || bench_die 4 "$bin/$e is missing (run scripts/build.sh --with-benchmarks)"
  done
}

# bench_time VAR CMD...: runs CMD (stdout and stderr to $work/last.log) and stores its CPU
# seconds (user + system, all threads) in VAR and its wall seconds in VAR_wall. CPU seconds are
# the cost the reports use: the machine is shared, so wall time measures the neighbours too.
# A failing CMD stops the script with its log tail (exit 3).
bench_time() {
  local var="$1"; shift
  local TIMEFORMAT='%R %U %S' times rc=0
  times="$( { time "$@" > "$work/last.log" 2>&1; } 2>&1 )" || rc=$?
  [[ $rc == 0 ]] || { tail -n 5 "$work/last.log" >&2; bench_die 3 "failed: $*"; }
  read -r wall user sys <<< "$times"
  printf -v "$var" '%s' "$(calc "$user + $sys")"
  printf -v "${var}_wall" '%s' "$wall"
}

# bench_best VAR REPEATS CMD...: the least CPU seconds of REPEATS runs.
bench_best() {
  local var="$1" n="$2"; shift 2
  local best="" t t_wall i
  for ((i = 0; i < n; ++i)); do
    bench_time t "$@"
    best="$(awk -v a="$best" -v b="$t" 'BEGIN { print (a == "" || b < a) ? b : a }')"
  done
  printf -v "$var" '%s' "$best"
}

# kv KEY LINE: the value of KEY=value in a line of key=value pairs.
kv() { tr ' ' '\n' <<< "$2" | sed -n "s/^$1=//p" | head -n 1; }

# calc EXPR: floating-point arithmetic through awk, e.g. calc "100 * ($a - $b) / $b".
calc() { awk "BEGIN { printf \"%.6g\", $1 }"; }

# bench_cached_shot SUBDIR SCENE [K=V]...: ferro-sim's frames of SCENE with `--set K=V` each, in
# $dir = $cache/SUBDIR/<hash of the scene text and the sets>, simulated once (a directory
# without its `done` file is run again); its CPU seconds in $cpu. The key leaves out the
# binary: after a rebuild that changes the simulation, clear $cache/SUBDIR.
bench_cached_shot() {
  local sub="$1" scene_file="$2"; shift 2
  local sets=() kv
  for kv in "$@"; do sets+=(--set "$kv"); done
  dir="$cache/$sub/$( (cat "$scene_file"; printf '%s\n' "${sets[@]}") | sha1sum | cut -c1-16)"
  if [[ ! -f "$dir/done" ]]; then
    bench_note "simulating $(basename "$scene_file") $* (cached in $dir)"
    rm -rf "$dir"; mkdir -p "$dir"
    bench_time cpu nice -n 5 "$bin/ferro-sim" "$scene_file" --out "$dir" "${sets[@]}" --quiet
    echo "$cpu" > "$dir/done"
  fi
  cpu="$(cat "$dir/done")"
}

# bench_settled_frame VAR SCENE [--set K=V]...: a settled frame 0 of SCENE (ferro-sim with its
# [shot] preroll and --max-frames 0), cached in $cache/frames/<hash of the scene text and the
# overrides>/particles_0000.ply and reused while they are unchanged; VAR gets its path.
# The executable is not part of the hash: a rebuild keeps the cache (delete $cache to redo).
bench_settled_frame() {
  local var="$1" scene="$2"; shift 2
  local key dir
  key="$( (cat "$scene"; printf '%s\n' "$@") | sha1sum | cut -c1-16)"
  dir="$cache/frames/$(basename "$scene" .toml)-$key"
  if [[ ! -f "$dir/particles_0000.ply" ]]; then
    bench_need ferro-sim
    bench_note "simulating the settled frame of $(basename "$scene") $* (cached in $dir)"
    rm -rf "$dir.tmp"
    local t t_wall
    bench_time t nice -n 5 "$bin/ferro-sim" "$scene" --out "$dir.tmp" --max-frames 0 "$@"
    cp "$work/last.log" "$dir.tmp/ferro-sim.log"
    echo "cpu $t wall $t_wall" > "$dir.tmp/seconds"
    rm -rf "$dir"; mv "$dir.tmp" "$dir"
  fi
  printf -v "$var" '%s' "$dir/particles_0000.ply"
}

# bench_plot CSV XCOL YCOL NAME TITLE: $out/NAME.png through plot.sh.
bench_plot() { "$root/scripts/bench/plot.sh" "$1" "$2" "$3" "$out/$4.png" "$5"; }

# Markdown helpers of the sections: numbers to 3 significant digits ("?" when missing),
# metres as mm, a CSV as a Markdown table (all columns but the last, the reference), and
# column C of the row whose first field is WANT.
mm() { awk -v x="$1" 'BEGIN { if (x == "") print "?"; else printf "%.3g mm", 1000 * x }'; }
r3() { awk -v x="$1" 'BEGIN { if (x == "") print "?"; else printf "%.3g", x }'; }
table() {
  awk -F, 'NR == 1 { h = "|"; s = "|"; for (i = 1; i < NF; ++i) { h = h " " $i " |"; s = s " --- |" }; print h; print s; next }
           { r = "|"; for (i = 1; i < NF; ++i) r = r " " $i " |"; print r }' "$1"
}
col() { awk -F, -v want="$2" -v c="$3" 'NR > 1 && $1 == want { print $c }' "$1"; }
