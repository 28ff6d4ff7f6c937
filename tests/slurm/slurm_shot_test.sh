#!/usr/bin/env bash
# A shot on a real Slurm cluster (issue 31): a one-node cluster of Debian's slurm-wlm and
# munge started in a temporary directory (scripts/slurm/local-cluster.sh), the shot
# submitted with scripts/shot.sh --slurm, and checked against a local make run of the same
# shot:
#   1. one frame task cancelled with scancel while it waits for its frame, and the
#      simulation job requeued mid-run (as on a node failure): the requeued job resumes after
#      the last frame it had written, and every other frame is made;
#   2. a second submission runs only the cancelled frame (the simulation is up to date);
#   3. the frames equal a local `make` run: meshes and includes bit for bit, particle files
#      bit for bit but for the header line naming the scene (frame-unchanged.sh), PNG pixels
#      (POV-Ray stamps its PNGs with the render date);
#   4. (issue 53) a second shot: a running frame task killed with SIGKILL, the node taken
#      down (scontrol update State=DOWN) and up again while the simulation runs, then the
#      same shot resubmitted until complete: its frames equal the local run too.
# Usage: slurm_shot_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR. Fails (never skips) when Slurm
# is not installed: scripts/install-deps.sh --with-slurm installs it, and CI runs this.
set -euo pipefail
src="$1" bin="$2" scratch="$3"
fail() { echo "FAIL: $*" >&2; exit 1; }
rm -rf "$scratch"
mkdir -p "$scratch"
# A short socket path: munge's Unix socket must fit in 108 bytes.
cluster="$(mktemp -d /tmp/ferro-slurm.XXXXXX)"
trap '"$src/scripts/slurm/local-cluster.sh" stop "$cluster" || true; rm -rf "$cluster"' EXIT
eval "$("$src/scripts/slurm/local-cluster.sh" start "$cluster")"
export FERRO_BIN="$bin"

# 2,000 particles over a weak magnet for 31 frames, of which frames 0..10 are made: the
# simulation takes several seconds, long enough to requeue it mid-run; spikes run (the scene
# has a magnet).
cat > "$scratch/shot.toml" <<'TOML'
[shot]
fps = 10
duration = 3.0

[[fluid.block]]
shape = "cylinder"
center = [0.0, 0.0, 0.0]
radius = 0.02
height = 0.005
count = 2000

[container]
type = "dish"
center = [0.0, 0.0, 0.0]
radius = 0.02
height = 0.01

[[magnets]]
position = [0.0, 0.0, -0.1]
moment = 0.01

[render]
width = 48
height = 36
camera_position = [0.0, -0.07, 0.045]
TOML
out="$scratch/slurm"

wait_jobs() { # until the queue is empty (timeout 600 s)
  for _ in $(seq 1200); do
    [[ -z "$(squeue -h -o %i)" ]] && return 0
    sleep 0.5
  done
  squeue; fail "jobs still queued after 600 s"
}
field() { sed -n "s/.*\\b$1=\\([^ ]*\\).*/\\1/p" <<< "$2"; }

# ---- 1. submit; cancel frame 2 while it is held; requeue the simulation mid-run -------------
res="$("$src/scripts/shot.sh" "$scratch/shot.toml" "$out" --frames 0:10 --slurm --max-parallel 2 2> "$scratch/submit1.err")" \
  || { cat "$scratch/submit1.err"; fail "first submission"; }
cat "$scratch/submit1.err"
sim="$(field sim "$res")" frames="$(field frames "$res")"
[[ -n "$sim" && -n "$frames" && "$(field tasks "$res")" == 0-10 ]] || fail "first submission: expected a simulation and tasks 0-10 (got: $res)"
grep -q -- "--requeue" "$out/.slurm/sbatch.log" || fail "the simulation job is not submitted with --requeue"
grep -q -- "--array=0-10%2 --hold" "$out/.slurm/sbatch.log" || fail "the frame array is not held: $(cat "$out/.slurm/sbatch.log")"
scancel "${frames}_2"
# Requeue once frame 3 is published and the simulation is still running.
for _ in $(seq 600); do
  [[ -f "$out/particles/particles_0003.ply" ]] && break
  sleep 0.1
done
[[ -f "$out/particles/particles_0003.ply" ]] || fail "frame 3 was never published"
[[ ! -f "$out/particles/particles_0030.ply" ]] || fail "the simulation ended before it could be requeued (make the scene longer)"
scontrol requeue "$sim"
# Slurm holds a requeued job back for two minutes (reason BeginTime) once it has left the
# node; an operator can let it go at once.
for _ in $(seq 300); do
  if [[ "$(squeue -h -j "$sim" -o %r 2>/dev/null)" == BeginTime ]]; then
    scontrol update JobId="$sim" StartTime=now
    break
  fi
  sleep 0.1
done
wait_jobs
cat "$out/logs/slurm/sim.out"
grep -q "restart 1" "$out/logs/slurm/sim.out" || fail "the simulation job did not run again after the requeue"
resumed="$(sed -n 's/.*holds frames up to \([0-9]*\).*/\1/p' "$out/logs/slurm/sim.out")"
[[ -n "$resumed" && "$resumed" -ge 3 && "$resumed" -lt 30 ]] || fail "the requeued simulation did not resume (frames it found: '${resumed}')"
grep -q "done: frames 0..30 published" "$out/logs/slurm/sim.out" || fail "the requeued simulation did not finish"
for f in 0 1 3 4 5 6 7 8 9 10; do
  tag="$(printf %04d "$f")"
  [[ -f "$out/png/frame_$tag.png" ]] || fail "frame $f: no PNG"
  for stage in surface spikes export render; do
    [[ -s "$out/logs/$stage/frame_$tag.log" ]] || fail "frame $f: no log of $stage"
  done
done
[[ ! -f "$out/png/frame_0002.png" ]] || fail "frame 2 was rendered although its task was cancelled"

# ---- 2. resubmission: only frame 2 ---------------------------------------------------------
res="$("$src/scripts/shot.sh" "$scratch/shot.toml" "$out" --frames 0:10 --slurm 2> "$scratch/submit2.err")" \
  || { cat "$scratch/submit2.err"; fail "second submission"; }
cat "$scratch/submit2.err"
[[ -z "$(field sim "$res")" && "$(field tasks "$res")" == 2 ]] || fail "resubmission: expected only frame 2 (got: $res)"
wait_jobs
[[ -f "$out/png/frame_0002.png" ]] || fail "the resubmission did not render frame 2"
res="$("$src/scripts/shot.sh" "$scratch/shot.toml" "$out" --frames 0:10 --slurm 2>/dev/null)"
[[ "$res" == "sim= frames= video= tasks=" ]] || fail "a third submission of a finished shot submitted: $res"

# ---- 3. the same as a local make run ---------------------------------------------------------
"$src/scripts/shot.sh" "$scratch/shot.toml" "$scratch/local" --frames 0:10 --no-video -j2 2> "$scratch/local.err" \
  || { cat "$scratch/local.err"; fail "local run"; }
for f in $(seq 0 10); do
  tag="$(printf %04d "$f")"
  "$src/scripts/frame-unchanged.sh" "$scratch/local/particles/particles_$tag.ply" "$out/particles/particles_$tag.ply" \
    || fail "frame $f: particles differ from the local run"
  for file in surface/surface_$tag.ply spiky/spiky_$tag.ply shot/mesh_$tag.inc shot/magnets_$tag.inc; do
    cmp -s "$scratch/local/$file" "$out/$file" || fail "$file differs from the local run"
  done
  python3 "$src/tests/tools/pngcheck.py" same "$scratch/local/png/frame_$tag.png" "$out/png/frame_$tag.png" \
    || fail "frame $f: PNG pixels differ"
done

# ---- 4. a running frame task killed, the node taken down and up, then resubmitted ---------------
# A second shot of the same scene: one frame task killed with SIGKILL while it runs; then,
# with the simulation running, the node goes down (its jobs die as on a node failure: the
# simulation, submitted with --requeue, is requeued) and comes back. Resubmitting the same
# shot fills in what failed; every frame then equals the local run.
out2="$scratch/slurm2"
res="$("$src/scripts/shot.sh" "$scratch/shot.toml" "$out2" --frames 0:10 --slurm --max-parallel 2 2> "$scratch/submit4.err")" \
  || { cat "$scratch/submit4.err"; fail "fourth submission"; }
sim="$(field sim "$res")" frames="$(field frames "$res")"
# The node goes down once frame 3 is published and the simulation still runs, and comes back.
for _ in $(seq 600); do
  [[ -f "$out2/particles/particles_0003.ply" ]] && break
  sleep 0.1
done
[[ -f "$out2/particles/particles_0003.ply" ]] || fail "node down: frame 3 was never published"
[[ ! -f "$out2/particles/particles_0030.ply" ]] || fail "the simulation ended before the node went down (make the scene longer)"
scontrol update NodeName=localhost State=DOWN Reason=ferro-test
# Its jobs end (the simulation requeued); the node takes RESUME once they have left it.
for _ in $(seq 300); do
  scontrol update NodeName=localhost State=RESUME 2> /dev/null && break
  sleep 0.2
done
sinfo -h -o %T | grep -qv down || fail "node down: the node did not come back"
# Then the first frame task seen running is killed with SIGKILL.
killed_task=""
for _ in $(seq 1200); do
  if [[ "$(squeue -h -j "$sim" -o %r 2> /dev/null)" == BeginTime ]]; then scontrol update JobId="$sim" StartTime=now; fi
  killed_task="$(squeue -h -j "$frames" -t RUNNING -o %i 2> /dev/null | head -n 1)"
  [[ -n "$killed_task" || -z "$(squeue -h -o %i)" ]] && break
  sleep 0.1
done
[[ -n "$killed_task" ]] && scancel --signal=KILL --full "$killed_task"
for _ in $(seq 1200); do
  if [[ "$(squeue -h -j "$sim" -o %r 2> /dev/null)" == BeginTime ]]; then scontrol update JobId="$sim" StartTime=now; fi
  [[ -z "$(squeue -h -o %i)" ]] && break
  sleep 0.5
done
wait_jobs
down_restarts="$(grep -c "restart" "$out2/logs/slurm/sim.out" || true)"
for attempt in 1 2 3; do
  res="$("$src/scripts/shot.sh" "$scratch/shot.toml" "$out2" --frames 0:10 --slurm 2> "$scratch/submit5.err")" \
    || { cat "$scratch/submit5.err"; fail "resubmission after the node came back"; }
  [[ "$res" == "sim= frames= video= tasks=" ]] && break
  echo "after the node came back, resubmitted: $res"
  for _ in $(seq 300); do
    if [[ -n "$(field sim "$res")" && "$(squeue -h -j "$(field sim "$res")" -o %r 2> /dev/null)" == BeginTime ]]; then
      scontrol update JobId="$(field sim "$res")" StartTime=now
    fi
    [[ -z "$(squeue -h -o %i)" ]] && break
    sleep 0.5
  done
  wait_jobs
done
[[ "$res" == "sim= frames= video= tasks=" ]] || fail "the shot is not complete after three resubmissions: $res"
for f in $(seq 0 10); do
  tag="$(printf %04d "$f")"
  "$src/scripts/frame-unchanged.sh" "$scratch/local/particles/particles_$tag.ply" "$out2/particles/particles_$tag.ply" \
    || fail "node down: frame $f: particles differ from the local run"
  for file in surface/surface_$tag.ply spiky/spiky_$tag.ply shot/mesh_$tag.inc shot/magnets_$tag.inc; do
    cmp -s "$scratch/local/$file" "$out2/$file" || fail "node down: $file differs from the local run"
  done
  python3 "$src/tests/tools/pngcheck.py" same "$scratch/local/png/frame_$tag.png" "$out2/png/frame_$tag.png" \
    || fail "node down: frame $f: PNG pixels differ"
done
[[ -n "$killed_task" ]] || fail "node down: no frame task ran after the node came back"
echo "Slurm faults: frame task $killed_task killed while running, node down and up with the simulation running (its log: $down_restarts restart lines), resubmitted until complete ($attempt submissions): 11 frames equal the local run"
echo "PASS: Slurm shot: requeued simulation resumed after frame $resumed, cancelled frame 2 filled in alone, 11 frames equal the local run; a killed frame task and a node down and up survived"
