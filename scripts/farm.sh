#!/usr/bin/env bash
# farm.sh: renders a shot's frames on several machines with GNU parallel.
#
#   scripts/farm.sh OUTDIR [--frames A:B] [--sshlogin LOGIN]... [--sshloginfile FILE] [--no-video]
#
# OUTDIR is a shot directory set up by scripts/shot.sh (its Makefile). Frames are independent
# after the simulation, so:
#   1. here, `make -C OUTDIR prepare` runs the simulation and writes the shot files once;
#   2. GNU parallel hands out one frame at a time (`make -C OUTDIR frames FIRST=N LAST=N`, which
#      runs surface, spikes, export and render for that frame) to the machines in --sshlogin,
#      each taking as many frames at once as it has cores, retrying a failed frame elsewhere;
#   3. here, `make -C OUTDIR video` assembles the video.
# Requirements for remote machines: password-less ssh, OUTDIR on a shared file system (NFS)
# mounted at the same path, and Ferro built at the same path (the Makefile names the absolute
# paths of the scene and the executables). LOGIN is GNU parallel's: `user@host`,
# `4/host` (at most 4 frames at once there), or `:` for this machine without ssh. Examples:
#   scripts/farm.sh out/fig9 --sshlogin : --sshlogin 8/render1 --sshlogin 8/render2
#   scripts/farm.sh out/fig9 --frames 30:59 --sshloginfile ~/farm-hosts
# Each machine gets whole frames, so a stage's own threads (TBB, POV-Ray) use its cores.
set -euo pipefail
usage() { sed -n '2,22s/^# \{0,1\}//p' "$0"; }
die() { echo "farm.sh: error: $*" >&2; exit 2; }

out="" frames="" video=1
logins=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --frames) frames="${2:?--frames needs A:B}"; shift 2 ;;
    --sshlogin|-S) logins+=(--sshlogin "${2:?--sshlogin needs a login}"); shift 2 ;;
    --sshloginfile|--slf) logins+=(--sshloginfile "${2:?--sshloginfile needs a file}"); shift 2 ;;
    --no-video) video=0; shift ;;
    -h|--help) usage; exit 0 ;;
    -*) die "unknown option $1 (see --help)" ;;
    *) [[ -z "$out" ]] || die "unexpected argument $1"; out="$1"; shift ;;
  esac
done
[[ -n "$out" ]] || { usage >&2; exit 2; }
[[ -f "$out/Makefile" ]] || die "$out/Makefile missing: set the shot up with scripts/shot.sh first"
command -v parallel >/dev/null || die "GNU parallel is not installed (scripts/install-deps.sh)"
[[ ${#logins[@]} -gt 0 ]] || logins=(--sshlogin :)
out="$(cd "$out" && pwd)"

last="$(sed -n 's/^SHOT_LAST := //p' "$out/Makefile")"
first=0
if [[ -n "$frames" ]]; then
  [[ "$frames" =~ ^[0-9]{1,7}:[0-9]{1,7}$ ]] || die "--frames needs FIRST:LAST up to 9999999 (got '$frames')"
  # 10#: "08" is eight, not a bad octal number.
  first="$((10#${frames%%:*}))" last="$((10#${frames##*:}))"
  (( first <= last )) || die "--frames $frames: FIRST must be <= LAST"
fi

make -C "$out" --no-print-directory prepare
# --retries 2: a frame that fails on one machine is tried again (on any machine);
# --halt soon,fail=1: after a frame failed for good, start no new frames and report.
# -o: the shared targets that `prepare` just made are never remade by a frame job (a remote
# make that saw them stale, e.g. after a scene edit, would re-simulate under every frame).
seq "$first" "$last" | parallel "${logins[@]}" --retries 2 --halt soon,fail=1 --tagstring 'frame {}' \
  make -C "$out" --no-print-directory -o particles/.complete -o shot/shot.pov -o shot/look.inc \
  frames FIRST={} LAST={}
if [[ $video == 1 && -z "$frames" ]] && command -v ffmpeg >/dev/null; then
  make -C "$out" --no-print-directory video
fi
echo "farm.sh: frames $first..$last rendered into $out/png" >&2
