#!/usr/bin/env bash
# Makes tests/data/still_magnet_preroll.ply, the settled start of the still-magnet tip test
# (tests/spikes/tracker/test_still_magnet_tips.cpp): that test's scene (tests/data/small_pool.toml
# and the test source's text, joined as the test joins them, so the two cannot differ)
# pre-rolled by ferro-sim until the fluid rests (RMS speed under [shot] preroll_rest_speed,
# 1 mm/s, or 1.5 s), the pre-roll cache copied as is. Its `preroll_fingerprint` comment keys
# it to the scene's [fluid], [container], [sim], [magnetization] sections (their values, not
# their text), the magnet at t = 0 and the pre-roll keys; the test warns when it no longer
# matches (ferro-sim then simulates the pre-roll again).
# Usage: scripts/make_still_magnet_preroll.sh [BUILD_BIN_DIR]   (default build/bin)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${1:-$root/build/bin}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# The test's scene: the small pool, then the test's own text, as smallPoolScene() joins them.
{ cat "$root/tests/data/small_pool.toml"; echo
  sed -n '/const char\* kSceneExtra = R"(/,/^)";/p' "$root/tests/spikes/tracker/test_still_magnet_tips.cpp" | sed '1d;$d'
} > "$tmp/still.toml"
grep -q '^\[\[magnets\]\]' "$tmp/still.toml" || { echo "make_still_magnet_preroll: no scene found in the test" >&2; exit 1; }
"$bin/ferro-sim" "$tmp/still.toml" --out "$tmp/p" --max-frames 0
cp "$tmp/p/preroll.ply" "$root/tests/data/still_magnet_preroll.ply"
echo "wrote tests/data/still_magnet_preroll.ply"
