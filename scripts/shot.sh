#!/usr/bin/env bash
# shot.sh: runs a whole shot: simulate, then per frame surface, spikes, POV-Ray export and
# render, then a video (shot.mp4) and a GIF (shot.gif) when ffmpeg is installed.
#
#   scripts/shot.sh SCENE.toml OUTDIR [--preset NAME] [--set KEY=VALUE]... [--frames A:B]
#                   [--max-frames N] [-j JOBS] [--no-video] [--no-run]
#                   [--slurm [SUBMIT_OPTION | SBATCH_OPTION]...]
#
# It writes OUTDIR/Makefile (see scripts/shot.mk) and runs make in OUTDIR, so a second run
# re-does only what changed (a scene section, the look, a deleted file), and
# `make -C OUTDIR -j2 FIRST=10 LAST=20` re-renders part of a shot by hand. ferro-spikes runs
# when it is built and the scene has [[magnets]]; otherwise the surface goes straight to
# ferro-pov.
#   --preset NAME     preview, final or large: the quality settings of scripts/presets.conf,
#                     chosen from the measured trade (tests/bench/report/README.md)
#   --set KEY=VALUE   override a scene key in every stage (after the preset's), e.g.
#                     --set render.width=480; repeatable
#   --frames A:B      render only frames A..B (the simulation still starts at frame 0)
#   --max-frames N    simulate and render only frames 0..N (a preview of a long shot)
#   -j JOBS           frames in flight (default: the number of cores)
#   --no-video        stop after the PNGs
#   --no-run          write OUTDIR/Makefile and stop (run make -C OUTDIR yourself)
#   --slurm ...       submit the shot to Slurm instead of running make here (last option:
#                     the words after it are scripts/slurm/submit.sh's options, such as
#                     --sim-cpus N, --frame-mem MB, --max-parallel K, --dry-run, and any
#                     other word is an option for every sbatch, e.g. --partition=render)
# Environment: FERRO_BIN (default: build/bin of this checkout), POVRAY_ARGS (extra povray
# options per frame, e.g. '+W320 +H240').
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
usage() { sed -n '2,32s/^# \{0,1\}//p' "$0"; }
die() { echo "shot.sh: error: $*" >&2; exit 2; }

scene="" out="" frames="" max_frames="" jobs="$(nproc)" video=1 run=1 preset="" sets=() set_args=()
slurm=0 submit_args=() sbatch_args=()
# A --set KEY=VALUE: a dotted key and a plain TOML scalar or array, nothing make or the shell
# would read differently (no spaces, quotes or $).
add_set() {
  [[ "$1" =~ ^[A-Za-z0-9_]+(\.[A-Za-z0-9_]+)+=[][A-Za-z0-9_.,+:-]+$ ]] || die "--set needs section.key=value without spaces, quotes or \$ (got '$1')"
  sets+=("--set=$1")
}
while [[ $# -gt 0 ]]; do
  case "$1" in
    --preset) preset="${2:?--preset needs a name}"; shift 2 ;;
    --set) set_args+=("${2:?--set needs KEY=VALUE}"); shift 2 ;;
    --no-run) run=0; shift ;;
    --frames) frames="${2:?--frames needs A:B}"; shift 2 ;;
    --max-frames) max_frames="${2:?--max-frames needs N}"; shift 2 ;;
    -j) jobs="${2:?-j needs a number}"; shift 2 ;;
    -j*) jobs="${1#-j}"; shift ;;
    --no-video) video=0; shift ;;
    --slurm) slurm=1; shift
      while [[ $# -gt 0 ]]; do
        case "$1" in
          --sim-cpus|--sim-mem|--sim-time|--frame-cpus|--frame-mem|--frame-time|--max-parallel)
            submit_args+=("$1" "${2:?$1 needs a value}"); shift 2 ;;
          --dry-run) submit_args+=("$1"); shift ;;
          *) sbatch_args+=("$1"); shift ;;
        esac
      done ;;
    -h|--help) usage; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) if [[ -z "$scene" ]]; then scene="$1"; elif [[ -z "$out" ]]; then out="$1"; else die "unexpected argument $1"; fi; shift ;;
  esac
done
[[ -n "$scene" && -n "$out" ]] || { usage >&2; exit 2; }
# A missing scene is a missing input: exit 4, as in every stage (sim/core/ExitCodes.hpp).
[[ -f "$scene" ]] || { echo "shot.sh: error: $scene: no such scene file" >&2; exit 4; }
# At most 7 digits (frames up to 9,999,999, like the stages): bash arithmetic never overflows.
[[ -z "$max_frames" || "$max_frames" =~ ^[0-9]{1,7}$ ]] || die "--max-frames needs a number up to 9999999 (got '$max_frames')"
[[ -z "$frames" || "$frames" =~ ^[0-9]{1,7}:[0-9]{1,7}$ ]] || die "--frames needs FIRST:LAST up to 9999999 (got '$frames')"
# 10#: "08" is eight, not a bad octal number.
[[ -z "$max_frames" ]] || max_frames="$((10#$max_frames))"
[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || die "-j needs a positive number (got '$jobs')"
# The preset's settings first, then the --set ones (the later of two settings of a key wins).
if [[ -n "$preset" ]]; then
  presets="$root/scripts/presets.conf"
  names="$(awk '/^[a-z]/ { print $1 }' "$presets" | sort -u | tr '\n' ' ')"
  [[ " $names" == *" $preset "* ]] || die "unknown preset '$preset' (presets: ${names% })"
  while read -r setting; do add_set "$setting"; done < <(awk -v p="$preset" '$1 == p { print $2 }' "$presets")
fi
for setting in "${set_args[@]}"; do add_set "$setting"; done

bin="${FERRO_BIN:-$root/build/bin}"
bin="$(cd "$bin" 2>/dev/null && pwd)" || die "no Ferro executables in ${FERRO_BIN:-$root/build/bin} (run scripts/build.sh)"
for stage in ferro-sim ferro-surface ferro-pov; do
  [[ -x "$bin/$stage" ]] || die "$bin/$stage is missing (run scripts/build.sh)"
done
command -v povray >/dev/null || die "povray is not installed (scripts/install-deps.sh)"
scene="$(cd "$(dirname "$scene")" && pwd)/$(basename "$scene")"
mkdir -p "$out"
out="$(cd "$out" && pwd)"

# One writer a shot: a second shot.sh on this folder is refused at once (exit 4) while this
# one, or the make it started, runs. The lock (flock(1) on OUTDIR/.shot.lock, descriptor 9)
# is inherited by make and the stages and released by the kernel when the last of them ends,
# killed or not: a lock file a killed run leaves is taken over. The file names the holder.
exec 9<>"$out/.shot.lock" || { echo "shot.sh: error: $out: cannot lock" >&2; exit 4; }
if ! flock -n 9; then
  holder="$(head -n 1 "$out/.shot.lock" 2>/dev/null || true)"
  echo "shot.sh: error: $out: in use by ${holder:-another run}; wait for it to end or stop it" >&2
  exit 4
fi
# (The holder's words are a courtesy: on a full disk they may not fit, and the lock holds.)
{ printf 'shot.sh %s (pid %d)\n' "$scene" "$$" > "$out/.shot.lock"; } 2> /dev/null || true

# The shot's frames: ferro-pov validates the scene and writes shot.ini for the whole shot
# (into a scratch directory: the shot's own files are make's business).
probe="$(mktemp -d)"
trap 'rm -rf "$probe"' EXIT
"$bin/ferro-pov" --scene "$scene" --out "$probe" --quiet "${sets[@]}"
last="$(sed -n 's/^Final_Frame=//p' "$probe/shot.ini")"
if [[ -n "$max_frames" && "$max_frames" -lt "$last" ]]; then last="$max_frames"; fi
first_render=0 last_render="$last"
if [[ -n "$frames" ]]; then
  # 10#: "08" is eight, not a bad octal number.
  first_render="$((10#${frames%%:*}))" last_render="$((10#${frames##*:}))"
  (( first_render <= last_render )) || die "--frames $frames: FIRST must be <= LAST"
  (( last_render <= last )) || die "--frames $frames: the shot ends at frame $last"
fi

# Spikes need ferro-spikes and a magnet.
spikes=0
if [[ -x "$bin/ferro-spikes" ]] && grep -Eq '^[[:space:]]*\[\[[[:space:]]*magnets[[:space:]]*\]\]' "$scene"; then
  spikes=1
fi

# Every stage parses its own sections here, so that a bad key in any of them (or in a --set)
# is bad input, exit 2 with the stage's line, before make runs: inside make it would be a
# failed stage (exit 3).
"$bin/ferro-sim" "$scene" --print-scene-inputs "${sets[@]}" > /dev/null
"$bin/ferro-surface" --scene "$scene" --print-scene-inputs "${sets[@]}" > /dev/null
if [[ $spikes == 1 ]]; then "$bin/ferro-spikes" --scene "$scene" --print-scene-inputs "${sets[@]}" > /dev/null; fi

# A full disk (exit 4) names the file system: the stages' lines say "No space left on
# device", but make's, POV-Ray's and this script's own writes may not.
disk_full_exit() {
  local avail mount
  read -r avail mount < <(df -Pk "$out" 2>/dev/null | awk 'NR == 2 { print $4, $6 }') || true
  if [[ -n "$avail" && "$avail" -lt 1024 ]]; then
    echo "shot.sh: error: the file system mounted at $mount is full (${avail} kB free); the frames before it are kept: free space and run the same command again" >&2
    exit 4
  fi
}
if ! { cat > "$out/Makefile.tmp"; } 2> /dev/null <<MAKEFILE
# Written by scripts/shot.sh for this shot; targets and variables: $root/scripts/shot.mk
SCENE := $scene
FERRO_BIN := $bin
SHOT_FIRST := 0
SHOT_LAST := $last
SPIKES := $spikes
MAX_FRAMES := ${max_frames:+$last}
SETS := ${sets[*]}
include $root/scripts/shot.mk
MAKEFILE
then
  rm -f "$out/Makefile.tmp"
  disk_full_exit
  echo "shot.sh: error: $out/Makefile: cannot write" >&2
  exit 4
fi
mv -f "$out/Makefile.tmp" "$out/Makefile"

if [[ $run == 0 ]]; then
  echo "shot.sh: wrote $out/Makefile${preset:+ (preset $preset)}; run: make -C $out -j$jobs" >&2
  exit 0
fi
if [[ $slurm == 1 ]]; then
  exec "$root/scripts/slurm/submit.sh" "$out" "$first_render" "$last_render" "${submit_args[@]}" -- "${sbatch_args[@]}"
fi
# make answers 2 for any failed rule, which would read as "bad input": a stage that failed
# is exit 3 (the run failed; sim/core/ExitCodes.hpp), its own line already on stderr.
run_make() {
  make -C "$out" --no-print-directory "$@" && return 0
  disk_full_exit
  echo "shot.sh: error: a stage failed (its line is above); the frames before it are kept: run the same command again to continue" >&2
  exit 3
}
start=$SECONDS
echo "shot.sh: $scene -> $out: frames $first_render..$last_render of 0..$last, spikes $([[ $spikes == 1 ]] && echo on || echo off), $jobs jobs${preset:+, preset $preset}" >&2
run_make -j"$jobs" prepare
run_make -j"$jobs" FIRST="$first_render" LAST="$last_render" frames
if [[ $video == 1 && -z "$frames" ]]; then
  if command -v ffmpeg >/dev/null; then
    run_make video
  else
    echo "shot.sh: ffmpeg not found: no video (frames are in $out/png)" >&2
  fi
fi
echo "shot.sh: done in $((SECONDS - start)) s: frames in $out/png$([[ -f $out/shot.mp4 && -z $frames ]] && echo ", video $out/shot.mp4, $out/shot.gif")" >&2
