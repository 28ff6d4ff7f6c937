#!/usr/bin/env bash
# frame-job.sh OUTDIR: the body of one task of a shot's frame array on Slurm (submitted by
# submit.sh; the task id is the frame number).
#
# Makes the frame's files stage by stage with OUTDIR's own make rules (scripts/shot.mk), so
# a task does exactly what `make FIRST=f LAST=f frames` would: nothing for a frame that is
# up to date, only the stale stages otherwise. SIM_ELSEWHERE=1: the particle file comes from
# the simulation job, which released this task once the file was complete.
# Logs: OUTDIR/logs/<stage>/frame_NNNN.log, one file per frame and stage (Slurm's own
# output of the task goes to OUTDIR/logs/slurm/frame_NNNN.out).
# A stage that fails is tried again (FERRO_SLURM_RETRIES more times, default 1: a busy
# shared file system, a node that ran out of memory); then the task fails with its exit code.
set -uo pipefail
out="$1"
cd "$out" || exit 4
# shellcheck source=/dev/null
source .slurm/job.env
f="${SLURM_ARRAY_TASK_ID:?frame-job.sh runs as a Slurm array task}"
tag="$(printf %04d "$f")"
retries="${FERRO_SLURM_RETRIES:-1}"
threads="${SLURM_CPUS_PER_TASK:-1}"

stages=(surface)
[[ "$SPIKES" == 1 ]] && stages+=(spikes)
stages+=(export render)
declare -A target=(
  [surface]="surface/surface_$tag.ply" [spikes]="spiky/spiky_$tag.ply"
  [export]="shot/mesh_$tag.inc" [render]="png/frame_$tag.png")

for stage in "${stages[@]}"; do
  mkdir -p "logs/$stage"
  logf="logs/$stage/frame_$tag.log"
  attempt=0
  while :; do
    echo "frame-job: $(date +%H:%M:%S) job ${SLURM_ARRAY_JOB_ID:-?}_$f on $(hostname), attempt $((attempt + 1)): ${target[$stage]}" >> "$logf"
    make --no-print-directory SIM_ELSEWHERE=1 THREADS="$threads" FIRST="$f" LAST="$f" "${target[$stage]}" >> "$logf" 2>&1
    rc=$?
    [[ $rc == 0 ]] && break
    if (( attempt >= retries )); then
      echo "frame-job: frame $f: $stage failed (exit $rc) after $((attempt + 1)) attempts; see $out/$logf" >&2
      exit "$rc"
    fi
    attempt=$((attempt + 1))
    sleep 5
  done
done
echo "frame-job: frame $f done"
