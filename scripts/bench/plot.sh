#!/usr/bin/env bash
# plot.sh: one cost-against-error plot of a benchmark CSV (gnuplot, PNG).
#
#   scripts/bench/plot.sh CSV XCOL YCOL PNG "title"
#
# CSV has a header row and one row per setting; the first column is the setting and labels
# each point. XCOL (the cost, plotted on a log scale) and YCOL (the error) are column names
# from the header or 1-based column numbers. Rows whose x is not a positive number (a failed
# or skipped setting) are left out, so the x log scale never sees a zero.
# Environment: PLOT_YLOG=1 also puts y on a log scale (rows with y <= 0, e.g. the reference
# itself, are then left out too).
# Exit codes: 4 missing CSV, 2 bad arguments or no such column, 3 gnuplot failed.
set -euo pipefail
die() { echo "plot.sh: error: $2" >&2; exit "$1"; }
[[ $# -eq 5 ]] || die 2 "usage: plot.sh CSV XCOL YCOL PNG \"title\""
csv="$1" xcol="$2" ycol="$3" png="$4" title="$5"
[[ -f "$csv" ]] || die 4 "$csv: no such file"
command -v gnuplot >/dev/null || die 3 "gnuplot is not installed (scripts/install-deps.sh --with-bench)"

header="$(head -n 1 "$csv")"
IFS=, read -r -a names <<< "$header"
# column_number NAME|NUMBER -> 1-based number
column_number() {
  if [[ "$1" =~ ^[0-9]+$ ]]; then
    (( $1 >= 1 && $1 <= ${#names[@]} )) || die 2 "$csv: no column $1 (it has ${#names[@]})"
    echo "$1"; return
  fi
  local i
  for i in "${!names[@]}"; do
    [[ "${names[$i]}" == "$1" ]] && { echo $((i + 1)); return; }
  done
  die 2 "$csv: no column '$1' (columns: $header)"
}
xi="$(column_number "$xcol")" yi="$(column_number "$ycol")"
xname="${names[$((xi - 1))]}" yname="${names[$((yi - 1))]}"

# The points gnuplot sees: label, x, y (positive finite x; positive y with PLOT_YLOG).
data="$(mktemp)"
trap 'rm -f "$data"' EXIT
awk -F, -v xi="$xi" -v yi="$yi" -v ylog="${PLOT_YLOG:-0}" '
  NR == 1 { next }
  function num(s) { return s ~ /^[ \t]*[-+]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?[ \t]*$/ }
  num($xi) && num($yi) && $xi + 0 > 0 && (ylog != 1 || $yi + 0 > 0) {
    label = $1; gsub(/"/, "", label); printf "\"%s\" %s %s\n", label, $xi, $yi
  }' "$csv" > "$data"
[[ -s "$data" ]] || die 2 "$csv: no row with a positive number in '$xname' and a number in '$yname'"

mkdir -p "$(dirname "$png")"
gnuplot > /dev/null 2> "$data.log" <<GNUPLOT || { cat "$data.log" >&2; rm -f "$data.log"; die 3 "gnuplot failed on $csv"; }
set terminal pngcairo size 640,420 font "sans,10"
set output "$png"
set datafile separator whitespace
set title "${title//\"/\\\"}"
set xlabel "$xname (log scale)" noenhanced
set ylabel "$yname" noenhanced
set logscale x
$([[ "${PLOT_YLOG:-0}" == 1 ]] && echo "set logscale y")
set grid
set key off
set offsets graph 0.05, graph 0.15, graph 0.08, graph 0.08
plot "$data" using 2:3 with linespoints pt 7 ps 1.2 lc rgb "#1f5fa8", \
     "" using 2:3:1 with labels offset char 0.8,0.8 left font "sans,9" noenhanced
GNUPLOT
rm -f "$data.log"
