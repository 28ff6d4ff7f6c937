#!/usr/bin/env bash
# A full disk (issue 53): a shot whose output folder is on a small file system that fills
# mid-shot stops with exit 4 and a line naming the disk; no file already written is damaged
# (every file under its final name is byte for byte the uninterrupted run's, a PNG pixel for
# pixel); once space is freed, the same command finishes and every output is identical to the
# uninterrupted run's. Each Ferro stage, writing onto a full disk, exits 4 with a line naming it.
#
#   tests/faults/full_disk_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR
#
# Mounts a size-limited tmpfs under SCRATCH_DIR (root only; fails, never skips, without it)
# and unmounts it at the end.
set -euo pipefail
src="$1" bin="$2" scratch="$3"
fail() { echo "full_disk_test: FAIL: $*" >&2; exit 1; }
[[ $(id -u) == 0 ]] || fail "needs root to mount a size-limited tmpfs"
command -v povray > /dev/null || fail "povray is not installed"

rm -rf "$scratch"
mkdir -p "$scratch/mnt"
mnt="$scratch/mnt"
trap 'umount "$mnt" 2> /dev/null || true' EXIT
cd "$scratch"

# A tiny shot: 4 frames, every stage.
cp "$src/tests/data/tiny_shot.toml" tiny.toml
source "$src/tests/faults/common.sh"
shot() { FERRO_BIN="$bin" "$src/scripts/shot.sh" "$scratch/tiny.toml" "$1" --no-video -j2 2> "$2"; }

shot "$scratch/ref" ref.log || { cat ref.log >&2; fail "the uninterrupted run failed"; }
refsize=$(du -sk "$scratch/ref" | cut -f1)
echo "full_disk_test: the uninterrupted shot: $(outputs "$scratch/ref" | wc -l) files, $refsize kB"

# A disk of half the shot's size: it fills mid-shot.
size=$((refsize / 2))
mount -t tmpfs -o size=${size}k tmpfs "$mnt"
code=0
shot "$mnt/shot" full.log || code=$?
echo "full_disk_test: on a ${size} kB disk: exit $code; its last line: $(tail -n 1 full.log)"
[[ $code == 4 ]] || { cat full.log >&2; fail "exit $code on a full disk, expected 4"; }
tail -n 1 full.log | grep -q "the file system mounted at $mnt is full" || { cat full.log >&2; fail "the last line does not name the disk"; }
grep -q "No space left on device" full.log || { cat full.log >&2; fail "no stage said 'No space left on device'"; }
kept=0
while read -r f; do
  same "$mnt/shot/$f" "$scratch/ref/$f" || fail "$f on the full disk differs from the uninterrupted run's"
  kept=$((kept + 1))
done < <(outputs "$mnt/shot")
leftovers=$(find "$mnt/shot" -name '*.tmp*' | wc -l)
echo "full_disk_test: $kept files written before the disk filled, all identical to the uninterrupted run's; $leftovers temporary files left"

# The same command on the disk still full: exit 4 again, the files kept.
code=0
shot "$mnt/shot" again.log || code=$?
[[ $code == 4 ]] && tail -n 1 again.log | grep -q "the file system mounted at $mnt is full" \
  || { cat again.log >&2; fail "a re-run on the still-full disk: exit $code"; }
while read -r f; do
  same "$mnt/shot/$f" "$scratch/ref/$f" || fail "$f differs after a re-run on the still-full disk"
done < <(outputs "$mnt/shot")
echo "full_disk_test: the same command on the still-full disk: exit 4 again, the files kept"

# Space freed: the same command finishes, byte-identical.
mount -o remount,size=$((refsize * 4))k "$mnt"
shot "$mnt/shot" resumed.log || { cat resumed.log >&2; fail "the re-run after freeing space failed"; }
diff <(outputs "$mnt/shot") <(outputs "$scratch/ref") > /dev/null || fail "the re-run's file list differs from the uninterrupted run's"
same=0
while read -r f; do
  same "$mnt/shot/$f" "$scratch/ref/$f" || fail "$f after the re-run differs from the uninterrupted run's"
  same=$((same + 1))
done < <(outputs "$scratch/ref")
echo "full_disk_test: after freeing space the same command finished: $same of $same files identical (PNGs pixel for pixel)"

# Each stage onto a full disk: exit 4, one line naming the disk.
umount "$mnt"
mount -t tmpfs -o size=64k tmpfs "$mnt"
head -c 60000 /dev/zero > "$mnt/fill"
r="$scratch/ref"
check_stage() {
  local name="$1"; shift
  local c=0
  "$@" > /dev/null 2> stage.log || c=$?
  [[ $c == 4 ]] || { cat stage.log >&2; fail "$name on a full disk: exit $c, expected 4"; }
  [[ $(wc -l < stage.log) == 1 ]] || { cat stage.log >&2; fail "$name on a full disk: more than one line"; }
  grep -q "the file system mounted at $mnt is full" stage.log || { cat stage.log >&2; fail "$name: the line does not name the disk"; }
  echo "full_disk_test: $name: exit 4: $(cat stage.log)"
}
check_stage ferro-sim "$bin/ferro-sim" tiny.toml --out "$mnt/p" --quiet
check_stage ferro-surface "$bin/ferro-surface" "$r/particles/particles_0002.ply" --scene tiny.toml --out "$mnt/s.ply" --quiet
check_stage ferro-spikes "$bin/ferro-spikes" "$r/surface/surface_0002.ply" --particles "$r/particles/particles_0002.ply" --scene tiny.toml --out "$mnt/k.ply" --quiet
check_stage ferro-pov "$bin/ferro-pov" "$r/spiky/spiky_0002.ply" --scene tiny.toml --frame 2 --out "$mnt/shot" --no-shot --quiet
echo "full_disk_test: passed"
