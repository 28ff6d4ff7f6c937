#!/usr/bin/env bash
# Faults survived (issue 53): a small shot (1,500 particles, 4 frames, a magnet that heaps the
# fluid) run through scripts/shot.sh (make -j2, every stage, POV-Ray at 48 x 36) has one
# process of its pipeline killed with SIGKILL at a random moment of each run: ferro-sim, a
# stage, POV-Ray, make or shot.sh, the kinds in a seeded shuffled order. The same command runs
# again until a run finishes; then again from an empty folder, until ROUNDS kills are done.
# Every output (particles, meshes, includes, scene files, PNGs) is then identical to an
# uninterrupted run's, and a watcher that looks at the shot folder every few milliseconds
# throughout never sees a file under its final name that differs from the uninterrupted
# run's (a partial file).
#
#   tests/faults/kill_test.sh SOURCE_DIR BIN_DIR SCRATCH_DIR [ROUNDS] [SEED]
#
# The seed is printed; the same seed replays the same choices (the moments depend on timing,
# so a replay is close, not exact). Prints the fault table at the end.
set -euo pipefail
src="$1" bin="$2" scratch="$3" rounds="${4:-12}" seed="${5:-53}"
fail() { echo "kill_test: FAIL (seed $seed): $*" >&2; exit 1; }
command -v povray > /dev/null || fail "povray is not installed"
RANDOM=$seed
echo "kill_test: $rounds rounds, seed $seed (replay: $0 SOURCE BIN SCRATCH $rounds $seed)"

rm -rf "$scratch"
mkdir -p "$scratch"
cd "$scratch"
# The tiny shot of the other fault tests with more fluid and a stronger, nearer magnet.
cp "$src/tests/data/tiny_shot.toml" tiny.toml
shot_sets=(--set fluid.block.0.count=1500 --set "magnets.0.position=[0.0,0.0,-0.015]" --set magnets.0.moment=0.4)
source "$src/tests/faults/common.sh"
# The stages and POV-Ray run through wrappers (FERRO_BIN and make's POVRAY point at them): a
# wrapper execs the real program under its own pid, and when the round's plan names its kind
# and its turn (the n-th of that kind to start in the run), it first arms a timer that kills
# it with SIGKILL after the planned delay. Short-lived processes (a stage takes 10-300 ms on
# this shot) are hit this way at a random moment of their own run, which no outside polling
# catches reliably. make and shot.sh, long-lived, are killed from outside.
wrap="$scratch/wrapbin"
mkdir -p "$wrap"
povray_real="$(command -v povray)"
for k in ferro-sim ferro-surface ferro-spikes ferro-pov povray; do
  real="$bin/$k"
  [[ $k == povray ]] && real="$povray_real"
  cat > "$wrap/$k" << WRAPPER
#!/usr/bin/env bash
plan="$scratch/plan"
# shot.sh's checks (--print-scene-inputs) are not turns: they do no work on the shot.
if [[ -f "\$plan/kind" && "\$(cat "\$plan/kind")" == "$k" && " \$* " != *" --print-scene-inputs "* ]]; then
  i=0
  until mkdir "\$plan/started.\$i" 2> /dev/null; do i=\$((i + 1)); done
  if [[ \$i == "\$(cat "\$plan/turn")" ]]; then
    ( sleep "\$(cat "\$plan/delay")"; kill -KILL \$\$ 2> /dev/null && echo "$k \$\$" > "\$plan/killed" ) &
  fi
fi
exec "$real" "\$@"
WRAPPER
  chmod +x "$wrap/$k"
done
run_shot() { FERRO_BIN="$wrap" POVRAY="$wrap/povray" "$src/scripts/shot.sh" "$scratch/tiny.toml" "$1" --no-video -j2 "${shot_sets[@]}"; }
run_shot "$scratch/ref" 2> ref.log || { cat ref.log >&2; fail "the uninterrupted run failed"; }
echo "kill_test: the uninterrupted shot: $(outputs "$scratch/ref" | wc -l) files"

out="$scratch/shot"
# The watcher: every file under a final name in the shot folder (particles.new/ included: the
# simulation's frames land there under their final names) must be the reference's, whenever
# it is seen. It records what it saw wrong in watch.bad and stops when watch.stop appears.
watch() {
  local seen=0
  while [[ ! -e "$scratch/watch.stop" ]]; do
    while read -r f; do
      local rel="${f#"$out"/}" base
      base="${rel#particles.new/}"
      [[ "$rel" == particles.new/* ]] && base="particles/$base"
      [[ -f "$scratch/ref/$base" ]] || continue
      # A file being renamed away or removed between find and cmp is not a partial file.
      [[ -f "$f" ]] || continue
      if ! same "$f" "$scratch/ref/$base" 2> /dev/null && [[ -f "$f" ]]; then
        # Seen again a moment later: a file replaced in between is not a partial one either.
        sleep 0.05
        [[ -f "$f" ]] && ! same "$f" "$scratch/ref/$base" && echo "$rel" >> "$scratch/watch.bad"
      fi
      seen=$((seen + 1))
    done < <(find "$out" -type f \( -name 'particles_*.ply' -o -name 'surface_*.ply' -o -name 'spiky_*.ply' -o -name '*.inc' -o -name 'frame_*.png' \) -newer "$scratch/watch.since" 2> /dev/null)
    touch -d '-1 second' "$scratch/watch.since"
    sleep 0.02
  done
  echo "$seen" > "$scratch/watch.count"
}
rm -f watch.stop watch.bad
touch -d '2000-01-01' watch.since
watch &
watcher=$!
trap 'touch "$scratch/watch.stop"' EXIT

kinds=(ferro-sim ferro-surface ferro-spikes ferro-pov povray make shot.sh)
declare -A killed=()
order=("${kinds[@]}")
for ((i = ${#order[@]} - 1; i > 0; i--)); do j=$((RANDOM % (i + 1))); t="${order[i]}"; order[i]="${order[j]}"; order[j]="$t"; done
refused=0 different=0 missing=0
# The pipeline's processes of a kind, working on this shot.
pids_of() {
  case "$1" in
    shot.sh) pgrep -f "scripts/shot.sh $scratch/tiny.toml $out" || true ;;
    make) pgrep -f "make -C $out" || true ;;
    povray) pgrep -f "^$povray_real" || true ;;
    *) pgrep -f "^$bin/$1" || true ;;
  esac
}
# One kill a run: choose a kind and a moment, start the same command, wait for the moment,
# then kill a process of that kind as soon as one runs (within 3 s; else any of the
# pipeline's). Orphans of a killed make or shot.sh keep running and hold the shot's lock;
# the next run waits for them, as an artist would on the refusal.
kill_round() {
  local round="$1" want delay_ms shot_pid victim="" kind="" p code=0
  # The kinds in a seeded shuffled order, one a run, so that each is hit as often.
  want="${order[(round - 1) % ${#order[@]}]}"
  rm -rf "$scratch/plan"
  mkdir -p "$scratch/plan"
  case "$want" in
    ferro-sim) delay_ms=$((RANDOM % 1500)) ;;                                      # the simulation: ~2 s
    povray) delay_ms=$((RANDOM % 300)); echo $((RANDOM % 3)) > "$scratch/plan/turn" ;; # a frame: ~0.3 s
    make | shot.sh) delay_ms=$((RANDOM % 5000)) ;;                                  # the whole run
    *) delay_ms=$((RANDOM % 20)); echo $((RANDOM % 3)) > "$scratch/plan/turn" ;;    # a stage's frame: 10-200 ms
  esac
  if [[ $want != make && $want != shot.sh ]]; then
    [[ -f "$scratch/plan/turn" ]] || echo 0 > "$scratch/plan/turn"
    echo "$((delay_ms / 1000)).$(printf '%03d' $((delay_ms % 1000)))" > "$scratch/plan/delay"
    echo "$want" > "$scratch/plan/kind"
  fi
  run_shot "$out" > "round_$round.log" 2>&1 &
  shot_pid=$!
  if [[ $want == make || $want == shot.sh ]]; then
    sleep "$((delay_ms / 1000)).$(printf '%03d' $((delay_ms % 1000)))"
    p="$(pids_of "$want" | head -n 1)"
    if [[ -n "$p" ]] && kill -KILL "$p" 2> /dev/null; then victim="$p" kind="$want"; fi
  fi
  wait "$shot_pid" 2> /dev/null || code=$?
  rm -f "$scratch/plan/kind" # no later process of this run (an orphan's) is armed
  if [[ -f "$scratch/plan/killed" ]]; then read -r kind victim < "$scratch/plan/killed"; fi
  if [[ $code == 4 ]] && grep -q "in use by" "round_$round.log"; then refused=$((refused + 1)); fi
  for ((w = 0; w < 600; w++)); do
    [[ -z "$(pids_of make)$(pids_of povray)$(pgrep -f "^$bin/ferro-" || true)$(pgrep -f "^$wrap/" || true)" ]] && break
    sleep 0.1
  done
  if [[ -n "$victim" ]]; then
    killed[$kind]=$((${killed[$kind]:-0} + 1))
    kills=$((kills + 1))
    echo "kill_test: run $round: killed $kind (pid $victim) ${delay_ms} ms into it"
    return 1
  fi
  echo "kill_test: run $round: chose $want (turn $(cat "$scratch/plan/turn" 2> /dev/null || echo -), ${delay_ms} ms): it ended first (exit $code)"
  # A run not killed (its victim ended before the moment) finished the shot (exit 0) or
  # failed (a bug).
  [[ $code == 0 ]] || { cat "round_$round.log" >&2; fail "run $round ended with exit $code without a kill"; }
  return 0
}

# Campaigns: an empty shot folder, then runs killed one after another until a run finishes;
# the rounds count the kills.
campaign=0 kills=0 runs=0
while ((kills < rounds)); do
  campaign=$((campaign + 1))
  rm -rf "$out"
  until kill_round $((++runs)); do :; done
  echo "kill_test: campaign $campaign finished after $runs runs in all"
  while read -r f; do
    same "$out/$f" "$scratch/ref/$f" || { echo "kill_test: campaign $campaign: $f differs" >&2; different=$((different + 1)); }
  done < <(outputs "$scratch/ref")
  missing=$((missing + $(comm -3 <(outputs "$out") <(outputs "$scratch/ref") | wc -l)))
done
touch watch.stop
wait "$watcher"

partial=$([[ -f watch.bad ]] && sort -u watch.bad | wc -l || echo 0)

echo "kill_test: fault table (seed $seed)"
echo "  kills (rounds)              $kills in $campaign campaigns, $runs runs"
for k in "${kinds[@]}"; do printf '  killed %-20s %d\n' "$k" "${killed[$k]:-0}"; done
echo "  re-runs refused (in use)    $refused"
echo "  files compared              $(outputs "$scratch/ref" | wc -l) a campaign"
echo "  files different at the end $different"
echo "  files missing or extra      $missing"
echo "  files checked while running $(cat watch.count)"
echo "  partial files seen          $partial"
[[ -f watch.bad ]] && sort -u watch.bad | sed 's/^/  partial: /'
[[ $different == 0 && $missing == 0 && $partial == 0 ]] || fail "see the table"
echo "kill_test: passed"
