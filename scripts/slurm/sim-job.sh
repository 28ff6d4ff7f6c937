#!/usr/bin/env bash
# sim-job.sh OUTDIR: the body of a shot's simulation job on Slurm (submitted by submit.sh).
#
# Runs ferro-sim into OUTDIR/particles.new/ and publishes each frame into OUTDIR/particles/
# as soon as its file is complete (ferro-sim writes a frame by rename, so a file that exists
# is whole), then releases that frame's held array task: meshing overlaps simulating.
#   - Publishing follows shot.mk's rule: a frame that holds the same bytes as the previous
#     run's (frame-unchanged.sh) keeps the previous file and its time, so its meshes and
#     render are not redone.
#   - particles.new/ holding frames of another scene (left by a failed or cancelled run before
#     the scene was edited) is removed first, so none of them is ever published.
#   - Requeued (node failure, preemption, scontrol requeue): the job starts again from the
#     top, ferro-sim --resume continues after the last complete frame in particles.new/, and
#     the frames published before are published again as no-ops.
#   - When ferro-sim fails, the frame tasks still held are cancelled (their frames do not
#     exist), which cancels the video job too (it depends on all of them); the frames
#     published so far stay, and so do the previous run's later ones.
#   - When it succeeds: frames past the shot's end left from a longer earlier run are
#     removed, particles/.complete is touched (make's mark of a finished simulation) and
#     particles.new/ goes.
# Reads OUTDIR/.slurm/job.env (written by submit.sh) and OUTDIR/.slurm/frames.id (the array
# job's id, once submitted).
set -uo pipefail
out="$1"
cd "$out" || exit 4
# shellcheck source=/dev/null
source .slurm/job.env
log() { echo "sim-job: $(date +%H:%M:%S) $*"; }

released=" "
array_id() { cat .slurm/frames.id 2>/dev/null || true; }
release() { # frame number
  local id; id="$(array_id)"
  [[ -n "$id" && "$released" != *" $1 "* ]] || return 0
  # Frames outside the array (not stale, or outside FIRST..LAST) are not tasks: no error.
  scontrol release "${id}_$1" 2>/dev/null || true
  released+="$1 "
}
published=" "
publish() { # particles.new/particles_NNNN.ply
  local new="$1" name="${1##*/}" old="particles/${1##*/}" f
  f="${name#particles_}"; f="${f%.ply}"; f="$((10#$f))"
  if [[ "$published" != *" $f "* ]]; then
    if ! { [[ -f "$old" ]] && "$FERRO_SCRIPTS/frame-unchanged.sh" "$old" "$new"; }; then
      ln -f "$new" "particles/.$name.tmp" && mv -f "particles/.$name.tmp" "$old"
    fi
    published+="$f "
  fi
  release "$f"
}
publish_all() {
  local f
  for f in particles.new/particles_*.ply; do [[ -e "$f" ]] && publish "$f"; done
}

mkdir -p particles particles.new
args=("$SCENE" --out particles.new --preroll-cache preroll.ply --quiet)
[[ -n "$MAX_FRAMES" ]] && args+=(--max-frames "$MAX_FRAMES")
# shellcheck disable=SC2206
sets=($SETS)
threads=()
[[ -n "${SLURM_CPUS_PER_TASK:-}" ]] && threads=(--threads "$SLURM_CPUS_PER_TASK")

log "job ${SLURM_JOB_ID:-?} (restart ${SLURM_RESTART_COUNT:-0}) on $(hostname): ferro-sim ${args[*]} ${sets[*]}"
# Resume only frames of this scene: particles.new/ left by a failed or cancelled run of an
# earlier version of the scene goes first, before any of its frames could be published.
# (ferro-sim --resume would refuse them too, but only after this job had published them.)
have="$(ls particles.new 2>/dev/null | sed -n 's/^particles_0*\([0-9][0-9]*\)\.ply$/\1/p' | sort -n | tail -1)"
if [[ -n "$have" ]]; then
  want="$("$FERRO_BIN/ferro-sim" "$SCENE" --print-size "${sets[@]}" | tr ' ' '\n' | sed -n 's/^scene_fingerprint=//p')"
  got="$(head -c 16384 "particles.new/particles_$(printf %04d "$have").ply" | sed -n 's/^comment scene_fingerprint //p' | head -1)"
  if [[ -z "$want" || "$got" != "$want" ]]; then
    log "particles.new/ holds frames of another scene ($got, this one is $want): starting over"
    rm -rf particles.new
    mkdir -p particles.new
  else
    log "particles.new/ holds frames up to $have: ferro-sim resumes after the last complete one"
  fi
fi
# --resume continues after the newest complete frame of particles.new/ (a requeued job), or
# starts when it is empty.
"$FERRO_BIN/ferro-sim" "${args[@]}" --resume "${threads[@]}" "${sets[@]}" &
pid=$!
while kill -0 "$pid" 2>/dev/null; do
  publish_all
  sleep 1
done
wait "$pid"; rc=$?
publish_all
if [[ $rc != 0 ]]; then
  log "ferro-sim failed (exit $rc): cancelling the frame tasks still waiting for their frames"
  id="$(array_id)"
  if [[ -n "$id" ]]; then
    squeue -h -r -j "$id" -t PD -o "%i %r" 2>/dev/null | awk '$2 ~ /Held/ { print $1 }' | xargs -r scancel
  fi
  exit "$rc"
fi
last="$(ls particles.new/particles_*.ply | sed 's/.*particles_0*\([0-9][0-9]*\)\.ply/\1/' | sort -n | tail -1)"
for f in particles/particles_*.ply; do
  [[ -e "$f" ]] || continue
  n="${f##*particles_}"; n="$((10#${n%.ply}))"
  (( n <= last )) || rm -f "$f"
done
touch particles/.complete
rm -rf particles.new
log "done: frames 0..$last published"
