#!/usr/bin/env bash
# The test command: installs missing packages (with Slurm and Blender, for the one-node cluster
# and the Blender import tests),
# builds, runs every test through ctest.
#
#   scripts/test.sh          everything (CI, .ci/run)
#   scripts/test.sh --fast   after a change: builds, then only the tests labelled `fast` (the
#                            test cases not tagged [slow]; about a minute on 2 cores), without
#                            installing packages
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
fast=0
case "${1:-}" in
  --fast) fast=1 ;;
  "") ;;
  *) echo "test.sh: unknown option '$1' (use --fast or nothing)" >&2; exit 2 ;;
esac
if [[ $fast == 1 ]]; then
  "$root/scripts/build.sh"
  cd "$root/build"
  exec ctest --output-on-failure -j"$(nproc)" --timeout 600 -L fast
fi
"$root/scripts/install-deps.sh" --with-slurm --with-blender
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j"$(nproc)" --timeout 1500
