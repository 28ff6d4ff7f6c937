#!/usr/bin/env bash
# Installs Ferro's Debian 12 build and run dependencies that are missing. clang and
# libclang-rt-dev build the libFuzzer targets of tests/fuzz, which the test suite runs briefly
# (libFuzzer's library is only a recommend of clang, and recommends are not installed).
# python3 runs the suite's checks of the manual (scripts/docs/) and of rendered images.
# Idempotent: installs nothing when everything is present.
# Usage: install-deps.sh [--with-video] [--with-bench] [--with-slurm] [--with-blender]
# As root it runs apt-get;
# otherwise it prints the exact apt-get line to run and exits 1.
set -euo pipefail
# --help prints the comment above (everything before `set -e`).
if [[ "${1:-}" == "--help" || "${1:-}" == "-h" ]]; then sed -n '2,/^set -e/{/^set -e/d;s/^# \{0,1\}//;p}' "$0"; exit 0; fi

PACKAGES=(
  build-essential cmake
  libeigen3-dev libtbb-dev libboost-iostreams-dev libopenvdb-dev
  libcgal-dev libassimp-dev libtomlplusplus-dev libcli11-dev catch2
  povray parallel python3
  clang libclang-rt-dev
)

# --with-video: also ffmpeg, which the demo uses to assemble the rendered frames into a
# video and a GIF (the tests do not need it, so CI does not install it).
# --with-bench: also gnuplot, which scripts/bench.sh uses to plot the report, and NumPy, which
# the field sweep's surface analysis (scripts/bench/spike_profile.py) needs.
# --with-slurm: also Slurm (slurm-wlm: slurmctld, slurmd and the client commands) and munge,
# for submitting shots (scripts/shot.sh --slurm) and for the suite's one-node cluster
# (scripts/slurm/local-cluster.sh, tests/slurm); the test command installs them.
# --with-blender: also Blender 3.4, for importing shots (scripts/blender/import_shot.py) and
# for the suite's headless import and render test (tests/blender); the test command installs it.
for arg in "$@"; do
  case "$arg" in
    --with-video) PACKAGES+=(ffmpeg) ;;
    --with-bench) PACKAGES+=(gnuplot-nox python3-numpy) ;;
    --with-slurm) PACKAGES+=(slurm-wlm munge) ;;
    --with-blender) PACKAGES+=(blender) ;;
    *) echo "install-deps: error: unknown option $arg (--with-video, --with-bench, --with-slurm, --with-blender)" >&2; exit 2 ;;
  esac
done

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#PACKAGES[@]} packages present"
  exit 0
fi

cmd="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "install-deps: missing packages; run as root:" >&2
  echo "  apt-get update && $cmd" >&2
  exit 1
fi
echo "install-deps: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
apt-get install -y -qq --no-install-recommends ${missing[*]}
