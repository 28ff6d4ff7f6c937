#!/usr/bin/env bash
# The test command: installs missing packages (with Slurm and Blender, for the one-node cluster
# and the Blender import tests),
# builds, runs every test through ctest.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
"$root/scripts/install-deps.sh" --with-slurm --with-blender
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j"$(nproc)" --timeout 1500
