# Shared by the shell tests of tests/faults (sourced; needs $src, the source directory).
# same A B: the two outputs are the same, byte for byte, except a PNG, whose pixels are
# compared (POV-Ray stamps each PNG with its render time).
same() {
  case "$1" in
    *.png) python3 "$src/tests/tools/pngcheck.py" same "$1" "$2" 2> /dev/null ;;
    *) cmp -s "$1" "$2" ;;
  esac
}
# outputs DIR: the shot's outputs compared (particles, meshes, includes, scene files, frames),
# relative to DIR, sorted.
outputs() { (cd "$1" && find particles surface spiky shot png -type f \( -name '*.ply' -o -name '*.inc' -o -name '*.pov' -o -name '*.ini' -o -name '*.png' \) 2> /dev/null | LC_ALL=C sort); }
