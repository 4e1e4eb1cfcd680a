#!/usr/bin/env bash
# Benchmark (figures, not pass/fail): `burnish bake` of a 4096² 8-bit normal map, every method but the
# mixture (the fitted lobe with the gltf preset: its GGX fit),
# all mips, written as PNG16, against OpenImageIO's `maketx` building a mip-mapped texture of the
# same PNG — both measured in one run, with their ratio and peak memory (/usr/bin/time -v).
#
#   [REPEATS=3] core/bench/bake_vs_maketx.sh [NORMAL_MAP] [BUILD_DIR]
#
# NORMAL_MAP (default: ../shared/data/normal-maps/trak-brick1_nm.png) is tiled to 4096².
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
src="${1:-$root/../shared/data/normal-maps/trak-brick1_nm.png}"
build="${2:-$root/build}"
burnish="$build/bin/burnish"
[ -x "$burnish" ] || { echo "bake_vs_maketx: build burnish first ($burnish missing)" >&2; exit 1; }
command -v maketx >/dev/null || { echo "bake_vs_maketx: maketx not found (Debian: openimageio-tools)" >&2; exit 1; }
[ -x /usr/bin/time ] || { echo "bake_vs_maketx: /usr/bin/time not found (Debian: time)" >&2; exit 1; }

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# Tile to 4096² (RGB only, alpha read unassociated so it does not scale the vectors).
oiiotool -iconfig oiio:UnassociatedAlpha 1 "$src" --ch R,G,B -o "$work/t1.png"
size=$(oiiotool --info "$work/t1.png" | sed -E 's/.*: *([0-9]+) x.*/\1/')
cur="$work/t1.png"
while [ "$size" -lt 4096 ]; do
  oiiotool "$cur" "$cur" "$cur" "$cur" --mosaic 2x2 -o "$work/t$((size*2)).png"
  cur="$work/t$((size*2)).png"; size=$((size*2))
done
oiiotool "$cur" --cut 4096x4096+0+0 -o "$work/map.png"
echo "input: $src tiled to $(oiiotool --info "$work/map.png" | sed -E 's/^[^:]*: *//')"

# REPEATS (default 3): each command runs that many times and its median time is kept, so a
# machine shared with other jobs gives steadier figures.
repeats="${REPEATS:-3}"
measure() { # label, command...: prints "label median-seconds cpu-seconds peakKiB"
  local label="$1"; shift
  : > "$work/runs.txt"
  for _ in $(seq "$repeats"); do
    /usr/bin/time -f "%e %U %S %M" -o "$work/time.txt" "$@" >/dev/null 2>"$work/err.txt" || { cat "$work/err.txt" >&2; exit 1; }
    cat "$work/time.txt" >> "$work/runs.txt"
  done
  read -r secs cpu kib < <(sort -g "$work/runs.txt" | awk '{r[NR]=$0} END {split(r[int((NR+1)/2)], f, " "); print f[1], f[2]+f[3], f[4]}')
  printf '%-28s %8.2f s (median of %d) %8.2f s cpu %10d KiB peak\n' "$label" "$secs" "$repeats" "$cpu" "$kib"
  echo "$secs" > "$work/$label.secs"
}

measure maketx maketx "$work/map.png" -o "$work/map.tx"
total=0
for method in naive toksvig toksvig-map variance-to-gloss lean clean vmf fitted; do
  case "$method" in
    toksvig-map|lean|clean) preset="$method" ;;
    fitted) preset=gltf ;; # the GGX fit, as the roughness presets bake it
    *) preset=blackops ;;
  esac
  measure "bake-$method" "$burnish" bake "$work/map.png" --preset "$preset" --method "$method" \
    --format png16 --out "$work/out-$method" --force
  total=$(python3 -c "print($total + $(cat "$work/bake-$method.secs"))")
done
maketx_s=$(cat "$work/maketx.secs")
python3 - "$maketx_s" "$total" <<'PY'
import sys
m, b = float(sys.argv[1]), float(sys.argv[2])
print(f"all eight bakes: {b:.2f} s; maketx: {m:.2f} s; ratio per bake (mean) / maketx = {b / 8 / m:.2f}")
PY
