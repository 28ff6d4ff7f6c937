#!/usr/bin/env bash
# frame-unchanged.sh OLD NEW: whether two particle files (ferro-sim's PLY) hold the same frame.
#
# Exit 0: the same frame. Every byte after the header (every particle's position, velocity,
# density, pressure, field and magnetization) is identical, and so is every header line
# except `comment scene ...` and `comment scene_fingerprint ...`, which name the run (the
# scene file and the hash of all its text), not the frame's state. The magnets at the frame's
# time, the spacing and the fluid law are header lines, so they are compared. Exact: no
# tolerance, so a frame counted unchanged would give the same meshes byte for byte.
# Exit 1: they differ (or OLD is missing: nothing to keep). Exit 2: bad arguments or NEW is
# not a PLY file (one line on stderr).
# Used by scripts/shot.mk after a re-simulation: an unchanged frame keeps the previous file's
# time, so make keeps its meshes and render.
set -euo pipefail
[[ $# -eq 2 ]] || { echo "frame-unchanged.sh: error: usage: frame-unchanged.sh OLD NEW" >&2; exit 2; }
old="$1" new="$2"
[[ -f "$new" ]] || { echo "frame-unchanged.sh: error: $new is not a file" >&2; exit 2; }
[[ -f "$old" ]] || exit 1
cmp -s "$old" "$new" && exit 0

# Byte offset of the `end_header` line (grep -b counts from 0), or nothing.
header_end() { { LC_ALL=C grep -a -b -o -m1 '^end_header$' "$1" || true; } | head -n1 | cut -d: -f1; }
eo="$(header_end "$old")" en="$(header_end "$new")"
[[ -n "$en" && "$(head -n1 "$new")" == ply ]] || { echo "frame-unchanged.sh: error: $new is not a PLY file" >&2; exit 2; }
[[ -n "$eo" ]] || exit 1
header() { head -c "$2" "$1" | LC_ALL=C grep -a -v -e '^comment scene ' -e '^comment scene_fingerprint '; }
# The body starts after "end_header\n" (11 bytes); tail -c +K starts at byte K (from 1).
cmp -s <(header "$old" "$eo") <(header "$new" "$en") &&
    cmp -s <(tail -c +"$((eo + 12))" "$old") <(tail -c +"$((en + 12))" "$new")
