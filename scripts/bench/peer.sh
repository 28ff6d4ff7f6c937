#!/usr/bin/env bash
# peer.sh: the peer area of scripts/bench.sh: SPlisHSPlasH against Ferro on bench-sim's
# 40,960-particle dam break, both solvers (scripts/bench-peer.sh does the work).
#
#   scripts/bench/peer.sh OUT_DIR
#
# Needs a SPlisHSPlasH simulator that the user built from SPlisHSPlasH's own source (this
# repository holds neither its code nor a recipe that builds it):
#   FERRO_PEER_SIM=/path/to/SPHSimulator, or
#   FERRO_PEER_SRC=/path/to/SPlisHSPlasH (a built source tree: its bin/SPHSimulator).
# Without one the area is skipped with a printed reason (exit 0) and OUT_DIR is left as it
# is, so an earlier peer.csv / peer.md is not destroyed. Writes OUT_DIR/peer.csv,
# OUT_DIR/peer.md and OUT_DIR/peer.png. BENCH_QUICK=1: 0.02 simulated seconds instead of 0.2.
# Exit codes: 2 bad arguments, 4 missing bench-sim, 3 a run failed (bench-peer.sh's).
set -euo pipefail
die() { echo "peer.sh: error: $2" >&2; exit "$1"; }
[[ $# -eq 1 ]] || die 2 "usage: peer.sh OUT_DIR"
out="$1"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"

sim="${FERRO_PEER_SIM:-}"
if [[ -z "$sim" && -n "${FERRO_PEER_SRC:-}" ]]; then
  sim="$FERRO_PEER_SRC/bin/SPHSimulator"
  if [[ ! -x "$sim" ]]; then
    echo "peer.sh: skipped: $sim is not built (build SPlisHSPlasH in FERRO_PEER_SRC first, as its documentation says)"
    exit 0
  fi
fi
if [[ -z "$sim" ]]; then
  echo "peer.sh: skipped: no SPlisHSPlasH simulator given (FERRO_PEER_SIM=/path/to/SPHSimulator or FERRO_PEER_SRC=/path/to/built/SPlisHSPlasH)"
  exit 0
fi
"$root/scripts/bench-peer.sh" "$sim" "$out"
