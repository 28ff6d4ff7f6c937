#!/usr/bin/env bash
# Makes tests/data/still_magnet_preroll.ply, the settled start of the still-magnet tip test
# (tests/spikes/tracker/test_still_magnet_tips.cpp): that test's scene (read from the test
# source, so the two cannot differ) pre-rolled by ferro-sim until the fluid rests (RMS speed
# under [shot] preroll_rest_speed, 1 mm/s, or 1.5 s), the pre-roll cache copied as is. Its
# `preroll_fingerprint` comment keys it to the scene's [fluid], [container], [sim],
# [magnetization] sections, the magnet at t = 0 and the pre-roll keys; the test warns when it
# no longer matches (ferro-sim then simulates the pre-roll again).
# Usage: scripts/make_still_magnet_preroll.sh [BUILD_BIN_DIR]   (default build/bin)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${1:-$root/build/bin}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
sed -n '/const char\* kScene = R"(/,/^)";/p' "$root/tests/spikes/tracker/test_still_magnet_tips.cpp" | sed '1d;$d' \
    > "$tmp/still.toml"
grep -q '^preroll' "$tmp/still.toml" || { echo "make_still_magnet_preroll: no scene found in the test" >&2; exit 1; }
"$bin/ferro-sim" "$tmp/still.toml" --out "$tmp/p" --max-frames 0
cp "$tmp/p/preroll.ply" "$root/tests/data/still_magnet_preroll.ply"
echo "wrote tests/data/still_magnet_preroll.ply"
