#!/usr/bin/env bash
# slurm.sh: the frame stages of a shot on Slurm with 1 and 2 workers (a one-node cluster of
# this machine, scripts/slurm/local-cluster.sh): how their wall time falls with the workers.
#
#   scripts/bench/slurm.sh [OUT_DIR]                          # the 40,960-particle shot
#   BENCH_SLURM_CASE=million scripts/bench/slurm.sh [OUT_DIR] # the million-particle shot
#
# Cases:
#   fig9     examples/paper_fig9_approach.toml without its pre-roll, frames 0..11 (spikes on),
#            simulated once locally first (make prepare), so that only the frame array is timed.
#   million  examples/million_dish.toml (1,000,000 particles) with the conjugate-gradient density
#            solve, frames 0..5, submitted whole to the cluster first (simulation job, frame
#            array, video: scripts/shot.sh --slurm) and timed from submission until the queue
#            is empty; ~45 min on 2 cores, most of it the simulation. BENCH_SLURM_SHOT=DIR
#            keeps the shot in DIR; a DIR whose whole shot ran before (DIR/bench-e2e-seconds
#            holds its time) is reused: only the array is timed again.
# Then for each setting the frames' files are deleted and the array submitted again:
#   1 worker x 1 core   (--max-parallel 1 --frame-cpus 1)
#   2 workers x 1 core  (--max-parallel 2 --frame-cpus 1)
#   1 worker x 2 cores  (--max-parallel 1 --frame-cpus 2: the stages' own threads instead)
# Wall time: from submission until the queue is empty (the local cluster keeps no accounting,
# so there is no sacct CPU time). Writes OUT_DIR/slurm-CASE.csv, the sbatch lines of the
# submission to OUT_DIR/slurm-CASE-sbatch.txt, and OUT_DIR/slurm.md from every case's CSV
# (BENCH_SLURM_REPORT_ONLY=1: only that, from the CSVs already there).
# Exit codes: 2 bad arguments, 3 a run failed, 4 Slurm or executables missing.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init slurm "$@"
report_only="${BENCH_SLURM_REPORT_ONLY:-0}"   # 1: only write slurm.md again from the CSVs in OUT_DIR
[[ $report_only == 1 ]] || bench_need ferro-sim ferro-surface ferro-spikes ferro-pov
[[ $report_only == 1 ]] || command -v sbatch >/dev/null || bench_die 4 "Slurm is not installed (scripts/install-deps.sh --with-slurm)"

case_name="${BENCH_SLURM_CASE:-fig9}"
case "$case_name" in
  fig9) scene="$root/examples/paper_fig9_approach.toml"; last=11; sets=(--set shot.preroll=0) ;;
  million) scene="$root/examples/million_dish.toml"; last=5; sets=() ;;
  *) bench_die 2 "BENCH_SLURM_CASE must be fig9 or million (got '$case_name')" ;;
esac
frames=$((last + 1))

if [[ $report_only != 1 ]]; then
cluster="$(mktemp -d /tmp/ferro-bench-slurm.XXXXXX)"
trap '"$root/scripts/slurm/local-cluster.sh" stop "$cluster" || true; rm -rf "$cluster" "$work"' EXIT
eval "$("$root/scripts/slurm/local-cluster.sh" start "$cluster")"
export FERRO_BIN="$bin"

# wait_queue: until the queue is empty, at most 4 hours (a held array whose simulation job
# Slurm killed would otherwise wait for ever: held jobs' time limits do not run).
wait_queue() {
  local t0=$SECONDS
  while [[ -n "$(squeue -h -o %i)" ]]; do
    (( SECONDS - t0 < 14400 )) || { scancel --user="$(id -un)" 2>/dev/null || true; bench_die 3 "the queue did not empty in 4 hours"; }
    sleep 2
  done
}

shot="${BENCH_SLURM_SHOT:-$work/shot}"
submit() { "$root/scripts/shot.sh" "$scene" "$shot" --max-frames "$last" ${sets[@]+"${sets[@]}"} "$@"; }
e2e=""
if [[ $case_name == fig9 ]]; then
  bench_note "simulating frames 0..$last locally"
  submit --no-run 2> /dev/null
  make -C "$shot" --no-print-directory -s prepare > "$work/prepare.log" 2>&1 ||
    { tail -5 "$work/prepare.log" >&2; bench_die 3 "simulation failed"; }
elif [[ -f "$shot/bench-e2e-seconds" && -f "$shot/particles/particles_$(printf %04d "$last").ply" ]]; then
  e2e="$(cat "$shot/bench-e2e-seconds")"
  bench_note "reusing the shot in $shot (its whole-shot submission took $e2e s)"
else
  bench_note "submitting the whole shot (frames 0..$last) to the cluster"
  start="$(date +%s.%N)"
  res="$(submit --slurm 2> "$work/submit.log")" || { cat "$work/submit.log" >&2; bench_die 3 "submission failed"; }
  wait_queue
  e2e="$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.0f", b - a }')"
  [[ -f "$shot/png/frame_$(printf %04d "$last").png" ]] || bench_die 3 "the shot did not finish (see $shot/logs)"
  echo "$e2e" > "$shot/bench-e2e-seconds"
  # The sbatch lines of that submission, and what a second one of the finished shot would send.
  { cat "$work/submit.log"
    echo "# a second submission of the finished shot (--dry-run): no simulation job and no frame task; the video job is always sent, its make finds shot.mp4 up to date"
    submit --slurm --dry-run 2>&1 > /dev/null; } > "$out/slurm-$case_name-sbatch.txt"
  bench_note "the whole shot: $e2e s"
fi

# The million's simulation under Slurm, frame by frame (each frame's time: when it was
# published after the one before; steps and density solves at the cap from its header),
# against the same scene at 40,960 particles run here with either density iteration: the cost
# a particle and step, and a particle and simulated second, over the frames whose density
# solve converged (frames from the cold fill end at the cap with CG; a run that never
# converges is timed over its frames after the first, all at the cap).
if [[ $case_name == million ]]; then
  bench_note "the same scene at 40,960 particles, frames 0..$last, 2 threads, Jacobi and CG"
  commit="$(git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  for it in jacobi cg; do
    "$bin/ferro-sim" "$scene" --out "$work/small-$it" --max-frames "$last" --threads 2 --quiet \
      --set fluid.block.0.count=40960 --set sim.pressure_iteration="$it" 2> "$work/small-$it.log" ||
      { tail -3 "$work/small-$it.log" >&2; bench_die 3 "ferro-sim (40,960, $it) failed"; }
  done
  python3 - "$out/slurm-million-sim.csv" "$last" "1000000:cg:$shot/particles:Slurm job (2 cores) at $commit" \
      "40960:jacobi:$work/small-jacobi:ferro-sim --threads 2 at $commit" "40960:cg:$work/small-cg:ferro-sim --threads 2 at $commit" <<'PY'
import os, sys
out, last = sys.argv[1], int(sys.argv[2])
def header(path):
    h = {}
    with open(path, 'rb') as f:
        for line in f.read(8192).split(b'\n'):
            if line.startswith(b'comment '):
                k, _, v = line[8:].decode().partition(' ')
                h[k] = v
            if line == b'end_header': break
    return h
rows = ["particles,iteration,frames,steps_per_frame,s_per_frame,us_per_particle_step,s_per_particle_and_simulated_s,capped_frames,reference"]
for spec in sys.argv[3:]:
    n, it, d, ref = spec.split(':', 3)
    n = int(n)
    f = lambda i: os.path.join(d, 'particles_%04d.ply' % i)
    fps = float(header(f(0))['fps'])
    capped = [i for i in range(1, last + 1) if int(header(f(i))['density_solve_at_cap'].split()[0]) > 0]
    good = [i for i in range(1, last + 1) if i not in capped]
    if not good:  # never converged: its frames after the first, at the cap
        good = list(range(2, last + 1))
    secs = sum(os.stat(f(i)).st_mtime - os.stat(f(i - 1)).st_mtime for i in good)
    steps = sum(int(header(f(i))['solver_steps']) for i in good)
    capped = [str(i) for i in capped]
    k = len(good)
    rows.append("%d,%s,%s,%.0f,%.3g,%.3g,%.3g,%s,%s" % (n, it, ' '.join(map(str, good)), steps / k, secs / k,
                1e6 * secs / (steps * n), secs / k * fps / n, ' '.join(capped) or 'none', ref))
open(out, 'w').write('\n'.join(rows) + '\n')
PY
fi

csv="$out/slurm-$case_name.csv"
echo "setting,workers,cores_per_task,frames,wall_s,speedup,reference" > "$csv"
[[ -n "$e2e" ]] && echo "whole shot (simulation + array + video),1,2,$frames,$e2e,,submission" >> "$csv"
base=""
for setting in "1 1" "2 1" "1 2"; do
  read -r workers cores <<< "$setting"
  rm -rf "$shot"/{surface,spiky,png,logs} "$shot"/shot/mesh_*.inc "$shot"/shot/magnets_*.inc
  start="$(date +%s.%N)"
  res="$(submit --slurm --max-parallel "$workers" --frame-cpus "$cores" 2> "$work/submit.log")" ||
    { cat "$work/submit.log" >&2; bench_die 3 "submission failed"; }
  [[ "$res" == *"tasks=0-$last"* ]] || bench_die 3 "expected tasks 0-$last, got: $res"
  wait_queue
  end="$(date +%s.%N)"
  [[ -f "$shot/png/frame_$(printf %04d "$last").png" ]] || bench_die 3 "the array did not finish (see $shot/logs)"
  wall="$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')"
  [[ -z "$base" ]] && base="$wall"
  speedup="$(awk -v a="$base" -v b="$wall" 'BEGIN { printf "%.2f", a / b }')"
  bench_note "$workers worker(s) x $cores core(s): $wall s"
  echo "$workers x $cores,$workers,$cores,$frames,$wall,$speedup,1 x 1" >> "$csv"
done

fi

# The report section from every case measured so far.
rows() { tail -n +2 "$1" | awk -F, '{ printf "| %s | %s | %s |\n", $1, $5, ($6 == "" ? "" : $6) }'; }
{
  cat <<'MD'
## Slurm: the frame stages with 1 and 2 workers

What ran: `scripts/bench/slurm.sh` on a one-node cluster of this 2-core machine
(scripts/slurm/local-cluster.sh), the frame array (surface, spikes, export, render of each
frame: `scripts/shot.sh --slurm`) timed from submission until the queue is empty.
MD
  if [[ -f "$out/slurm-fig9.csv" ]]; then
    cat <<'MD'

**40,960 particles** (examples/paper_fig9_approach.toml without its pre-roll, frames 0..11,
simulated once before):

| setting (workers x cores a task) | wall s | speed-up over 1 x 1 |
| --- | --- | --- |
MD
    rows "$out/slurm-fig9.csv"
  fi
  if [[ -f "$out/slurm-million.csv" ]]; then
    cat <<'MD'

**1,000,000 particles** (examples/million_dish.toml, `sim.pressure_iteration = "cg"`, frames
0..5; `BENCH_SLURM_CASE=million`). First the whole shot submitted as a user would: the
simulation job, the frame array held until each frame is published, the video; on one 2-core
node the array's tasks wait for the simulation's cores. Then the array alone:

| setting (workers x cores a task) | wall s | speed-up over 1 x 1 |
| --- | --- | --- |
MD
    rows "$out/slurm-million.csv"
    if [[ -f "$out/slurm-million-sim.csv" ]]; then
      cat <<'MD'

The simulation job against the same scene at 40,960 particles (2 threads here), over the
frames whose density solve converged (each frame's time: when it was published after the one
before; CG from the cold fill ends at its iteration cap in the frames listed as capped):

| particles | density iteration | frames timed | steps a frame | s a frame | µs a particle and step | s a particle and simulated s | capped frames | run |
| --- | --- | --- | --- | --- | --- | --- | --- | --- |
MD
      tail -n +2 "$out/slurm-million-sim.csv" | awk -F, '{ printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9 }'
      awk -F, 'NR == 2 { m = $7; ms = $4; mu = $6 } NR > 2 && (best == "" || $7 < best) { best = $7; bs = $4; bu = $6; bi = $2 }
        END { printf "\nThe million with CG against the 40,960 with its cheaper iteration (%s): **%.2fx** a particle and\n", bi, m / best
              printf "simulated second (Jacobi at a million, million.md: 3.61x), of which %.2fx a particle and step and\n", mu / bu
              printf "%.2fx the steps a simulated second.\n", ms / bs }' "$out/slurm-million-sim.csv"
    fi
    if [[ -f "$out/slurm-million-sim.csv" ]]; then
      awk -F, 'NR == FNR && FNR == 2 { S = $5 } NR != FNR && $1 == "1 x 1" { F = $5 / $4 }
        END { printf "\nFor this shot: a frame task takes F = %.0f s on one core (the 1 x 1 array over its frames), the\n", F
              printf "simulation S = %.0f s a frame once converged: one core of frame tasks keeps up with the\n", S
              printf "simulation (W = %.2f would do), so on any cluster the million shot is bound by its one\n", F / S
              printf "sequential simulation job, about %.1f h for its 61 frames (plus the first frames from the cold fill).\n", 61 * S / 3600
              printf "These frames have the magnet far (no spikes); with spikes over the dish a frame costs about\n"
              printf "37 CPU s (million.md, the near frame), still under S. Only a re-render (a new look, the\n"
              printf "simulation kept) is bound by the frame stages: 61 F / W, until the file server is: a frame\n"
              printf "task reads or writes ~110 MB at a million (particles 26 MB, surface and spiky meshes 22 MB\n"
              printf "each, includes ~40 MB), so about %.0f tasks in flight fill a 1 GbE server (~110 MB/s).\n", F * 110 / 110 }' \
        "$out/slurm-million-sim.csv" "$out/slurm-million.csv"
    fi
    if [[ -f "$out/slurm-million-sbatch.txt" ]]; then
      echo
      echo 'The sbatch lines Ferro generated for it (`scripts/shot.sh ... --slurm --dry-run`):'
      echo
      echo '```'
      cat "$out/slurm-million-sbatch.txt"
      echo '```'
    fi
  fi
  cat <<'MD'

The model for N machines of c cores: the simulation is one sequential job (its time is the
shot's floor: S seconds a simulated second, from the million-particle table), the frames are
independent tasks of F seconds each that start as their frames are published. With W = N c
tasks in flight the frame stages take about max(F x frames / W, the simulation's time + F):
they keep up with the simulation once W > F / (the simulation's time a frame). The shared file
system carries each frame's particle file once (read by surface and spikes), its meshes and
its PNG: (particles + surface + spiky + includes + PNG) bytes a frame x W / F bytes a second,
against the file server's bandwidth; at a million particles (million.md) that limit comes
before the cores do.
MD
} > "$out/slurm.md"
bench_note "wrote $out/slurm.md${csv:+ and $csv}"
