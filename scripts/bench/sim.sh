#!/usr/bin/env bash
# sim.sh: ferro-sim's speed/accuracy trade (issue 16): particle count, pressure solver, DFSPH
# density tolerance and the time-step bound, on the heap pool (scripts/bench/heap_pool.toml:
# a 5 cm dish, 1 cm of ferrofluid, a 3 A m^2 dipole held still 2 cm under the floor,
# `external` magnetization so that the pool comes to rest).
#
#   scripts/bench/sim.sh [OUT_DIR]        (default tests/bench/report; BENCH_QUICK=1: tiny)
#
# Every run simulates SETTLE seconds from the flat fill (1.5 s; the heap forms and settles);
# its last frame is measured with bench-heap-profile against a reference run of the same
# scene: the finest particle count for the count ladder (particles.csv), the tightest DFSPH
# tolerance with the smallest step bound at the base count for pressure_solver.csv,
# density_tolerance.csv and max_dt.csv. Errors: the heap profile (column height h(r) from
# the centre to 0.9 x the pool radius, RMS and largest difference over 20 radii), the settled
# surface height over the magnet (centre height) and the heap's rise h(0) - h(rmax) relative
# to the reference's. Cost: CPU seconds per simulated second and CPU ms per step of a
# one-thread run (the machine is shared; see sim-lib.sh), plus wall seconds as measured.
# Writes OUT_DIR/{particles,pressure_solver,density_tolerance,max_dt}.csv, their PNG plots
# and OUT_DIR/sim.md. Runs are cached in OUT_DIR/cache/sim (sim-lib.sh).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
source "$here/sim-lib.sh"
out="${1:-$bench_root/tests/bench/report}"
mkdir -p "$out/cache"
out="$(cd "$out" && pwd)"
cache="$out/cache"
for exe in ferro-sim bench-heap-profile; do
    [[ -x "$bench_bin/$exe" ]] || { echo "sim.sh: error: $bench_bin/$exe is missing (run scripts/build.sh)" >&2; exit 4; }
done

if [[ "${BENCH_QUICK:-0}" == 1 ]]; then
    settle=0.5 counts=(320 640) base=320
else
    settle=1.5 counts=(640 2560 10240) base=2560
fi
fine=${counts[-1]}
echo "sim.sh: heap pool, settle ${settle} s, particles ${counts[*]}, base $base, $bench_jobs runs at a time"

# The runs (name, overrides). The reference of the solver ladders, refB: DFSPH at a 4x tighter
# density tolerance than the default and half the default step bound.
{
    for ((i = ${#counts[@]} - 1; i >= 0; i--)); do echo "p${counts[i]} fluid.block.0.count=${counts[i]}"; done
    echo "refB fluid.block.0.count=$base sim.max_density_error=5e-5 sim.max_dt=0.0005"
    echo "wcsph fluid.block.0.count=$base sim.solver=wcsph"
    echo "tol1e-3 fluid.block.0.count=$base sim.max_density_error=0.001"
    echo "tol5e-5 fluid.block.0.count=$base sim.max_density_error=5e-5"
    echo "dt2e-3 fluid.block.0.count=$base sim.max_dt=0.002"
    echo "dt5e-4 fluid.block.0.count=$base sim.max_dt=0.0005"
} | sim_batch "$cache" "$settle"

# row NAME REFNAME SETTING: "setting,particles,spacing_mm,steps,cpu_s_per_sim_s,cpu_ms_per_step,
# wall_s_per_sim_s,profile_rms_err_mm,profile_max_err_mm,centre_height_mm,centre_err_mm,
# rise_mm,rise_err_pct,rms_speed_mm_s,reference"
header="setting,particles,spacing_mm,steps,cpu_s_per_sim_s,cpu_ms_per_step,wall_s_per_sim_s,profile_rms_err_mm,profile_max_err_mm,centre_height_mm,centre_err_mm,rise_mm,rise_err_pct,rms_speed_mm_s,reference"
row() {
    local name="$1" ref="$2" setting="$3"
    local s wall cpu steps
    s="$("$bench_bin/bench-heap-profile" "$(sim_last_frame "$cache" "$name")" --ref "$(sim_last_frame "$cache" "$ref")" --summary)"
    read -r wall cpu steps <"$cache/sim/$name/cost"
    awk -v setting="$setting" -v n="$(kv "$s" particles)" -v sp="$(kv "$s" spacing_m)" -v steps="$steps" \
        -v cpu="$cpu" -v wall="$wall" -v T="$settle" -v prms="$(kv "$s" profile_rms_err_m)" \
        -v pmax="$(kv "$s" profile_max_err_m)" -v ch="$(kv "$s" centre_height_m)" -v ce="$(kv "$s" centre_err_m)" \
        -v rise="$(kv "$s" rise_m)" -v re="$(kv "$s" rise_err_rel)" -v v="$(kv "$s" rms_speed_m_s)" -v ref="$ref" \
        'BEGIN { printf "%s,%d,%.3f,%d,%.1f,%.1f,%.1f,%.3f,%.3f,%.3f,%.3f,%.3f,%.1f,%.2f,%s\n",
                 setting, n, 1e3 * sp, steps, cpu / T, 1e3 * cpu / steps, wall / T, 1e3 * prms, 1e3 * pmax,
                 1e3 * ch, 1e3 * ce, 1e3 * rise, 100 * re, 1e3 * v, ref }'
}

{
    echo "$header"
    for n in "${counts[@]}"; do row "p$n" "p$fine" "$n"; done
} >"$out/particles.csv"
{
    echo "$header"
    row "p$base" refB "dfsph"
    row wcsph refB "wcsph"
    row refB refB "dfsph 5e-5 max_dt 5e-4 (ref)"
} >"$out/pressure_solver.csv"
{
    echo "$header"
    row tol1e-3 refB "1e-3"
    row "p$base" refB "2e-4"
    row tol5e-5 refB "5e-5"
    row refB refB "5e-5 max_dt 5e-4 (ref)"
} >"$out/density_tolerance.csv"
{
    echo "$header"
    row dt2e-3 refB "2e-3"
    row "p$base" refB "1e-3"
    row dt5e-4 refB "5e-4"
    row refB refB "5e-4 tol 5e-5 (ref)"
} >"$out/max_dt.csv"

for k in particles pressure_solver density_tolerance max_dt; do
    "$here/plot.sh" "$out/$k.csv" cpu_s_per_sim_s profile_rms_err_mm "$out/$k.png" \
        "ferro-sim $k: heap profile error vs cost (heap pool, settle $settle s)" || echo "sim.sh: plot of $k failed" >&2
done
echo "sim.sh: wrote $out/{particles,pressure_solver,density_tolerance,max_dt}.csv and .png"
