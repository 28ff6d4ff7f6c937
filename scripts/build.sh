#!/usr/bin/env bash
# Configures and builds Ferro in build/ (Release). Executables land in build/bin/.
#   scripts/build.sh                    the stages, their tests and tools
#   scripts/build.sh --with-benchmarks  also the bench-* executables (scripts/bench.sh asks
#                                       for them; the tests never run them)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
targets=()
case "${1:-}" in
  "") ;;
  --with-benchmarks) targets=(--target all benchmarks) ;;
  *) echo "build.sh: error: unknown option '$1' (scripts/build.sh [--with-benchmarks])" >&2; exit 2 ;;
esac
cmake -S "$root" -B "$root/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$root/build" -j"$(nproc)" "${targets[@]+"${targets[@]}"}"
