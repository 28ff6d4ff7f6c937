#!/usr/bin/env bash
# slurm.sh: the frame stages of a shot on Slurm with 1 and 2 workers (a one-node cluster of
# this machine, scripts/slurm/local-cluster.sh): how their wall time falls with the workers.
#
#   scripts/bench/slurm.sh [OUT_DIR]
#
# The shot: examples/paper_fig9_approach.toml without its pre-roll, frames 0..11 (spikes on),
# simulated once locally first, so that only the frame array is timed. Then for each setting
# the frames' files are deleted and the array submitted (scripts/shot.sh --slurm):
#   1 worker x 1 core   (--max-parallel 1 --frame-cpus 1)
#   2 workers x 1 core  (--max-parallel 2 --frame-cpus 1)
#   1 worker x 2 cores  (--max-parallel 1 --frame-cpus 2: the stages' own threads instead)
# Wall time: from submission until the queue is empty (the local cluster keeps no accounting,
# so there is no sacct CPU time). Writes OUT_DIR/slurm.csv and OUT_DIR/slurm.md.
# Exit codes: 2 bad arguments, 3 a run failed, 4 Slurm or executables missing.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init slurm "$@"
bench_need ferro-sim ferro-surface ferro-spikes ferro-pov
command -v sbatch >/dev/null || bench_die 4 "Slurm is not installed (scripts/install-deps.sh --with-slurm)"

cluster="$(mktemp -d /tmp/ferro-bench-slurm.XXXXXX)"
trap '"$root/scripts/slurm/local-cluster.sh" stop "$cluster" || true; rm -rf "$cluster" "$work"' EXIT
eval "$("$root/scripts/slurm/local-cluster.sh" start "$cluster")"
export FERRO_BIN="$bin"

shot="$work/shot"
sets=(--set shot.preroll=0)
bench_note "simulating frames 0..11 locally"
"$root/scripts/shot.sh" "$root/examples/paper_fig9_approach.toml" "$shot" --max-frames 11 "${sets[@]}" --no-run 2> /dev/null
make -C "$shot" --no-print-directory -s prepare > "$work/prepare.log" 2>&1 || { tail -5 "$work/prepare.log" >&2; bench_die 3 "simulation failed"; }

csv="$out/slurm.csv"
echo "setting,workers,cores_per_task,frames,wall_s,speedup,reference" > "$csv"
base=""
for setting in "1 1" "2 1" "1 2"; do
  read -r workers cores <<< "$setting"
  rm -rf "$shot"/{surface,spiky,png,logs} "$shot"/shot/mesh_*.inc "$shot"/shot/magnets_*.inc
  start="$(date +%s.%N)"
  res="$("$root/scripts/shot.sh" "$root/examples/paper_fig9_approach.toml" "$shot" --max-frames 11 "${sets[@]}" \
          --slurm --max-parallel "$workers" --frame-cpus "$cores" 2> "$work/submit.log")" ||
    { cat "$work/submit.log" >&2; bench_die 3 "submission failed"; }
  [[ "$res" == *"tasks=0-11"* ]] || bench_die 3 "expected tasks 0-11, got: $res"
  for _ in $(seq 7200); do [[ -z "$(squeue -h -o %i)" ]] && break; sleep 0.5; done
  end="$(date +%s.%N)"
  [[ -f "$shot/png/frame_0011.png" ]] || bench_die 3 "the array did not finish (see $shot/logs)"
  wall="$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }')"
  [[ -z "$base" ]] && base="$wall"
  speedup="$(awk -v a="$base" -v b="$wall" 'BEGIN { printf "%.2f", a / b }')"
  bench_note "$workers worker(s) x $cores core(s): $wall s"
  echo "$workers x $cores,$workers,$cores,12,$wall,$speedup,1 x 1" >> "$csv"
done

cat > "$out/slurm.md" <<MD
## Slurm: the frame stages with 1 and 2 workers

What ran: \`scripts/bench/slurm.sh\`: examples/paper_fig9_approach.toml without its pre-roll
(40,960 particles), frames 0..11 simulated once, then the frame array (surface, spikes,
export, render of each frame: \`scripts/shot.sh --slurm\`) on a one-node cluster of this
2-core machine, from submission until the queue is empty.

| setting (workers x cores a task) | wall s | speed-up over 1 x 1 |
| --- | --- | --- |
$(tail -n +2 "$csv" | awk -F, '{ printf "| %s | %s | %s |\n", $1, $5, $6 }')

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
bench_note "wrote $csv and $out/slurm.md"
