#!/usr/bin/env bash
# bench-peer.sh: the peer comparison of issue 16. SPlisHSPlasH (the reference SPH library)
# and Ferro run the same 40,960-particle dam break, each with WCSPH and DFSPH, in one run,
# and the report gets their cost as ratios (the machine is shared: ratios, not times).
#
#   scripts/bench-peer.sh PEER_SIM OUT_DIR
#
# PEER_SIM is SPlisHSPlasH's SPHSimulator executable (built by the user from SPlisHSPlasH's
# own source; this repository holds no copy of it and no recipe that builds it). Writes
# OUT_DIR/peer.csv (one row per code and solver), OUT_DIR/peer.md (a Markdown section) and
# OUT_DIR/peer.png when scripts/bench/plot.sh is there; scratch files (scenes, logs, the
# exported densities) go to OUT_DIR/cache/peer/ and the densities are deleted once read.
#
# The scene is bench-sim's (tests/bench/bench_sim.cpp): a 32 x 32 x 40 block of water at
# 2.5 mm spacing (particle radius 1.25 mm, kernel support 5 mm in both codes) in a
# 0.32 x 0.08 x 0.2 m box, gravity -z, no surface tension, from t = 0 for PEER_SECONDS
# (WCSPH) and PEER_DFSPH_SECONDS (DFSPH).
# (SPlisHSPlasH 2.16.0 was measured; its scene format is the one since 2.16.0, with a block
# per solver, e.g. "Standard viscosity" inside the material.)
# Settings handed to SPlisHSPlasH from the `scene:` line bench-sim prints (so they cannot
# drift from Ferro's): the same particle positions, viscosity (its "Standard" viscosity has
# Ferro's form and coefficient: fluid plus artificial viscosity), walls of one layer of
# Akinci 2012 boundary particles (regular sampling) where Ferro's lie, half a spacing outside
# the box faces, without wall viscosity, cubic spline kernel, 2 threads; DFSPH: the same CFL
# rule (0.4 x spacing / max speed, cflFactor 1), the same 1 ms step bound (floor: its
# default 0.1 ms), density tolerance 0.02 % and divergence tolerance 0.1 %, 100
# iterations at most; WCSPH: Tait exponent 7 with Ferro's stiffness rho0 c^2 / 7 and
# Ferro's mean time step of the same run as a fixed step (SPlisHSPlasH's CFL ignores the
# speed of sound, so Ferro's sound-speed CFL cannot be given to it as a rule).
# Not matched (stated in peer.md): SPlisHSPlasH's particle volume is 0.8 d^3 (a fixed
# factor of its fluid model), so its fluid is the same lattice at 0.928 d (0.8 of Ferro's
# volume, at rest density: see peer_scene) and has 1.25x Ferro's neighbours a particle;
# it is compiled with -march=native (AVX2), Ferro for generic x86-64 unless FERRO_BIN is a
# FERRO_NATIVE=ON build (peer.md says which; a generic Ferro still runs its pressure sweeps'
# x86-64-v3 copy where the processor has it: sim/sph/sweeps); both in
# single precision; OpenMP against TBB.
#
# The density error each code reaches is measured one way for both: the mean compression
# max(0, rho / rho0 - 1) over the particles, from each code's own SPH densities after the
# first step past every 5 ms (SPlisHSPlasH: its exported densities; Ferro: bench-sim's
# `rho err %`), averaged over those samples. Ferro's own per-step solver figure (DFSPH:
# mean residual, the quantity its tolerance bounds) is reported beside it.
#
# Cost: ms per step is the mean over all steps of the step alone (SPlisHSPlasH: its
# "SimStep" timer; Ferro: bench-sim's clock around FluidSimulation::step), without set-up
# or output; wall s per simulated s = steps x ms per step / simulated time. Each run of the
# pair is adjacent in time (Ferro, then SPlisHSPlasH, per solver) so both see similar load;
# with PEER_REPEAT=N the pair runs N times and the fastest run of each is kept.
#
# Threads: bench-sim's TBB limit and OMP_NUM_THREADS for SPlisHSPlasH (OpenMP), with
# OMP_WAIT_POLICY=passive: on this shared, oversubscribed machine OpenMP's default spinning
# at barriers made SPlisHSPlasH's neighbour search 1.4x slower on 2 threads than on 1
# (160 against 116 ms per search at a load of 9); passive waiting gave 135 ms.
#
# Environment: FERRO_BIN (default build/bin: bench-sim), PEER_SECONDS (simulated time of the
# WCSPH pair, default 0.05; BENCH_QUICK=1: 0.02), PEER_DFSPH_SECONDS (the DFSPH pair, default
# 0.1; quick: 0.005), PEER_THREADS (default 2), PEER_REPEAT (default 1), PEER_REUSE=1 (only
# rewrite CSV and Markdown from the runs kept in OUT_DIR/cache/peer), PEER_BUILD_NOTE (a
# sentence on how PEER_SIM was built, for peer.md). SPlisHSPlasH's WCSPH pair takes ~6 min
# of the ~8 here (2 shared cores).
# Exit codes: 2 bad arguments (or PEER_SIM is not SPlisHSPlasH's simulator), 4 missing
# PEER_SIM or bench-sim, 3 a run failed.
set -euo pipefail
die() { echo "bench-peer.sh: error: $2" >&2; exit "$1"; }
[[ $# -eq 2 ]] || die 2 "usage: bench-peer.sh PEER_SIM OUT_DIR (PEER_SIM: SPlisHSPlasH's SPHSimulator executable)"
peer_sim="$1" out="$2"
[[ -e "$peer_sim" ]] || die 4 "$peer_sim: no such file"
[[ -f "$peer_sim" && -x "$peer_sim" ]] || die 2 "$peer_sim: not an executable file"
"$peer_sim" --help 2>/dev/null | grep -q "SPlisHSPlasH" ||
  die 2 "$peer_sim: not SPlisHSPlasH's simulator (its --help does not name SPlisHSPlasH)"
peer_sim="$(cd "$(dirname "$peer_sim")" && pwd)/$(basename "$peer_sim")"
peer_version="$("$peer_sim" --version 2>/dev/null | head -n 1)"

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bin="${FERRO_BIN:-$root/build/bin}"
# Whether FERRO_BIN is a build tuned for this processor (CMake option FERRO_NATIVE), as
# SPlisHSPlasH's own build is (-march=native): the report says which comparison it is.
ferro_native=0
grep -qs '^FERRO_NATIVE:BOOL=ON' "$bin/../CMakeCache.txt" && ferro_native=1
# bench-sim is not in the default build: with the default build/bin it is (re)built here, so
# an old one cannot stand in for the code being measured.
if [[ -z "${FERRO_BIN:-}" && -f "$root/build/CMakeCache.txt" ]]; then
  cmake --build "$root/build" --target bench-sim > /dev/null 2>&1 || die 3 "building bench-sim failed (cmake --build build --target bench-sim)"
fi
[[ -x "$bin/bench-sim" ]] || die 4 "$bin/bench-sim: not built (scripts/build.sh --with-benchmarks)"
# The pressure sweeps' copy bench-sim runs (its first line: "pressure sweeps NAME").
ferro_sweeps="$("$bin/bench-sim" --seconds 0.0001 --warmup 0 --solver wcsph --tension off 2>/dev/null | sed -n 's/.*pressure sweeps \([^ ]*\)$/\1/p' | head -1 || true)"
ferro_sweeps="${ferro_sweeps:-the baseline}"
seconds="${PEER_SECONDS:-$([[ "${BENCH_QUICK:-0}" == 1 ]] && echo 0.02 || echo 0.05)}"
# The WCSPH pair is shorter: SPlisHSPlasH's WCSPH steps cost ~5x Ferro's here (its
# neighbour search every step), and WCSPH takes ~15x as many steps as DFSPH. Over its first
# ~20 ms SPlisHSPlasH's under-dense block needs no pressure, so DFSPH runs 0.1 s.
dfsph_seconds="${PEER_DFSPH_SECONDS:-$([[ "${BENCH_QUICK:-0}" == 1 ]] && echo 0.005 || echo 0.1)}"
seconds_for() { [[ "$1" == dfsph ]] && echo "$dfsph_seconds" || echo "$seconds"; }
threads="${PEER_THREADS:-2}"
repeat="${PEER_REPEAT:-1}"
sample=0.005 # density sampling interval [s]; SPlisHSPlasH exports at 1 / sample frames per second
for s in "$seconds" "$dfsph_seconds"; do
  [[ "$s" =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v s="$s" 'BEGIN { exit !(s > 0) }' ||
    die 2 "PEER_SECONDS / PEER_DFSPH_SECONDS=$s: not a positive number"
done
[[ "$threads" =~ ^[1-9][0-9]*$ ]] || die 2 "PEER_THREADS=$threads: not a positive integer"
[[ "$repeat" =~ ^[1-9][0-9]*$ ]] || die 2 "PEER_REPEAT=$repeat: not a positive integer"
command -v python3 >/dev/null || die 4 "python3 is not installed (it reads SPlisHSPlasH's VTK files)"

mkdir -p "$out" || die 2 "$out: cannot create the output directory"
out="$(cd "$out" && pwd)"
work="$out/cache/peer"
# PEER_REUSE=1 keeps the results of earlier runs in OUT_DIR/cache/peer and only rewrites the
# CSV and Markdown from them (for changes to the report's form, not to the runs).
[[ "${PEER_REUSE:-0}" == 1 ]] || rm -rf "$work"
mkdir -p "$work"


# Processor time (user + system, all threads) of a whole process: a cross-check of the
# step timers that other load on the machine disturbs less (it includes set-up and output).
TIMEFORMAT='%U %S'
cpu_seconds() { awk '{ s = $1 + $2 } END { printf "%.2f", s }' "$1"; }

# ferro_run SOLVER -> prints "steps ms_per_step wall_s_per_sim_s iterations solver_err rho_err cpu_s div_iterations"
# and leaves the scene line in $work/scene.txt.
ferro_run() {
  local log="$work/ferro_$1.log"
  if ! { time OMP_NUM_THREADS="$threads" "$bin/bench-sim" --threads "$threads" --seconds "$(seconds_for "$1")" --warmup 0 \
      --solver "$1" --tension off --sample "$sample" > "$log" 2>&1; } 2> "$work/ferro_$1.cpu"; then
    cat "$log" >&2
    die 3 "bench-sim --solver $1 failed"
  fi
  grep '^scene:' "$log" > "$work/scene.txt" || die 3 "bench-sim printed no scene line ($log)"
  awk -v label="$(tr a-z A-Z <<< "$1")" -v cpu="$(cpu_seconds "$work/ferro_$1.cpu")" '$1 == label && $2 == "off" {
      split($7, it, "/"); print $3, $4, $6, it[1], $9, $10, cpu, (it[2] == "" ? 0 : it[2]); found = 1 }
    END { exit !found }' "$log" || die 3 "no $1 row in bench-sim's output ($log)"
}

scene_value() { # KEY -> value from bench-sim's scene line
  tr ' ' '\n' < "$work/scene.txt" | awk -F= -v k="$1" '$1 == k { print $2; found = 1 } END { exit !found }' ||
    die 3 "bench-sim's scene line has no $1"
}

# peer_scene SOLVER FIXED_DT -> writes $work/peer_SOLVER.json
peer_scene() {
  local solver="$1" dt="$2"
  local spacing nu c rho0 tol dtol maxdt maxit g
  spacing="$(scene_value spacing)" nu="$(scene_value nu)" c="$(scene_value c)" rho0="$(scene_value rho0)"
  tol="$(scene_value density_tol)" dtol="$(scene_value divergence_tol)" maxdt="$(scene_value max_dt)"
  maxit="$(scene_value max_iterations)" g="$(scene_value gravity)"
  python3 - "$work/peer_$solver.json" "$solver" "$dt" "$spacing" "$nu" "$c" "$rho0" "$tol" "$dtol" "$maxdt" \
    "$maxit" "$g" "$(seconds_for "$solver")" "$sample" "$work/box.obj" <<'PY'
import json, os, sys
(path, solver, dt, spacing, nu, c, rho0, tol, dtol, maxdt, maxit, g, seconds, sample, box) = sys.argv[1:]
spacing, nu, c, rho0, g = float(spacing), float(nu), float(c), float(rho0), float(g)
r = 0.5 * spacing
wcsph = solver == "wcsph"
config = {
    "particleRadius": r,                      # support 4 r = 2 spacings, as Ferro's
    "simulationMethod": 0 if wcsph else 4,
    "gravitation": [0, 0, -g],
    "boundaryHandlingMethod": 0,              # Akinci 2012 boundary particles, as Ferro
    "kernel": 0, "gradKernel": 0,             # cubic spline, as Ferro
    "stopAt": float(seconds), "pause": False,
    # WCSPH: Ferro's mean step of this run, fixed; DFSPH: Ferro's CFL rule and bound.
    "timeStepSize": float(dt) if wcsph else float(maxdt),
    "cflMethod": 0 if wcsph else 1,
    "cflFactor": 1,                           # dt = 1 x 0.4 x diameter / max speed
    # SPlisHSPlasH's default floor: its CFL step, which counts each particle's acceleration,
    # fell towards it in the first DFSPH steps; with Ferro's floor (1e-7 s) its run had not
    # reached t = 2.5 ms after 5 minutes.
    "cflMinTimeStepSize": 1e-4,
    "cflMaxTimeStepSize": float(maxdt),
    "enableVTKExport": True,
    "dataExportFPS": 1.0 / float(sample),
    "particleAttributes": "density",
    "WCSPH": {"stiffness": rho0 * c * c / 7, "exponent": 7},
    "DFSPH": {"minIterations": 2, "maxIterations": int(maxit), "maxError": 100 * float(tol),
              "maxIterationsV": int(maxit), "maxErrorV": 100 * float(dtol), "enableDivergenceSolver": True},
}
# The same start for both: each code's block at its own rest density. SPlisHSPlasH's
# particle volume is 0.8 d^3 (fixed in its fluid model), so its own fluid blocks (a lattice
# at d) start 20 % under-dense and need no pressure for the first ~20 ms (2 iterations a
# step where Ferro's block, at rest density, needs ~50). It gets Ferro's 32 x 32 x 40
# lattice at the spacing 0.8^(1/3) d = 0.928 d instead, from a particle file (Partio's
# ASCII PDA), the first layer half a spacing d from the walls as Ferro's: the same count,
# at rest density from the first step, 0.8 of Ferro's volume.
n = (32, 32, 40)
dense = spacing * 0.8 ** (1.0 / 3.0)
pda = os.path.join(os.path.dirname(path), "peer_block.pda")
with open(pda, "w") as f:
    f.write("ATTRIBUTES\nposition\nTYPES\nV\nNUMBER_OF_PARTICLES: %d\nBEGIN DATA\n" % (n[0] * n[1] * n[2]))
    for i in range(n[0]):
        for j in range(n[1]):
            for k in range(n[2]):
                f.write("%.9g %.9g %.9g\n" % (r + i * dense, r + j * dense, r + k * dense))
scene = {
    "Configuration": config,
    "Materials": [{"id": "Fluid", "density0": rho0, "viscosityMethod": 1,
                   "Standard viscosity": {"viscosity": nu, "viscosityBoundary": 0.0}}],
    "RigidBodies": [{"geometryFile": box, "translation": [0, 0, 0], "scale": [1, 1, 1],
                     "isDynamic": False, "isWall": True, "samplingMode": 1}],
    "FluidModels": [{"id": "Fluid", "particleFile": pda, "translation": [0, 0, 0], "scale": [1, 1, 1]}],
}
json.dump(scene, open(path, "w"), indent=1)
# The box as a closed triangle mesh (SPlisHSPlasH samples its surface), each face moved half
# a spacing out: SPlisHSPlasH's wall particles then lie where Ferro's do (Ferro offsets its
# wall layer half a spacing into the solid, the mirror image of the first fluid layer).
# On the box faces themselves the first fluid layer sat half a spacing from the wall
# particles and SPlisHSPlasH's first DFSPH step threw particles through the walls at 6 m/s.
lo, hi = [-r] * 3, [0.32 + r, 0.08 + r, 0.2 + r]
with open(box, "w") as f:
    for k in range(8):
        f.write("v %.9g %.9g %.9g\n" % tuple(hi[a] if k >> a & 1 else lo[a] for a in range(3)))
    # vertex index = 1 + x + 2 y + 4 z
    for tri in ((1, 4, 2), (1, 3, 4), (5, 6, 8), (5, 8, 7), (1, 2, 6), (1, 6, 5),
                (2, 4, 8), (2, 8, 6), (4, 3, 7), (4, 7, 8), (3, 1, 5), (3, 5, 7)):
        f.write("f %d %d %d\n" % tri)
PY
}

# peer_run SOLVER -> prints "steps ms_per_step wall_s_per_sim_s iterations particles rho_err cpu_s div_iterations"
peer_run() {
  local solver="$1" dir="$work/peer_$1"
  rm -rf "$dir"
  mkdir -p "$dir"
  if ! { time OMP_NUM_THREADS="$threads" OMP_WAIT_POLICY=passive "$peer_sim" --no-gui --no-cache --output-dir "$dir" "$work/peer_$solver.json" \
      > "$dir/stdout.log" 2>&1; } 2> "$dir/cpu.txt"; then
    tail -5 "$dir/stdout.log" >&2
    die 3 "SPlisHSPlasH ($solver) failed: $dir/stdout.log"
  fi
  python3 - "$dir" "$solver" "$(seconds_for "$solver")" "$(scene_value rho0)" "$(cpu_seconds "$dir/cpu.txt")" <<'PY' || die 3 "could not read SPlisHSPlasH's $solver results in $dir"
import glob, os, re, sys
from array import array
d, solver, seconds, rho0, cpu = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
log = open(os.path.join(d, "log", "SPH_log.txt"), errors="replace").read()
def last(pattern):
    m = re.findall(pattern, log)
    if not m:
        sys.exit("no '%s' in SPH_log.txt" % pattern)
    return float(m[-1])
ms = last(r"Average time: SimStep: ([0-9.eE+-]+) ms")
total_ms = last(r"Time sum: SimStep: ([0-9.eE+-]+) ms")
steps = round(total_ms / ms)
simulated = last(r"Total number: Time step size: ([0-9.eE+-]+)")
iterations = last(r"Average number: DFSPH - iterations: ([0-9.eE+-]+)") if solver == "dfsph" else 0.0
div_iterations = last(r"Average number: DFSPH - iterationsV: ([0-9.eE+-]+)") if solver == "dfsph" else 0.0
# Exported densities: frame 1 is written after the first step, frame k + 1 after the first
# step past k x sample, so frames 2.. are the samples Ferro takes.
def frame(p):
    return int(re.search(r"_(\d+)\.vtk$", p).group(1))
files = sorted(glob.glob(os.path.join(d, "vtk", "ParticleData_Fluid_*.vtk")), key=frame)[1:]
if not files:
    sys.exit("no exported frames in %s/vtk" % d)
errors, particles = [], 0
for p in files:
    data = open(p, "rb").read()
    m = re.search(rb"\ndensity 1 (\d+) (float|double)\n", data)
    if not m:
        sys.exit("%s: no density field" % p)
    particles = int(m.group(1))
    a = array("f" if m.group(2) == b"float" else "d")
    a.frombytes(data[m.end():m.end() + particles * a.itemsize])
    a.byteswap()  # VTK legacy binary is big-endian
    errors.append(sum(max(0.0, rho / rho0 - 1) for rho in a) / particles)
    os.remove(p)
print(steps, ms, steps * ms / 1e3 / simulated, iterations, particles, 100 * sum(errors) / len(errors), cpu, div_iterations)
PY
}

declare -A best
for ((r = 1; r <= repeat; ++r)); do
  for solver in wcsph dfsph; do
    echo "bench-peer.sh: run $r/$repeat, $solver: Ferro" >&2
    [[ "${PEER_REUSE:-0}" == 1 && -s "$work/ferro_$solver.txt" ]] || ferro_run "$solver" > "$work/ferro_$solver.txt"
    grep '^scene:' "$work/ferro_$solver.log" > "$work/scene.txt" || die 3 "no scene line in $work/ferro_$solver.log"
    read -r f_steps f_ms f_wall f_iter f_err f_rho f_cpu f_div < "$work/ferro_$solver.txt"
    dt="$(awk -v s="$(seconds_for "$solver")" -v n="$f_steps" 'BEGIN { printf "%.9g", s / n }')"
    peer_scene "$solver" "$dt"
    echo "bench-peer.sh: run $r/$repeat, $solver: SPlisHSPlasH" >&2
    [[ "${PEER_REUSE:-0}" == 1 && -s "$work/peer_$solver.txt" ]] || peer_run "$solver" > "$work/peer_$solver.txt"
    read -r p_steps p_ms p_wall p_iter p_particles p_rho p_cpu p_div < "$work/peer_$solver.txt"
    [[ "$p_particles" == "$(scene_value particles)" ]] ||
      die 3 "SPlisHSPlasH made $p_particles particles, Ferro $(scene_value particles): the scenes differ"
    # Keep each code's fastest run (least disturbed by other load on the machine).
    if [[ -z "${best[ferro_$solver]:-}" ]] || awk -v a="$f_ms" -v b="${best[ferro_$solver]%% *}" 'BEGIN { exit !(a < b) }'; then
      best[ferro_$solver]="$f_ms $f_steps $f_wall $f_iter $f_err $f_rho $dt $f_cpu ${f_div:-0}"
    fi
    if [[ -z "${best[peer_$solver]:-}" ]] || awk -v a="$p_ms" -v b="${best[peer_$solver]%% *}" 'BEGIN { exit !(a < b) }'; then
      best[peer_$solver]="$p_ms $p_steps $p_wall $p_iter $p_rho $p_cpu ${p_div:-0}"
    fi
  done
done

particles="$(scene_value particles)"
tol_percent="$(awk -v t="$(scene_value density_tol)" 'BEGIN { printf "%g", 100 * t }')"
csv="$out/peer.csv"
{
  echo "setting,code,solver,particles,threads,simulated_s,steps,mean_dt_ms,ms_per_step,wall_s_per_sim_s,iterations_per_step,solver_density_error_percent,mean_density_error_percent,density_tolerance_percent,ms_ratio_to_ferro,ratio_to_ferro,cpu_s_per_sim_s,cpu_ratio_to_ferro,search_ms_per_step,reference,divergence_iterations_per_step,solve_iterations_ratio_to_ferro"
  for solver in wcsph dfsph; do
    label="$(tr a-z A-Z <<< "$solver")"
    read -r f_ms f_steps f_wall f_iter f_err f_rho dt f_cpu f_div <<< "${best[ferro_$solver]}"
    read -r p_ms p_steps p_wall p_iter p_rho p_cpu p_div <<< "${best[peer_$solver]}"
    tol="$([[ $solver == dfsph ]] && echo "$tol_percent" || echo "")"
    # SPlisHSPlasH's own timer of its neighbour search (CompactNSearch), part of ms_per_step.
    p_search="$(awk '/Average time: neighborhood_search:/ { v = $4 } END { print v }' "$work/peer_$solver/stdout.log")"
    awk -v OFS=, -v s="$(seconds_for "$solver")" -v n="$particles" -v th="$threads" -v L="$label" -v tol="$tol" \
      -v fms="$f_ms" -v fs="$f_steps" -v fw="$f_wall" -v fi="$f_iter" -v fe="$f_err" -v fr="$f_rho" \
      -v pms="$p_ms" -v ps="$p_steps" -v pw="$p_wall" -v pi="$p_iter" -v pr="$p_rho" -v fc="$f_cpu" -v pc="$p_cpu" -v psearch="$p_search" -v fd="$f_div" -v pd="$p_div" 'BEGIN {
        fwall = fs * fms / 1e3 / s   # from the step times, as for SPlisHSPlasH
        print "Ferro " L, "Ferro", L, n, th, s, fs, sprintf("%.4f", 1e3 * s / fs), sprintf("%.2f", fms), sprintf("%.1f", fwall),
              sprintf("%.1f", fi), sprintf("%.4f", fe), sprintf("%.4f", fr), tol, "1.00", "1.00", sprintf("%.1f", fc / s), "1.00", "", "itself",
              sprintf("%.1f", fd), (fi + fd > 0 ? "1.00" : "")
        print "SPlisHSPlasH " L, "SPlisHSPlasH", L, n, th, s, ps, sprintf("%.4f", 1e3 * s / ps), sprintf("%.2f", pms), sprintf("%.1f", pw),
              sprintf("%.1f", pi), "", sprintf("%.4f", pr), tol, sprintf("%.2f", pms / fms), sprintf("%.2f", pw / fwall),
              sprintf("%.1f", pc / s), sprintf("%.2f", pc / fc), psearch == "" ? "" : sprintf("%.1f", psearch),
              "Ferro " L " in the same run", sprintf("%.1f", pd), (fi + fd > 0 ? sprintf("%.2f", (pi + pd) / (fi + fd)) : "")
      }'
  done
} > "$csv"

# The Markdown section.
col() { awk -F, -v row="$1" -v name="$2" 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  $1 == row { print $c[name] }' "$csv"; }
{
  echo "## Peer comparison: SPlisHSPlasH and Ferro on the same dam break"
  echo
  echo "Both codes ran bench-sim's dam break ($particles particles, 2.5 mm spacing, 0.32 x 0.08 x 0.2 m"
  echo "box, water, no surface tension) from t = 0 for $seconds simulated seconds (WCSPH) and $dfsph_seconds (DFSPH) on $threads threads, one"
  echo "after the other per solver; the fastest of $repeat run(s) each. Ratios are SPlisHSPlasH over"
  echo "Ferro (below 1: SPlisHSPlasH is faster); absolute times vary with the load of this shared"
  echo "machine. Made by \`scripts/bench-peer.sh\` (settings and what could not be matched: its header)"
  echo "on $(date -u +%F) at Ferro commit $(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown) with SPlisHSPlasH $peer_version."
  [[ -z "${PEER_BUILD_NOTE:-}" ]] || echo "SPlisHSPlasH build: $PEER_BUILD_NOTE"
  echo
  echo "| code | solver | steps | ms/step | wall s per sim s | iterations/step | density error % (measured) | ratio ms/step | ratio wall s/sim s | ratio CPU s |"
  echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $2, $3, $7, $9, $10, $11, $13, $15, $16, $18 }' "$csv"
  echo
  echo "- DFSPH at the same tolerance ($tol_percent % mean density error): SPlisHSPlasH takes"
  echo "  $(col "SPlisHSPlasH DFSPH" ratio_to_ferro)x Ferro's wall time per simulated second ($(col "SPlisHSPlasH DFSPH" ms_ratio_to_ferro)x per step; $(col "SPlisHSPlasH DFSPH" steps) steps"
  echo "  against $(col "Ferro DFSPH" steps), $(col "SPlisHSPlasH DFSPH" iterations_per_step) against $(col "Ferro DFSPH" iterations_per_step) density iterations per step, and"
  echo "  $(col "SPlisHSPlasH DFSPH" divergence_iterations_per_step) against $(col "Ferro DFSPH" divergence_iterations_per_step) divergence iterations: Ferro does $(awk -v r="$(col "SPlisHSPlasH DFSPH" solve_iterations_ratio_to_ferro)" 'BEGIN { printf "%.2f", 1 / r }')x SPlisHSPlasH's solver iterations a step); measured mean"
  echo "  compression $(col "SPlisHSPlasH DFSPH" mean_density_error_percent) % against Ferro's $(col "Ferro DFSPH" mean_density_error_percent) % (Ferro's solver residual: $(col "Ferro DFSPH" solver_density_error_percent) %)."
  echo "- WCSPH with the same stiffness and the same time step: SPlisHSPlasH takes"
  echo "  $(col "SPlisHSPlasH WCSPH" ratio_to_ferro)x Ferro's wall time per simulated second; mean compression"
  echo "  $(col "SPlisHSPlasH WCSPH" mean_density_error_percent) % against $(col "Ferro WCSPH" mean_density_error_percent) %. Ferro keeps a Verlet skin (a search every"
  echo "  few steps); SPlisHSPlasH searches every step."
  echo "- SPlisHSPlasH's neighbour search (CompactNSearch, every step) takes $(col "SPlisHSPlasH WCSPH" search_ms_per_step) of its $(col "SPlisHSPlasH WCSPH" ms_per_step) ms"
  echo "  per WCSPH step and $(col "SPlisHSPlasH DFSPH" search_ms_per_step) of $(col "SPlisHSPlasH DFSPH" ms_per_step) ms per DFSPH step."
  echo "- Processor time of the whole processes (set-up and output included, less disturbed by other"
  echo "  load): SPlisHSPlasH over Ferro $(col "SPlisHSPlasH WCSPH" cpu_ratio_to_ferro)x with WCSPH, $(col "SPlisHSPlasH DFSPH" cpu_ratio_to_ferro)x with DFSPH."
  echo "- Same start: each code's block at its own rest density. SPlisHSPlasH's particle volume is"
  echo "  0.8 d^3 (fixed in its fluid model), so it gets Ferro's 32 x 32 x 40 lattice at 0.928 d from a"
  echo "  particle file (its own blocks at d start 20 % under-dense and need no pressure for ~20 ms)."
  echo "- Not matched: its fluid has 0.8 of Ferro's volume and ~1.25x Ferro's neighbours per particle;"
  if [[ "$ferro_native" == 1 ]]; then
    echo "  both are built for this processor (-march=native: SPlisHSPlasH's AVX kernels, Ferro's"
    echo "  FERRO_NATIVE=ON); its threads are OpenMP (passive waiting) against Ferro's TBB."
  else
    echo "  it is built with -march=native (AVX2 kernels), Ferro for generic"
    echo "  x86-64 (SSE2), its pressure sweeps picked at run time ($ferro_sweeps copy here, the same"
    echo "  bits as the generic one); its threads are OpenMP (passive waiting) against Ferro's TBB, and OpenMP"
    echo "  suffers more on this oversubscribed machine."
  fi
} > "$out/peer.md"

if [[ -x "$root/scripts/bench/plot.sh" ]]; then
  "$root/scripts/bench/plot.sh" "$csv" wall_s_per_sim_s mean_density_error_percent "$out/peer.png" \
    "Dam break, $particles particles: wall s per simulated s against measured density error" ||
    echo "bench-peer.sh: plot failed (the CSV and Markdown are written)" >&2
fi
echo "bench-peer.sh: wrote $csv and $out/peer.md" >&2
