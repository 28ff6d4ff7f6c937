#!/usr/bin/env bash
# field-sweep.sh: a flat layer swept up and down through the critical field with the full force
# (issue 32): where the pattern appears on the way up, how tall it stands against the field,
# and where it vanishes on the way down (the hysteresis of the subcritical hexagons).
#
#   scripts/bench/field-sweep.sh [OUT_DIR]   (default tests/bench/report; BENCH_QUICK=1:
#                                             the same sweep, it has no smaller version)
#
# scripts/bench/field_sweep.toml (periodic_layer.toml's layer and fluid, csf tension,
# force = "surface"; 17 plateaus of 0.5 s from 0.8 to 1.3 times the critical 10.42 kA/m and
# back) at the spacings of $spacings, simulated once (cached in $cache/field-sweep/<hash>).
# Every frame goes through scripts/bench/rosensweig.py --period; scripts/bench/field_sweep.py
# averages the second half of each plateau. A 0.5 s plateau cannot tell a pattern that stands
# from one that sinks slowly near the lower threshold, so the holds of $holds
# (scripts/bench/field_hold.toml) make the pattern at 1.1 x critical and hold a field below
# the critical one for 2 s. Costs are ferro-sim's CPU seconds. Writes field_sweep.csv,
# field_hold.csv, field_sweep.png (the pattern's height against the field, up and down),
# field_profile.csv and field_profile.png (the standing plateaus' spike shape against the
# fundamental Fourier mode, scripts/bench/spike_profile.py), field_spike.csv and field_spike.png
# (their mean spike against the fundamental's J0) and field-sweep.md.
# The jumps of $jumps switch the flat layer's field on at once: the pattern's growth rate and
# wavelength as it is born against linear theory (field_jump.csv, scripts/bench/field_jump.py),
# and every wavelength's growth rate, the simulated dispersion relation (field_dispersion.csv,
# field_dispersion.png).
# FIELD_SWEEP_SPACINGS, FIELD_SWEEP_HOLDS and FIELD_SWEEP_JUMPS override the lists.
set -euo pipefail
source "$(dirname "$0")/common.sh"
bench_init field-sweep "$@"
bench_need ferro-sim

scene="$root/scripts/bench/field_sweep.toml"
hold_scene="$root/scripts/bench/field_hold.toml"
critical=10420
spacings="${FIELD_SWEEP_SPACINGS:-0.001}"
# The holds, SPACING:FIELD/CRITICAL[:flat]: the pattern made at 1.1 x critical, then the field
# held below the critical one for 2 s (field_hold.toml); with "flat" the field goes straight
# to the held one (from the flat layer, held 2.9 s: the onset, slower than a plateau's 0.5 s).
holds="${FIELD_SWEEP_HOLDS:-0.001:0.875 0.001:0.9 0.001:0.925 0.001:0.95 0.001:0.975 0.001:0.9:flat 0.001:0.925:flat 0.001:0.95:flat
  0.00075:0.85 0.00075:0.9 0.00075:0.95 0.00075:0.95:flat}"
# The jumps, SPACING:FIELD/CRITICAL[:BOX_MM]: the flat layer's field switched on at once, in the
# 24 mm box or a wider one (its side in mm: a 24 mm box holds few wavelengths near 4-7 mm).
jumps="${FIELD_SWEEP_JUMPS:-0.001:1.1 0.001:1.2 0.001:1.5 0.00075:1.1 0.00075:1.2 0.00075:1.5
  0.00075:1.1:48 0.00075:1.2:48 0.00075:1.3:48 0.00075:1.5:48 0.0005:1.2:48}"

# simulate SCENE K=V...: bench_cached_shot in $cache/field-sweep.
simulate() { bench_cached_shot field-sweep "$@"; }

echo "spacing_mm,particles,sim_cpu_s,plateau,direction,field_A_m,field_over_critical,frames,rms_h_spacings,peaks,nn_median_mm,height_mm,stands" \
  > "$out/field_sweep.csv"
echo "spacing_mm,direction,field_over_critical,frames,ptp_mm,lambda_mm,dev_max,dev_rms,below,above,move,shape_dev" > "$out/field_profile.csv"
echo "spacing_mm,label,r_over_lambda,mean_spike,j0" > "$out/field_spike.csv"
echo "spacing_mm,label,distance_mm,surface_mm,fundamental_mm" > "$out/field_profile_cut.csv"
summary=()
for s in $spacings; do
  simulate "$scene" "fluid.spacing=$s"
  n="$(head -c 4000 "$dir/particles_0000.ply" | grep -a -m1 '^element vertex' | awk '{print $3}')"
  python3 "$root/scripts/bench/rosensweig.py" "$dir" --period 0.024,0.024 --smooth > "$work/pattern.txt"
  python3 "$root/scripts/bench/field_sweep.py" "$scene" "$work/pattern.txt" "$critical" "$s" \
    > "$work/plateaus.csv" 2> "$work/summary.txt"
  tail -n +2 "$work/plateaus.csv" | awk -v s="$s" -v n="$n" -v cpu="$cpu" '{ printf "%g,%d,%.0f,%s\n", s * 1e3, n, cpu, $0 }' \
    >> "$out/field_sweep.csv"
  summary+=("- sweep at $(awk -v s="$s" 'BEGIN { printf "%g mm", s * 1e3 }') ($n particles, $(printf '%.0f' "$cpu") CPU s): $(paste -sd';' "$work/summary.txt" | sed 's/;/; /g').")
  # The standing plateaus' spike shape against the fundamental Fourier mode (Gollwitzer et al.
  # 2007: within 10 % up to 40 % above onset), each frame of the plateau's second half.
  windows=()
  python3 "$root/scripts/bench/field_sweep.py" "$scene" --windows "$critical" > "$work/windows.txt"
  # Joined on the plateau index (plateaus.csv leaves out a plateau without frames).
  while IFS= read -r w; do windows+=(--window "$w"); done < <(
    awk -F, 'NR == FNR { if (FNR > 1 && $10 == 1) standing[$1] = 1; next } ($1 in standing) { print $2 }' \
      "$work/plateaus.csv" FS=' ' "$work/windows.txt")
  if (( ${#windows[@]} )); then
    python3 "$root/scripts/bench/spike_profile.py" "$dir" --period 0.024,0.024 "${windows[@]}" \
      --profile-csv "$work/cut.csv" --spike-csv "$work/spike.csv" > "$work/profile.txt"
    awk -v s="$s" 'NR > 1 { split($1, l, "_"); printf "%g,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s\n", s * 1e3, l[1], l[2], $2, $3, $4, $5, $6, $7, $8, $10, $11 }' \
      "$work/profile.txt" >> "$out/field_profile.csv"
    tail -n +2 "$work/spike.csv" | awk -v s="$s" '{ printf "%g,%s\n", s * 1e3, $0 }' >> "$out/field_spike.csv"
    tail -n +2 "$work/cut.csv" | awk -v s="$s" '{ printf "%g,%s\n", s * 1e3, $0 }' >> "$out/field_profile_cut.csv"
  fi
done

# The holds: the mean over the hold's last 0.25 s (3.05-3.3 s: the state it ends in; a layer
# near onset may erupt and sink again on the way) against the pattern at 1.1 x critical just
# before the fall (0.9-1.2 s).
echo "spacing_mm,particles,sim_cpu_s,field_over_critical,from,rms_h_spacings,peaks,height_mm,height_before_mm,stands" \
  > "$out/field_hold.csv"
for c in $holds; do
  IFS=: read -r s r from <<< "$c"
  H="$(awk -v r="$r" -v c="$critical" 'BEGIN { printf "%d", r * c + 0.5 }')"
  if [[ "$from" == flat ]]; then
    simulate "$hold_scene" "fluid.spacing=$s" "magnets.0.keys.2.field=$H" "magnets.0.keys.3.field=$H" \
      "magnets.0.keys.4.field=$H" "magnets.0.keys.5.field=$H"
  else
    from=pattern
    simulate "$hold_scene" "fluid.spacing=$s" "magnets.0.keys.4.field=$H" "magnets.0.keys.5.field=$H"
  fi
  n="$(head -c 4000 "$dir/particles_0000.ply" | grep -a -m1 '^element vertex' | awk '{print $3}')"
  python3 "$root/scripts/bench/rosensweig.py" "$dir" --period 0.024,0.024 --smooth --first 0.899 > "$work/hold.txt"
  # Columns of rosensweig.py: t mean_h rms_h change detached peaks nn nn/lambda spectrum apex.
  awk -v s="$s" -v r="$r" -v from="$from" -v n="$n" -v cpu="$cpu" 'NR > 2 {
      late = $1 >= 3.049; early = $1 <= 1.201
      if (late) { k++; rms += $3; pk += $6; if ($10 != "nan") h += $10 - $2 }
      if (early) { e++; if ($10 != "nan") he += $10 - $2 } }
    END { printf "%g,%d,%.0f,%s,%s,%.3f,%.2f,%.2f,%.2f,%d\n", s * 1e3, n, cpu, r, from, rms / k, pk / k, h / k, he / e,
          (pk / k >= 1 && rms / k >= 0.35) }' "$work/hold.txt" >> "$out/field_hold.csv"
done
# The lower threshold per spacing: between the highest held field whose pattern sank and the
# lowest one whose pattern stood; and whether a flat layer held below critical stayed flat.
for s in $(awk -F, 'NR > 1 { print $1 }' "$out/field_hold.csv" | sort -u -g -r); do
  summary+=("- holds at $s mm: $(awk -F, -v s="$s" 'NR > 1 && $1 == s && $5 == "pattern" {
      if ($10 == 1) { if (lo == "" || $4 < lo) lo = $4 } else if (hi == "" || $4 > hi) hi = $4 }
    NR > 1 && $1 == s && $5 == "flat" { flat = flat sprintf("; from flat at %s x critical the layer %s", $4, ($10 == 1 ? "rose" : "stayed flat")) }
    END { if (lo == "") printf "no held pattern stood"
          else if (hi == "") printf "every held pattern stood, down to %s x critical", lo
          else printf "the pattern sank at %s x critical and stood at %s: the lower threshold lies between", hi, lo
          printf "%s", flat }' "$out/field_hold.csv").")
done

# The jumps: the flat layer's field switched at 0.301 s from 0 to a field above critical (the
# hold scene, every key after the settling at that field), frames at 240 per second to 0.45 s:
# the pattern's growth rate and wavelength as it is born, against linear theory's
# fastest-growing mode (scripts/bench/field_jump.py).
echo "spacing_mm,box_mm,field_over_critical,m_over_mc,frames,rate_sim_per_s,lambda_sim_mm,lambda_late_mm,rate_nu_per_s,lambda_nu_mm,nu_eff_m2_s,rate_eff_per_s,lambda_eff_mm,nu_fit_m2_s,lambda_fit_mm,lambda_disp_mm,sim_cpu_s" \
  > "$out/field_jump.csv"
echo "spacing_mm,box_mm,field_over_critical,wavelength_mm,rate_sim_per_s,rate_nu_per_s,rate_eff_per_s" > "$out/field_dispersion.csv"
for c in $jumps; do
  IFS=: read -r s r box <<< "$c"
  box="${box:-24}"
  H="$(awk -v r="$r" -v c="$critical" 'BEGIN { printf "%d", r * c + 0.5 }')"
  L="$(awk -v b="$box" 'BEGIN { printf "%g", b / 1e3 }')"
  wide=()   # the 24 mm box is the scene's own (and keeps its cache key)
  [[ "$box" == 24 ]] || wide=("fluid.block.0.max=[$L,$L,0.005]" "container.max=[$L,$L,0.03]")
  simulate "$hold_scene" "fluid.spacing=$s" "${wide[@]}" shot.fps=240 shot.duration=0.45 magnets.0.keys.2.time=0.301 \
    "magnets.0.keys.2.field=$H" "magnets.0.keys.3.field=$H" "magnets.0.keys.4.field=$H" "magnets.0.keys.5.field=$H"
  # One window a frame, 0.3-0.45 s at 240 frames a second, labelled by its time.
  mapfile -t windows < <(awk 'BEGIN { for (i = 72; i <= 108; ++i)
    printf "--window\nt%.5f:%.5f:%.5f\n", i / 240, i / 240 - 0.001, i / 240 + 0.001 }')
  python3 "$root/scripts/bench/spike_profile.py" "$dir" --period "$L,$L" "${windows[@]}" \
    --spectrum-csv "$work/spectrum.csv" > "$work/jump.txt"
  row="$(python3 "$root/scripts/bench/field_jump.py" "$work/jump.txt" --scene "$hold_scene" --jump 0.301 --ratio "$r" --spacing "$s" \
    --spectrum "$work/spectrum.csv" --dispersion-csv "$work/dispersion.csv")" ||
    { bench_note "jump $c: no growth to measure"; continue; }
  tail -n +2 "$work/dispersion.csv" | awk -v s="$s" -v b="$box" -v r="$r" '{ printf "%g,%s,%s,%s\n", s * 1e3, b, r, $0 }' \
    >> "$out/field_dispersion.csv"
  echo "$row,$(printf '%.0f' "$cpu")" | awk -F, -v OFS=, -v box="$box" '{ $1 = $1 OFS box; print }' >> "$out/field_jump.csv"
done

if command -v gnuplot > /dev/null; then
  for s in $spacings; do
    mm="$(awk -v s="$s" 'BEGIN { printf "%g", s * 1e3 }')"
    awk -F, -v mm="$mm" 'NR > 1 && $1 == mm && $5 == "up" { print $7, $12 }' "$out/field_sweep.csv" > "$work/up_$mm.dat"
    awk -F, -v mm="$mm" 'NR > 1 && $1 == mm && $5 == "down" { print $7, $12 }' "$out/field_sweep.csv" > "$work/down_$mm.dat"
  done
  plots=""
  for s in $spacings; do
    mm="$(awk -v s="$s" 'BEGIN { printf "%g", s * 1e3 }')"
    plots+="'$work/up_$mm.dat' with linespoints title 'up, $mm mm', '$work/down_$mm.dat' with linespoints title 'down, $mm mm', "
  done
  gnuplot <<PLOT || bench_note "gnuplot failed: no plot"
set terminal pngcairo size 640,420
set output '$out/field_sweep.png'
set xlabel 'applied field / critical field (10.42 kA/m)'
set ylabel 'pattern height above the mean surface [mm]'
set key top left
set grid
plot ${plots%, }
PLOT
fi

# One spike's profile: the cut through the tallest peak of the last frame at 1.1 x critical on
# the way up, the surface against its fundamental Fourier mode.
python3 "$root/scripts/bench/spike_profile.py" --procedural 1,1.25,1.4,1.5,2,3,4,5 --spike-csv "$work/procedural_spike.csv" \
  > "$work/procedural.txt"
first_mm="$(awk -v s="${spacings%% *}" 'BEGIN { printf "%g", s * 1e3 }')"
awk -F, -v mm="$first_mm" 'NR > 1 && $1 == mm && $2 == "up_1.1" { print $3, $4, $5 }' "$out/field_profile_cut.csv" > "$work/cut_1.1.dat"
if command -v gnuplot > /dev/null && [[ -s "$work/cut_1.1.dat" ]]; then
  gnuplot <<PLOT || bench_note "gnuplot failed: no profile plot"
set terminal pngcairo size 640,420
set output '$out/field_profile.png'
set xlabel 'distance from the tip toward the nearest peak [mm]'
set ylabel 'surface height above the floor [mm]'
set key top left
set grid
plot '$work/cut_1.1.dat' using 1:2 with lines lw 2 title 'simulated, $first_mm mm, 1.1 x critical (up)', \
     '$work/cut_1.1.dat' using 1:3 with lines dt 2 title 'its fundamental Fourier mode'
PLOT
fi

# The mean spike of the standing plateaus at 1.1 and 1.3 x critical (up) against the fundamental's
# J0 and the procedural profile at sharpness 1.4 (the lab's 10 % bound) and 3.
awk -F, -v mm="$first_mm" 'NR > 1 && $1 == mm && $2 == "up_1.1" { print $3, $4, $5 }' "$out/field_spike.csv" > "$work/spike_1.1.dat"
awk -F, -v mm="$first_mm" 'NR > 1 && $1 == mm && $2 == "up_1.3" { print $3, $4 }' "$out/field_spike.csv" > "$work/spike_1.3.dat"
awk -F, 'NR > 1 && $1 == "p1.4" { print $2, $3 }' "$work/procedural_spike.csv" > "$work/spike_p1.4.dat"
awk -F, 'NR > 1 && $1 == "p3" { print $2, $3 }' "$work/procedural_spike.csv" > "$work/spike_p3.dat"
if command -v gnuplot > /dev/null && [[ -s "$work/spike_1.1.dat" ]]; then
  gnuplot <<PLOT || bench_note "gnuplot failed: no mean spike plot"
set terminal pngcairo size 640,420
set output '$out/field_spike.png'
set xlabel 'distance from the tip / wavelength of the fundamental'
set ylabel 'height above the mean level / tip height'
set key top right
set grid
plot '$work/spike_1.1.dat' using 1:3 with lines lw 2 dt 1 lc rgb 'black' title 'fundamental, J0(2 pi r / lambda)', \
     '$work/spike_1.1.dat' using 1:2 with linespoints lw 2 title 'simulated, $first_mm mm, 1.1 x critical', \
     '$work/spike_1.3.dat' using 1:2 with linespoints lw 2 title 'simulated, $first_mm mm, 1.3 x critical', \
     '$work/spike_p1.4.dat' using 1:2 with lines dt 2 title 'Ferro, sharpness 1.4', \
     '$work/spike_p3.dat' using 1:2 with lines dt 3 title 'Ferro, sharpness 3'
PLOT
fi

# The simulated dispersion relation of the wide box's jumps against linear theory at nu_eff.
if command -v gnuplot > /dev/null && awk -F, 'NR > 1 && $2 == 48 { found = 1 } END { exit !found }' "$out/field_dispersion.csv"; then
  plots=""
  for c in $(awk -F, 'NR > 1 && $2 == 48 { print $1 ":" $3 }' "$out/field_dispersion.csv" | sort -u -t: -k1,1gr -k2,2g); do
    IFS=: read -r mm r <<< "$c"
    awk -F, -v mm="$mm" -v r="$r" 'NR > 1 && $2 == 48 && $1 == mm && $3 == r && $4 <= 30 { print 2 * 3.14159265 / $4, $5, $7 }' \
      "$out/field_dispersion.csv" > "$work/disp_${mm}_$r.dat"
    plots+="'$work/disp_${mm}_$r.dat' using 1:2 with linespoints title 'simulated, $mm mm, $r x', "
    [[ "$mm" == 0.75 ]] && plots+="'$work/disp_${mm}_$r.dat' using 1:3 with lines dt 2 title 'theory at nu_eff, $r x', "
  done
  gnuplot <<PLOT || bench_note "gnuplot failed: no dispersion plot"
set terminal pngcairo size 720,460
set output '$out/field_dispersion.png'
set xlabel 'wavenumber k [1/mm]'
set ylabel 'growth rate [1/s]'
set key top right font ',9'
set grid
set xrange [0:2]
set yrange [0:*]
plot ${plots%, }
PLOT
fi

{
  echo "## Field sweep: the pattern against the field, up and down (issue 32)"
  echo
  echo "What ran: \`scripts/bench/field-sweep.sh\` on scripts/bench/field_sweep.toml: the periodic layer"
  echo "(5 mm, 24 x 24 mm box with periodic sides, examples/rosensweig_uniform.toml's fluid) with the"
  echo "csf tension and \`force = \"surface\"\`, the field in plateaus of 0.5 s from 0.8 to 1.3 times"
  echo "the critical 10.42 kA/m and back. Each row is the second half of a plateau: rms_h in"
  echo "spacings (a settled layer reads 0.13-0.17), the height is the peaks' mean apex above the mean"
  echo "surface (0 where a frame has no peak); a plateau stands with at least one peak and rms_h >= 0.35."
  echo
  printf '%s\n' "${summary[@]}"
  echo
  echo "| spacing mm | direction | field / critical | rms_h | peaks | nearest peak mm | height mm | stands |"
  echo "| ---: | --- | ---: | ---: | ---: | ---: | ---: | --- |"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $5, $7, $9, $10, $11, $12, ($13 == 1 ? "yes" : "no") }' \
    "$out/field_sweep.csv"
  echo
  [[ -f "$out/field_sweep.png" ]] && printf '\n%s\n' "![height against field](field_sweep.png)"
  echo
  echo "The holds (scripts/bench/field_hold.toml): from \"pattern\", the pattern made at 1.1 x critical"
  echo "(0.4-1.2 s), then the field held below the critical one for 2 s; from \"flat\", the field"
  echo "ramped straight to the held one and held 2.9 s. Mean over the last 0.25 s; \"before\" is the"
  echo "height over 0.9-1.2 s; it stands with at least one peak and rms_h >= 0.35 (a sunk layer"
  echo "reads 0.3-0.36 here, a settled one 0.13-0.17)."
  echo
  echo "| spacing mm | particles | sim CPU s | field / critical | from | rms_h | peaks | height mm | before mm | stands |"
  echo "| ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: | --- |"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9, ($10 == 1 ? "yes" : "no") }' \
    "$out/field_hold.csv"
  echo
  echo "### The spike's shape against the fundamental Fourier mode"
  echo
  echo "Gollwitzer et al. (J. Fluid Mech. 2007, arXiv nlin/0604009) measured that the fundamental"
  echo "Fourier mode (the sum of three cosines of the paper's eq. 13) approximates a spike's shape to"
  echo "within 10 % up to 40 % of the bifurcation parameter (1.18-1.4 x the critical induction, as that"
  echo "parameter is defined on B^2 or B). \`scripts/bench/spike_profile.py\` measures the standing plateaus"
  echo "above: the surface (the colour field's 0.5 level on a half-spacing grid), its fundamental (the"
  echo "band of box modes within 0.75-1.3 of the wavenumber, of at least two wavelengths across the"
  echo "box, that holds the most power), and per frame: ptp, the surface's peak-to-trough height;"
  echo "lambda, the band's wavelength (lambda_c = 9.16 mm); dev_max, the largest deviation from the"
  echo "fundamental over ptp (the lab's \"within 10 %\"; it also counts a few peaks of unequal height,"
  echo "so it cannot tell shape from disorder); dev_rms; below, the share of the variance in longer"
  echo "modes than the band (peaks of unequal height in a small box); above, the share in shorter"
  echo "modes (the harmonics that sharpen tips and flatten troughs: the shape); move, the RMS change"
  echo "between frames over ptp. Means over the plateau's second half. shape_dev, one spike's"
  echo "shape: the mean spike (the surface's azimuthal mean around each peak over the peak's own"
  echo "height above the mean level, averaged over the peaks and frames, in r / lambda) against"
  echo "J0(2 pi r / lambda), the fundamental's own profile about a tip; the largest difference out to"
  echo "half a wavelength. Each peak is scaled by its own height, so unequal peaks do not count."
  echo
  echo "| spacing mm | direction | field / critical | frames | ptp mm | lambda mm | dev_max | dev_rms | below | above | move | shape_dev |"
  echo "| ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  awk -F, 'NR > 1 { printf "| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12 }' \
    "$out/field_profile.csv"
  echo
  [[ -f "$out/field_profile.png" ]] && printf '%s\n\n' "![one spike's profile](field_profile.png)"
  [[ -f "$out/field_spike.png" ]] && printf '%s\n\n' "![the mean spike against the fundamental](field_spike.png)"
  echo "Ferro's procedural profile (spikes/SpikePhysics.hpp, hexProfile sharpened with exponent p, the"
  echo "\`sharpness\` key) by the same measures, on one periodic cell of its lattice (no longer modes:"
  echo "every deviation is above the band):"
  echo
  echo "| sharpness p | dev_max | dev_rms | above | shape_dev |"
  echo "| ---: | ---: | ---: | ---: | ---: |"
  awk 'NR > 1 { printf "| %s | %s | %s | %s | %s |\n", $1, $2, $3, $4, $5 }' "$work/procedural.txt"
  echo
  echo "### The pattern as it is born: field jumps against the fastest-growing mode"
  echo
  echo "The flat layer's field switched from 0 to a field above critical at 0.301 s (the hold scene,"
  echo "frames at 240 per second). The exponential phase: the first run of frames from 0.3 to 2 mm peak"
  echo "to trough, ended where the fundamental's wavelength jumps by over 10 % between frames; its"
  echo "growth rate (the slope of ln of the fundamental band's RMS amplitude) and the median"
  echo "wavelength of its fundamental; then the wavelength over the last five frames (0.43-0.45 s),"
  echo "after it has coarsened. Theory: linear stability's fastest-growing mode of a deep layer, at the"
  echo "scene's viscosity (5e-6 m^2/s); at nu_eff, the viscosity the simulator's step uses (the"
  echo "scene's plus 0.02 x 2 spacings x sqrt(2 g depth)), a prediction; and at nu_fit, the viscosity"
  echo "whose fastest rate is the simulated one. The 24 mm box holds wavelengths 24 / sqrt(m^2 + n^2) mm"
  echo "only: 8.49, 7.59, 6.66, 6.0, 5.82, 5.66, 5.37 near these; the 48 mm box half those steps."
  echo
  echo "| spacing mm | box mm | field / critical | M / M_c | frames | rate 1/s | lambda mm | lambda late mm | rate at nu 1/s | lambda at nu mm | nu_eff m^2/s | rate at nu_eff 1/s | lambda at nu_eff mm | nu_fit m^2/s | lambda at nu_fit mm | fastest simulated lambda mm | sim CPU s |"
  echo "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
  awk -F, 'NR > 1 { line = "|"; for (i = 1; i <= 17; ++i) line = line " " $i " |"; print line }' "$out/field_jump.csv"
  echo
  echo "The simulated dispersion relation (field_dispersion.csv, field_dispersion.png): every"
  echo "wavelength's growth rate, the slope of ln of its ring of box modes' RMS amplitude over the"
  echo "exponential phase's frames, beside linear theory's at nu and nu_eff. \"fastest simulated"
  echo "lambda\" is where it peaks (a parabola through the fastest ring of at least 4 mm and its"
  echo "neighbours). Wavelengths the theory calls stable still grow in the simulation: the"
  echo "harmonics of the growing pattern and, at the box scale, its slow modulation."
  [[ -f "$out/field_dispersion.png" ]] && printf '\n%s\n' "![the simulated dispersion relation](field_dispersion.png)"
} > "$out/field-sweep.md"
bench_note "wrote $out/field_sweep.csv and $out/field-sweep.md"
