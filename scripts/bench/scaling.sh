#!/usr/bin/env bash
# scaling.sh: the scaling area of scripts/bench.sh: what the SPH core costs as the work
# grows. bench-sim's dam break at 40,960, 163,840 and 1,024,000 particles (--widen 1, 2, 5:
# the same 40 layers deep, wider and longer), both solvers, the same simulated interval:
# time a particle-step, peak memory a particle, and DFSPH's pressure sweep alone against the
# machine's memory bandwidth (a triad measured in the same run).
#
#   scripts/bench/scaling.sh [OUT_DIR]
#
# Writes OUT_DIR/scaling.csv and OUT_DIR/scaling.md. BENCH_QUICK=1: 40,960 and 163,840 only.
# Exit codes: 2 bad arguments, 3 a run failed, 4 missing bench-sim.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init scaling "$@"
bench_need bench-sim

widths=(1 2 5)
[[ "$quick" == 1 ]] && widths=(1 2)
# From t = 2 ms to 6 ms: the block at rest settling under gravity, the same phase at every
# size (the dam break's later flow differs with the width), a few DFSPH steps at 1,024,000.
warmup=0.002 seconds=0.004
csv="$out/scaling.csv"
echo "setting,solver,particles,steps,iterations_per_step,ns_per_particle_step,ns_per_particle_iteration,peak_bytes_per_particle,sweep_ns_per_particle,sweep_bytes_per_particle,sweep_gbytes_per_s,triad_gbytes_per_s,reference" > "$csv.tmp"
for w in "${widths[@]}"; do
  bench_note "bench-sim --widen $w"
  "$bin/bench-sim" --threads 2 --tension off --warmup "$warmup" --seconds "$seconds" --widen "$w" > "$work/w$w.txt" 2>&1 ||
    { tail -n 5 "$work/w$w.txt" >&2; bench_die 3 "bench-sim --widen $w failed"; }
  triad="$(sed -n 's/^memory bandwidth (triad, [0-9]* threads): \([0-9.]*\) GB\/s$/\1/p' "$work/w$w.txt")"
  [[ -n "$triad" ]] || bench_die 3 "bench-sim --widen $w printed no bandwidth"
  # Row lines (solver, tension, steps, ms/step, dt, wall, iter p/d, ...) and cost lines.
  awk -v triad="$triad" '
    $1 == "WCSPH" || $1 == "DFSPH" { split($7, it, "/"); steps[$1] = $3; iters[$1] = it[1] + it[2] }
    $1 == "cost:" {
      for (i = 2; i <= NF; ++i) { split($i, kv, "="); c[kv[1]] = kv[2] }
      s = c["solver"]; n = c["particles"]
      per_iter = iters[s] > 0 ? c["ns_per_particle_step"] / iters[s] : ""
      printf "%s %s,%s,%s,%s,%.1f,%s,%s,%s,%s,%s,%s,%s,%s\n", s, n, s, n, steps[s], iters[s], c["ns_per_particle_step"],
             per_iter == "" ? "" : sprintf("%.1f", per_iter), c["peak_bytes_per_particle"],
             s == "DFSPH" ? c["sweep_ns_per_particle"] : "", s == "DFSPH" ? c["sweep_bytes_per_particle"] : "",
             s == "DFSPH" ? c["sweep_gbytes_per_s"] : "", triad, s " at 40960"
    }' "$work/w$w.txt" >> "$csv.tmp"
done
mv -f "$csv.tmp" "$csv"

col() { awk -F, -v row="$1" -v name="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next } $1 == row { print $c[name] }' "$csv"; }
big="$(tail -n 1 "$csv" | cut -d, -f3)"
ratio() { awk -v a="$(col "$1 $big" "$2")" -v b="$(col "$1 40960" "$2")" 'BEGIN { printf "%.2f", a / b }'; }
{
  echo "## Scaling: cost as the work grows"
  echo
  echo "bench-sim's dam break widened (\`--widen 1, 2, 5\`: the block and the box 1, 2 and 5 times as"
  echo "wide and long, 40 layers deep as before), from t = $warmup s for $seconds simulated s, 2 threads,"
  echo "no surface tension. Time a particle-step from the step clock; peak memory is the process's"
  echo "resident peak over the particles (set-up included); the sweep is DFSPH's iteration body alone"
  echo "(pressure accelerations, then their divergence), timed on the state at the end, with the bytes"
  echo "it must stream (each pair's neighbour index and kernel gradient factor twice, per-particle arrays)."
  echo "Made by \`scripts/bench/scaling.sh\` on $(date -u +%F) at commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)."
  echo
  echo "| solver | particles | steps | iterations/step | ns a particle-step | ns a particle-iteration | peak bytes a particle | sweep ns a particle | sweep bytes a particle | sweep GB/s | triad GB/s |"
  echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12 }' "$csv"
  echo
  echo "- From 40,960 to $big particles: WCSPH's time a particle-step $(ratio WCSPH ns_per_particle_step)x, DFSPH's time a"
  echo "  particle-iteration $(ratio DFSPH ns_per_particle_iteration)x and its sweep $(ratio DFSPH sweep_ns_per_particle)x; peak memory a particle $(ratio DFSPH peak_bytes_per_particle)x"
  echo "  (fixed set-up costs spread thinner). Nothing grows faster than the particle count."
  echo "- DFSPH's time a particle-step also follows its iterations a step: 100 is the cap"
  echo "  (sim.max_iterations), the block building its pressure from rest in the first milliseconds,"
  echo "  where the wider blocks reach it; the cost of one iteration grows far less."
  echo "- The sweep streams $(col "DFSPH $big" sweep_bytes_per_particle) bytes a particle at $(col "DFSPH $big" sweep_gbytes_per_s) GB/s against the triad's $(col "DFSPH $big" triad_gbytes_per_s) GB/s: not"
  echo "  bound by memory bandwidth but by the gathers of neighbours' values (SSE2 has no gather:"
  echo "  four scalar loads a lane group). Storing one gradient factor a pair instead of a 12-byte"
  echo "  gradient halved the bytes (1,052 to 520 at 40,960) at the same sweep time, and took peak"
  echo "  memory from 1,910 to 1,350 bytes a particle."
} > "$out/scaling.md"
bench_note "wrote $csv and $out/scaling.md"
