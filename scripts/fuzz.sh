#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz, clang++ with -fsanitize=fuzzer,address,undefined)
# and runs each on its committed corpus, printing the executions per target.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]     run each target SECONDS (default 60) of wall time
#   scripts/fuzz.sh --runs N [TARGET...]      run each target exactly N inputs (what ctest does)
#
# Targets: scene particles mesh (default: all). Options:
#   --build-dir DIR  where the fuzz build lives (default build/fuzz)
#   --build-only     build and stop;  --no-build: run what is built
#   --merge          afterwards add the inputs that found new coverage to tests/fuzz/corpus/
#                    (libFuzzer -merge=1 -use_counters=0: only inputs that reach new code)
#   --jobs N         compile jobs (default 2)
#   --keep-going     (timed runs) after a crash, note it and go on fuzzing for the time left
# New inputs of a timed run go to DIR/work/<target>, kept for the next run (the corpus is only
# read, unless --merge); those of a --runs run to DIR/runs/<target>, emptied first;
# a crash is saved as DIR/artifacts/<target>-crash-<sha1> and ends the script with exit 1.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build/fuzz"
seconds=60 runs="" merge=0 do_build=1 do_run=1 jobs=2 keep_going=0 targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --runs) runs="$2"; shift 2 ;;
    --build-dir) build="$2"; shift 2 ;;
    --build-only) do_run=0; shift ;;
    --no-build) do_build=0; shift ;;
    --merge) merge=1; shift ;;
    --keep-going) keep_going=1; shift ;;
    --jobs) jobs="$2"; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    [0-9]*) seconds="$1"; shift ;;
    scene|particles|mesh) targets+=("$1"); shift ;;
    *) echo "fuzz.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[ ${#targets[@]} -gt 0 ] || targets=(scene particles mesh)

if [ "$do_build" = 1 ]; then
  cxx="$(command -v clang++ || true)"
  if [ -z "$cxx" ]; then
    echo "fuzz.sh: clang++ not found: the fuzz targets need Debian's clang (scripts/install-deps.sh installs it)" >&2
    exit 1
  fi
  mkdir -p "$build"
  if ! { cmake -S "$root/tests/fuzz" -B "$build" -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE=None &&
         cmake --build "$build" -j"$jobs"; } >"$build/build.log" 2>&1; then
    grep -v '^\[' "$build/build.log" | tail -30 >&2
    echo "fuzz.sh: the fuzz build failed (all of it in $build/build.log; libFuzzer itself comes with" \
         "Debian's libclang-rt-dev, which scripts/install-deps.sh installs)" >&2
    exit 1
  fi
fi
[ "$do_run" = 1 ] || exit 0

mkdir -p "$build/artifacts"
# Leaks are findings too; -timeout turns a hang into a crash; -malloc_limit_mb a huge allocation.
common=(-timeout=10 -rss_limit_mb=2048 -malloc_limit_mb=1024 -print_final_stats=1)
# Every sanitizer report is fatal; the suppressions name third-party code only (see README).
sanitizers=(ASAN_OPTIONS=detect_leaks=1
            LSAN_OPTIONS="suppressions=$root/tests/fuzz/lsan.supp"
            UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$root/tests/fuzz/ubsan.supp")
status=0
summary=()
for t in "${targets[@]}"; do
  exe="$build/fuzz_$t"
  [ -x "$exe" ] || { echo "fuzz.sh: $exe is not built (run without --no-build)" >&2; exit 1; }
  corpus="$root/tests/fuzz/corpus/$t"
  work="$build/work/$t"
  if [ -n "$runs" ]; then
    # A fixed run starts from the committed corpus alone, every time, and leaves the
    # inputs of timed runs alone.
    work="$build/runs/$t"
    rm -rf "$work"
  fi
  mkdir -p "$work"
  # Separate logs, so that a --runs run (ctest) never touches those of a timed run.
  log="$build/$([ -n "$runs" ] && echo runs || echo fuzz)_$t.log"
  echo "fuzz.sh: $t: $([ -n "$runs" ] && echo "$runs runs" || echo "$seconds s") on $(find "$corpus" -type f | wc -l) corpus inputs"
  start=$(date +%s)
  execs=0 crashes=0 rc=0
  : >"$log"
  while :; do
    if [ -n "$runs" ]; then
      limit=(-runs="$runs" -seed=1)
    else
      left=$(( seconds - ($(date +%s) - start) ))
      [ "$left" -gt 0 ] || break
      limit=(-max_total_time="$left")
    fi
    set +e
    (cd "$build" && env "${sanitizers[@]}" "$exe" "${common[@]}" "${limit[@]}" \
       -artifact_prefix="$build/artifacts/$t-" "$work" "$corpus") >"$log.round.$$" 2>&1
    rc=$?
    set -e
    cat "$log.round.$$" >>"$log"
    n=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log.round.$$" | tail -1)
    execs=$(( execs + ${n:-0} ))
    rm -f "$log.round.$$"
    [ "$rc" -eq 0 ] && break
    crashes=$(( crashes + 1 ))
    echo "fuzz.sh: $t FAILED (exit $rc); the end of $log:" >&2
    grep -v '^    #\|^#\|^INFO\|NEW_FUNC' "$log" | tail -25 >&2
    [ "$keep_going" = 1 ] && [ -z "$runs" ] || break
  done
  elapsed=$(( $(date +%s) - start ))
  [ "$crashes" -eq 0 ] || status=1
  summary+=("$t: $execs executions in ${elapsed} s$([ "$crashes" -ne 0 ] && echo " ($crashes crashes: see $build/artifacts)" || true)")
  if [ "$merge" = 1 ]; then
    (cd "$build" && env "${sanitizers[@]}" "$exe" -merge=1 -use_counters=0 "${common[@]:0:3}" "$corpus" "$work") \
      >"$build/merge_$t.log" 2>&1
    echo "fuzz.sh: $t: corpus now $(find "$corpus" -type f | wc -l) inputs"
  fi
done
printf 'fuzz.sh: %s\n' "${summary[@]}"
exit $status
