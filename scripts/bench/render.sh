#!/usr/bin/env bash
# render.sh: the POV-Ray trade: quality (+Q) and anti-aliasing (+A threshold, +R depth) on one
# frame: render CPU time against the image's RMSE versus a high-quality render of the same frame.
#
#   scripts/bench/render.sh [OUT_DIR]      (default tests/bench/report; BENCH_QUICK=1: tiny)
#
# The frame: the settled, spiky frame of spikes.sh (examples/magnet_slide.toml, 10,240
# particles, ferro-surface and ferro-spikes at their defaults) exported by ferro-pov with the
# default look, rendered at 160x120 (small, so the run stays cheap; the cost per pixel carries
# over to larger images, the error roughly too). The reference: +Q11 +A0.02 +R4.
# RMSE: root mean square of the 8-bit RGB differences, as a fraction of full scale (0..1).
# Motion blur (render.motion_blur): frame 40 of the same scene at 5,120 particles, the magnet
# sliding at 20 mm/s, rendered with 1 (sharp), 2, 4 and 8 sub-frames against 16.
# Writes render_quality.csv/.png, render_antialias.csv/.png, render_motion_blur.csv/.png, render.md.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init render "$@"
bench_need ferro-surface ferro-spikes ferro-pov
command -v povray > /dev/null || bench_die 4 "povray is not installed (scripts/install-deps.sh)"

count=10240 preroll=2.0 width=160 height=120
qualities="3 5 8 9"
antialias=("-A" "+A0.3 +R2" "+A0.3 +R3" "+A0.1 +R3" "+A0.05 +R4")
reference="+Q11 +A0.02 +R4"
if [[ $quick == 1 ]]; then count=2560 preroll=0.2 width=64 height=48 qualities="3 9" antialias=("-A" "+A0.3 +R3"); fi
scene="$root/examples/magnet_slide.toml"
sets=(--set "fluid.block.0.count=$count" --set "shot.preroll=$preroll")
bench_settled_frame frame "$scene" "${sets[@]}"
"$bin/ferro-surface" "$frame" --out "$work/surface.ply" --quiet
"$bin/ferro-spikes" "$work/surface.ply" --particles "$frame" --scene "$scene" "${sets[@]}" --out "$work/spiky.ply" --quiet
"$bin/ferro-pov" "$work/spiky.ply" --scene "$scene" "${sets[@]}" --frame 0 --out "$work/shot" --quiet
"$bin/ferro-pov" --scene "$scene" "${sets[@]}" --out "$work/shot" --quiet

# render NAME OPTIONS...: $work/NAME.ppm; POV-Ray's own CPU seconds of the trace in $seconds.
render() {
  local name="$1"; shift
  ( cd "$work/shot" && povray render.ini -D Declare=FerroFrame=0 +W$width +H$height +FP "+O$work/$name.ppm" "$@" ) \
    > "$work/$name.log" 2>&1 || { tail -n 5 "$work/$name.log" >&2; bench_die 3 "povray failed: $*"; }
  seconds="$(sed -n 's/.*using [0-9]* thread(s) with \([0-9.]*\) CPU-seconds total.*/\1/p' "$work/$name.log" | tail -n 1)"
  [[ -n "$seconds" ]] || bench_die 3 "no CPU time in POV-Ray's log of $name"
}
# rmse A.ppm B.ppm: RMS of the RGB differences of two binary PPMs, as a fraction of full scale.
rmse() {
  python3 - "$1" "$2" <<'PY'
import math, sys
def ppm(path):
    data = open(path, "rb").read()
    fields, pos = [], 0
    while len(fields) < 4:  # magic, width, height, maxval; '#' comments skipped
        while data[pos:pos + 1].isspace(): pos += 1
        if data[pos:pos + 1] == b"#":
            pos = data.index(b"\n", pos) + 1; continue
        end = pos
        while not data[end:end + 1].isspace(): end += 1
        fields.append(data[pos:end]); pos = end
    pos += 1
    if fields[0] != b"P6" or int(fields[3]) > 255: sys.exit("not an 8-bit binary PPM: " + path)
    return int(fields[1]), int(fields[2]), data[pos:pos + 3 * int(fields[1]) * int(fields[2])]
wa, ha, a = ppm(sys.argv[1]); wb, hb, b = ppm(sys.argv[2])
if (wa, ha) != (wb, hb): sys.exit("image sizes differ")
print("%.6f" % (math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)) / len(a)) / 255))
PY
}

# shellcheck disable=SC2086
render reference $reference
ref_seconds="$seconds"
header="setting,options,cpu_seconds,rmse,reference"
{
  echo "$header"
  for q in $qualities; do render current "+Q$q"; echo "Q$q,+Q$q (AA as [render]: +A0.3 +R3),$seconds,$(rmse "$work/current.ppm" "$work/reference.ppm"),$reference"; done
  echo "reference,$reference,$ref_seconds,0,$reference"
} > "$out/render_quality.csv"
{
  echo "$header"
  for aa in "${antialias[@]}"; do
    # shellcheck disable=SC2086
    render current +Q9 $aa
    echo "${aa// /},+Q9 $aa,$seconds,$(rmse "$work/current.ppm" "$work/reference.ppm"),$reference"
  done
  echo "reference,$reference,$ref_seconds,0,$reference"
} > "$out/render_antialias.csv"
# Motion blur: a frame in motion (the slide's frame 40, cached like the settled frame), its mesh
# with velocities, rendered through blur.ini and average.ini as shot.mk does.
blur_count=5120 blur_frame=40 blur_levels="1 2 4 8" blur_reference=16
if [[ $quick == 1 ]]; then blur_count=2560 blur_frame=8 blur_levels="1 4" blur_reference=8; fi
msets=(--set "fluid.block.0.count=$blur_count")
mkey="$( (cat "$scene"; printf '%s\n' "${msets[@]}" "$blur_frame") | sha1sum | cut -c1-16)"
mdir="$cache/frames/magnet_slide-moving-$mkey"
if [[ ! -f "$mdir/particles_$(printf %04d "$blur_frame").ply" ]]; then
  bench_note "simulating the slide to frame $blur_frame at $blur_count particles (cached in $mdir)"
  rm -rf "$mdir.tmp"
  nice -n 5 "$bin/ferro-sim" "$scene" --out "$mdir.tmp" --max-frames "$blur_frame" --quiet "${msets[@]}" \
    || bench_die 3 "ferro-sim failed on the moving frame"
  rm -rf "$mdir"; mv "$mdir.tmp" "$mdir"
fi
mframe="$mdir/particles_$(printf %04d "$blur_frame").ply"
"$bin/ferro-surface" "$mframe" --out "$work/moving_surface.ply" --quiet
"$bin/ferro-spikes" "$work/moving_surface.ply" --particles "$mframe" --scene "$scene" "${msets[@]}" \
  --out "$work/moving_spiky.ply" --quiet
# blur N: $work/blurN.ppm (N = 1: the sharp render); POV-Ray's CPU seconds of every pass in $seconds.
blur() {
  local n="$1" d="$work/blur$1"
  rm -rf "$d"
  "$bin/ferro-pov" --scene "$scene" "${msets[@]}" --set "render.motion_blur=$n" --out "$d" --quiet
  "$bin/ferro-pov" "$work/moving_spiky.ply" --scene "$scene" "${msets[@]}" --set "render.motion_blur=$n" \
    --frame "$blur_frame" --out "$d" --no-shot --quiet
  mkdir -p "$d/sub"
  if [[ $n -gt 1 ]]; then
    ( cd "$d" && povray blur.ini -D Declare=FerroFrame=$blur_frame +W$width +H$height "+Osub/frame_$(printf %04d "$blur_frame")_.png" &&
      povray average.ini -D Declare=FerroFrame=$blur_frame +W$width +H$height +FP "+O$work/blur$n.ppm" ) > "$d.log" 2>&1
  else
    ( cd "$d" && povray render.ini -D Declare=FerroFrame=$blur_frame +W$width +H$height +FP "+O$work/blur$n.ppm" ) > "$d.log" 2>&1
  fi || { tail -n 5 "$d.log" >&2; bench_die 3 "povray failed with motion_blur = $n"; }
  seconds="$(sed -n 's/.*using [0-9]* thread(s) with \([0-9.]*\) CPU-seconds total.*/\1/p' "$d.log" | awk '{ s += $1 } END { print s }')"
}
blur "$blur_reference"
blur_ref_seconds="$seconds"
{
  echo "setting,motion_blur,cpu_seconds,rmse,reference"
  for n in $blur_levels; do
    blur "$n"
    echo "N$n,$n,$seconds,$(rmse "$work/blur$n.ppm" "$work/blur$blur_reference.ppm"),motion_blur = $blur_reference"
  done
  echo "reference,$blur_reference,$blur_ref_seconds,0,motion_blur = $blur_reference"
} > "$out/render_motion_blur.csv"

bench_plot "$out/render_quality.csv" cpu_seconds rmse render_quality "POV-Ray quality (+Q): image RMSE vs +Q11 +A0.02 +R4, ${width}x${height}"
bench_plot "$out/render_antialias.csv" cpu_seconds rmse render_antialias "POV-Ray anti-aliasing at +Q9: image RMSE vs +Q11 +A0.02 +R4, ${width}x${height}"
bench_plot "$out/render_motion_blur.csv" cpu_seconds rmse render_motion_blur "Motion blur sub-frames: image RMSE vs $blur_reference sub-frames, ${width}x${height}"

q1="$out/render_quality.csv" a1="$out/render_antialias.csv"
{
  echo "## Render: POV-Ray quality and anti-aliasing"
  echo
  echo "What ran: \`scripts/bench/render.sh\`. The settled spiky frame of spikes.sh exported by ferro-pov"
  echo "with the default look (area lights, fresnel reflection), rendered at ${width}x${height}; each image is"
  echo "compared with a reference render of the same frame ($reference, $ref_seconds CPU s). RMSE: root"
  echo "mean square of the 8-bit RGB differences as a fraction of full scale. CPU seconds: POV-Ray's own"
  echo "count for the trace (all threads). Render time scales with the pixel count: 640x480 is 16x this."
  echo
  echo "Quality (+Q, with the default anti-aliasing): ![](render_quality.png)"
  echo
  table "$q1"
  echo
  echo "Anti-aliasing at +Q9 (-A = off; +A threshold, +R depth): ![](render_antialias.png)"
  echo
  table "$a1"
  echo
  echo "Findings:"
  echo
  echo "- The default (+Q9 +A0.3 +R3): RMSE $(r3 "$(col "$a1" "+A0.3+R3" 4)") in $(r3 "$(col "$a1" "+A0.3+R3" 3)") CPU s; without anti-aliasing"
  echo "  $(r3 "$(col "$a1" "-A" 4)") in $(r3 "$(col "$a1" "-A" 3)") CPU s; +A0.1 +R3: $(r3 "$(col "$a1" "+A0.1+R3" 4)") in $(r3 "$(col "$a1" "+A0.1+R3" 3)") CPU s."
  echo "- Quality below 8 drops the reflections the black fluid is seen by: +Q5 RMSE $(r3 "$(col "$q1" Q5 4)")"
  echo "  ($(r3 "$(col "$q1" Q5 3)") CPU s) against +Q8 $(r3 "$(col "$q1" Q8 4)") ($(r3 "$(col "$q1" Q8 3)") CPU s) and +Q9 $(r3 "$(col "$q1" Q9 4)") ($(r3 "$(col "$q1" Q9 3)") CPU s):"
  echo "  +Q9 adds only media and radiosity, which the default look does not use."
  echo "- Anti-aliasing is most of the render's cost: +R2 costs $(r3 "$(col "$a1" "+A0.3+R2" 3)") CPU s for RMSE $(r3 "$(col "$a1" "+A0.3+R2" 4)"), about half the default's."
  echo
  echo "Recommended: preview +Q8 without anti-aliasing at 320x240 (\`render.quality = 8\`, \`render.antialias ="
  echo "false\`); final the defaults (+Q9 +A0.3 +R3, 640x480); a large shot +A0.3 +R2 (\`render.antialias_depth = 2\`)."
  m1="$out/render_motion_blur.csv"
  echo
  echo "### Motion blur (\`render.motion_blur\`, \`render.shutter\`)"
  echo
  echo "Frame $blur_frame of the slide at $blur_count particles (the magnet moving 20 mm/s, the tips with it), each"
  echo "sub-frame the meshes moved along their vertex velocities across a 180-degree shutter (0.5 of the"
  echo "frame interval), averaged in linear light; against $blur_reference sub-frames ($(r3 "$blur_ref_seconds") CPU s). The cost is"
  echo "one render a sub-frame plus an average that takes under a second: ![](render_motion_blur.png)"
  echo
  table "$m1"
  echo
  echo "The sharp frame (N1) is as far from the blurred reference as the blur is wide; a few sub-frames"
  echo "leave the blur stepped (N2, N4), 8 is close to the converged blur. Off by default: at this"
  echo "speed the blur is about a pixel at 640x480, visible on fast pours and slides, not on heaps"
  echo "that rise over seconds."
} > "$out/render.md"
bench_note "wrote $out/render.md, render_quality.csv/.png, render_antialias.csv/.png"
