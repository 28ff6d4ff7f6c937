#!/usr/bin/env bash
# submit.sh OUTDIR FIRST LAST [options] [-- SBATCH_OPTION...]: submits a shot that
# scripts/shot.sh has set up in OUTDIR (its Makefile) to Slurm, as jobs that depend on each
# other. shot.sh --slurm calls it; it can be run again by hand.
#
#   simulation   one job (if the particles are missing or stale by make's rule), --requeue:
#                after a node failure or preemption it resumes from its last complete frame
#                (scripts/slurm/sim-job.sh); log OUTDIR/logs/slurm/sim.out
#   frames       one array, a task per frame that is missing or stale (all of FIRST..LAST
#                while the simulation is to run), submitted held; the simulation job
#                releases task f once frame f's particle file is complete, so meshing
#                overlaps simulating (scripts/slurm/frame-job.sh); logs
#                OUTDIR/logs/<stage>/frame_NNNN.log
#   video        one job after every task succeeded (when ffmpeg is there and FIRST..LAST is
#                the whole shot); log OUTDIR/logs/slurm/video.out
# A second submission runs only what is missing or stale, by the same rule as make (each
# task runs the shot's own make rules). Prints the job ids and the sbatch lines it ran.
#
# Resources come from the shot's size (ferro-sim --print-size: particles, frames) and the
# costs measured in tests/bench/report (see `cost model` below); override them with
#   --sim-cpus N --sim-mem MB --sim-time MIN --frame-cpus N --frame-mem MB --frame-time MIN
#   --max-parallel K    at most K frame tasks at once (sbatch --array=...%K)
#   --dry-run           print the sbatch lines, submit nothing
# SBATCH_OPTION words after `--` go to every sbatch (partition, account, qos, ...).
# Exit codes: 2 bad arguments, 4 no Makefile in OUTDIR or no sbatch, 1 a submission failed.
set -euo pipefail
# --help prints the comment above (everything before `set -e`).
if [[ "${1:-}" == "--help" || "${1:-}" == "-h" ]]; then sed -n '2,/^set -e/{/^set -e/d;s/^# \{0,1\}//;p}' "$0"; exit 0; fi
here="$(cd "$(dirname "$0")" && pwd)"
die() { echo "submit.sh: error: $1" >&2; exit "${2:-2}"; }

[[ $# -ge 3 ]] || die "usage: submit.sh OUTDIR FIRST LAST [options] [-- SBATCH_OPTION...]"
out="$1" first="$2" last="$3"; shift 3
[[ -f "$out/Makefile" ]] || die "$out/Makefile: missing (scripts/shot.sh writes it)" 4
out="$(cd "$out" && pwd)"
[[ "$first" =~ ^[0-9]+$ && "$last" =~ ^[0-9]+$ ]] && (( first <= last )) || die "FIRST..LAST must be frame numbers, FIRST <= LAST (got $first..$last)"
sim_cpus="" sim_mem="" sim_time="" frame_cpus="" frame_mem="" frame_time="" max_parallel="" dry=0 sbatch_opts=()
number() { [[ "$2" =~ ^[1-9][0-9]*$ ]] || die "$1 needs a positive whole number (got '$2')"; echo "$2"; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --sim-cpus) sim_cpus="$(number "$1" "${2:-}")"; shift 2 ;;
    --sim-mem) sim_mem="$(number "$1" "${2:-}")"; shift 2 ;;
    --sim-time) sim_time="$(number "$1" "${2:-}")"; shift 2 ;;
    --frame-cpus) frame_cpus="$(number "$1" "${2:-}")"; shift 2 ;;
    --frame-mem) frame_mem="$(number "$1" "${2:-}")"; shift 2 ;;
    --frame-time) frame_time="$(number "$1" "${2:-}")"; shift 2 ;;
    --max-parallel) max_parallel="$(number "$1" "${2:-}")"; shift 2 ;;
    --dry-run) dry=1; shift ;;
    --) shift; sbatch_opts=("$@"); break ;;
    *) die "unknown option $1" ;;
  esac
done
command -v sbatch >/dev/null || [[ $dry == 1 ]] || die "sbatch not found: is this a Slurm login node? (scripts/install-deps.sh --with-slurm installs Slurm's client)" 4

# The shot's settings, from the Makefile shot.sh wrote.
var() { sed -n "s/^$1 := //p" "$out/Makefile"; }
SCENE="$(var SCENE)" FERRO_BIN="$(var FERRO_BIN)" SPIKES="$(var SPIKES)" MAX_FRAMES="$(var MAX_FRAMES)"
SETS="$(var SETS)" SHOT_FIRST="$(var SHOT_FIRST)" SHOT_LAST="$(var SHOT_LAST)"
[[ -n "$SCENE" && -x "$FERRO_BIN/ferro-sim" ]] || die "$out/Makefile does not name a scene and ferro-sim" 4
mkdir -p "$out/.slurm" "$out/logs/slurm"
cat > "$out/.slurm/job.env" <<ENV
# Written by scripts/slurm/submit.sh: what the shot's jobs need to know.
FERRO_BIN='$FERRO_BIN'
FERRO_SCRIPTS='$(cd "$here/.." && pwd)'
SCENE='$SCENE'
SETS='$SETS'
MAX_FRAMES='$MAX_FRAMES'
SPIKES='$SPIKES'
ENV

# ---- cost model ----------------------------------------------------------------------------
# Measured on the project's 2-core machine, in CPU seconds (tests/bench/report: million.md at
# 1,000,000 particles, scene_cost.csv and spikes_presets.csv at 10,240):
#   simulation  20 us a particle and step (1,000,000 particles with a magnet, the poured layer
#               settling: 10.5 s a step on 2 cores; 7 us at 10,240, whose layers are shallower),
#               1,400 steps a simulated second, the pre-roll included; memory: ferro-sim's own
#               estimate (--print-size bytes, 3 kB a particle; measured 2.4 kB at 1,000,000);
#   surface     8 us a particle (8 s at 1,000,000);
#   spikes      3 s plus 10 us a particle (10 s at 1,000,000 with 199 tips, 3 s at 10,240);
#   render      60 s a frame at the presets' 640 x 480 (14 s at 1,000,000 with the scene's own
#               settings; the final preset's antialiasing costs more);
#   memory      1 kB a particle for the per-frame stages (spikes: 890 MB at 1,000,000).
# A time limit is 3x the estimate on the cores asked for plus 10 minutes (a shared node, a
# slow file system); memory 1.5x plus 512 MB. Each can be overridden.
read -r -a size < <("$FERRO_BIN/ferro-sim" "$SCENE" --print-size ${MAX_FRAMES:+--max-frames "$MAX_FRAMES"} $SETS)
declare -A S; for w in "${size[@]}"; do S[${w%%=*}]="${w#*=}"; done
n="${S[particles]}" frames="${S[frames]}" fps="${S[fps]}" preroll="${S[preroll]}" bytes="${S[bytes]}"
sim_cpus="${sim_cpus:-$(( $(nproc) < 8 ? $(nproc) : 8 ))}"
frame_cpus="${frame_cpus:-$(( n > 500000 ? 2 : 1 ))}"
est() { awk "BEGIN { printf \"%d\", $1 }"; }
sim_seconds="$(est "20e-6 * $n * 1400 * ($frames / $fps + $preroll) / $sim_cpus")"
frame_seconds="$(est "(8e-6 * $n + ($SPIKES == 1 ? 3 + 10e-6 * $n : 0) + 60) / $frame_cpus")"
sim_time="${sim_time:-$(( (3 * sim_seconds) / 60 + 10 ))}"
frame_time="${frame_time:-$(( (3 * frame_seconds) / 60 + 10 ))}"
sim_mem="${sim_mem:-$(est "1.5 * $bytes / 1048576 + 512")}"
frame_mem="${frame_mem:-$(est "1.5 * 1000 * $n / 1048576 + 512")}"
echo "submit.sh: $n particles, frames $first..$last of $SHOT_FIRST..$SHOT_LAST; estimates: simulation ${sim_seconds} s on $sim_cpus cores, a frame ${frame_seconds} s on $frame_cpus" >&2

# ---- what is stale: make's own rule ----------------------------------------------------------
# The shot files first, here (every frame's render needs them; make also rewrites the stamps
# .scene/*.toml, and stops on a scene a stage cannot read).
make -s -C "$out" --no-print-directory shot/shot.pov shot/look.inc >/dev/null
sim=0
make -C "$out" --no-print-directory -q particles/.complete 2>/dev/null || sim=1
tasks=()
for ((f = first; f <= last; f++)); do
  if [[ $sim == 1 ]] || ! make -C "$out" --no-print-directory -q FIRST="$f" LAST="$f" frames 2>/dev/null; then tasks+=("$f"); fi
done
# An array spec from the frame list: runs of consecutive frames as A-B.
spec="$(printf '%s\n' "${tasks[@]}" | awk 'NR == 1 { a = b = $1; next } $1 == b + 1 { b = $1; next }
  { printf "%s%s,", a, (a == b ? "" : "-" b); a = b = $1 } END { if (NR) printf "%s%s", a, (a == b ? "" : "-" b) }')"

common=(--parsable --chdir="$out" "${sbatch_opts[@]}")
submit() { # name, then sbatch arguments
  local name="$1"; shift
  echo "sbatch $*" >> "$out/.slurm/sbatch.log"
  echo "  sbatch $*" >&2
  if [[ $dry == 1 ]]; then echo "DRY-$name"; return; fi
  sbatch "$@" || die "sbatch of the $name job failed" 1
}
: > "$out/.slurm/sbatch.log"
rm -f "$out/.slurm/frames.id"
# The frame array first (held while a simulation is to run), then the simulation job, which
# reads the array's id from .slurm/frames.id to release its tasks.
frames_id=""
if [[ ${#tasks[@]} -gt 0 ]]; then
  frames_id="$(submit frames "${common[@]}" --job-name=ferro-frames --array="$spec${max_parallel:+%$max_parallel}" \
    $([[ $sim == 1 ]] && echo --hold) --output="$out/logs/slurm/frame_%4a.out" --cpus-per-task="$frame_cpus" \
    --mem="$frame_mem" --time="$frame_time" "$here/frame-job.sh" "$out")"
  [[ $dry == 1 ]] || echo "$frames_id" > "$out/.slurm/frames.id"
fi
sim_id=""
if [[ $sim == 1 ]]; then
  sim_id="$(submit sim "${common[@]}" --job-name=ferro-sim --requeue --open-mode=append \
    --output="$out/logs/slurm/sim.out" --cpus-per-task="$sim_cpus" --mem="$sim_mem" --time="$sim_time" \
    "$here/sim-job.sh" "$out")"
fi
video_id=""
if [[ "$first" == "$SHOT_FIRST" && "$last" == "$SHOT_LAST" ]] && command -v ffmpeg >/dev/null; then
  video_id="$(submit video "${common[@]}" --job-name=ferro-video ${frames_id:+--dependency=afterok:$frames_id} \
    --kill-on-invalid-dep=yes --output="$out/logs/slurm/video.out" --cpus-per-task=1 --mem=1024 --time=30 \
    --wrap="make -C '$out' --no-print-directory SIM_ELSEWHERE=1 video")"
fi
echo "submit.sh: simulation ${sim_id:-up to date}, frames ${frames_id:-up to date}${frames_id:+ (tasks $spec)}, video ${video_id:-none}" >&2
echo "sim=${sim_id:-} frames=${frames_id:-} video=${video_id:-} tasks=${spec:-}"
