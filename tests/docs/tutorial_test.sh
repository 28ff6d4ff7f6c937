#!/usr/bin/env bash
# Runs docs/tutorial.md as a new user would: in an empty directory beside a checkout, every
# `file:` block written to its file and every ```sh block run, in the page's order. Then the
# frames the page shows must exist and not be blank.
#   tutorial_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR
set -euo pipefail
src="$1" bin="$2" scratch="$3"
fail() { echo "tutorial test: FAILED: $*" >&2; exit 1; }
rm -rf "$scratch" && mkdir -p "$scratch/build"
# The user's checkout, seen from the directory the tutorial runs in: scripts/, examples/ and
# build/bin (the executables of this build).
ln -s "$src/scripts" "$scratch/scripts"
ln -s "$src/examples" "$scratch/examples"
ln -s "$bin" "$scratch/build/bin"

# The page split into steps: "file NAME" + content, or "sh" + one command a line.
python3 - "$src/docs/tutorial.md" "$scratch/steps" <<'PY'
import os, re, sys
lines = open(sys.argv[1]).read().split("\n")
out = sys.argv[2]
os.makedirs(out)
n, i, pending_file = 0, 0, None
while i < len(lines):
    m = re.match(r"<!-- file: (\S+) -->", lines[i])
    if m:
        pending_file = m.group(1)
    fence = re.match(r"```(\w*)$", lines[i])
    if fence:
        j = i + 1
        while lines[j] != "```":
            j += 1
        body = lines[i + 1:j]
        if pending_file:
            n += 1
            open(f"{out}/{n:02d}.file", "w").write(pending_file + "\n" + "\n".join(body) + "\n")
        elif fence.group(1) == "sh":
            n += 1
            open(f"{out}/{n:02d}.sh", "w").write("\n".join(body) + "\n")
        pending_file = None
        i = j
    i += 1
print(f"tutorial: {n} steps")
PY

cd "$scratch"
for step in steps/*; do
  case "$step" in
    *.file)
      name="$(head -1 "$step")"
      tail -n +2 "$step" > "$name"
      echo "tutorial: wrote $name" ;;
    *.sh)
      while IFS= read -r cmd; do
        [[ -z "$cmd" || "$cmd" == \#* ]] && continue
        echo "tutorial: \$ $cmd"
        log="$scratch/$(basename "$step").log"
        if ! bash -c "$cmd" < /dev/null > "$log" 2>&1; then
          tail -20 "$log" >&2
          fail "\`$cmd\` failed"
        fi
      done < "$step" ;;
  esac
done

# Every picture the page shows, as the commands above made it: present and not one flat colour.
for f in 0010 0029 0030; do
  png="out/my_dish/png/frame_$f.png"
  [[ -f "$png" ]] || fail "$png: missing"
  python3 "$src/tests/tools/pngcheck.py" varied "$png" || fail "$png is one flat colour"
done
# The final frames are final quality (the scene's 480 x 360), the preview ones 320 x 240.
python3 "$src/tests/tools/pngcheck.py" size out/my_dish/png/frame_0030.png 480 360 || fail "frame 30 is not 480 x 360"
python3 "$src/tests/tools/pngcheck.py" size out/my_dish/png/frame_0010.png 320 240 || fail "frame 10 is not 320 x 240"
[[ -s out/my_dish/preroll.ply ]] || fail "no pre-roll cache"
grep -q "frame-job.sh" "$scratch/"*.log || fail "the Slurm dry run showed no frame array"
echo "tutorial test: passed"
