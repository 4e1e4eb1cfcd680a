#!/usr/bin/env bash
# Every command's memory estimate beside its measured peak (figures, not pass/fail): each run is made
# twice, once with BURNISH_MEMORY_LIMIT=1 (the command refuses and names its estimate, "needs about X"),
# once under GNU time (its peak resident set). The estimates are meant to stay within 1.5x of the peak
# both ways; tests/core/test_memory.cpp and tests/render/test_renderer.cpp (RenderMemory) hold the
# figures this prints.
#
#   core/bench/command_memory.sh BURNISH_BINARY NORMAL_MAP ENVIRONMENT_EXR [SIZES]
#
# SIZES (default "512 1024 2048"): the map is resized to each SIZE² with oiiotool.
set -euo pipefail
bin="$1" map="$2" envmap="$3" sizes="${4:-512 1024 2048}"
command -v oiiotool >/dev/null || { echo "command_memory: oiiotool not found (Debian: openimageio-tools)" >&2; exit 2; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The estimate a command states when it may use 1 byte, in MB.
estimate() {
  local line
  line=$(BURNISH_MEMORY_LIMIT=1 "$bin" "$@" 2>&1 >/dev/null | grep -o 'needs about [0-9.]* [MG]B' | head -1)
  [ -n "$line" ] || { echo "?"; return; }
  echo "$line" | awk '{ v = $3; if ($4 == "GB") v *= 1000; printf "%.0f", v }'
}
# The peak resident set of a run, in MB (decimal).
peak() {
  local kb
  kb=$(/usr/bin/time -f %M "$bin" "$@" 2>&1 >/dev/null | tail -1)
  echo "$kb" | awk '{ printf "%.1f", $1 * 1024 / 1e6 }'
}
row() {
  local label="$1"
  shift
  local e m
  e=$(estimate "$@")
  m=$(peak "$@")
  printf "%-44s %10s %10s %7s\n" "$label" "$e" "$m" "$(awk -v e="$e" -v m="$m" 'BEGIN { if (e + 0 > 0) printf "%.2f", e / m; else print "-" }')"
}

printf "%-44s %10s %10s %7s\n" command "estimate" "peak MB" "ratio"
for size in $sizes; do
  oiiotool "$map" --resize "${size}x${size}" -o "$work/m$size.png"
  oiiotool "$work/m$size.png" --ch R -o "$work/g$size.png"
  m="$work/m$size.png"
  row "bake $size² godot" bake "$m" --preset godot --force --out "$work/b"
  row "bake $size² mixture" bake "$m" --preset mixture --force --out "$work/b"
  row "evaluate $size²" evaluate "$m" --json
  row "render $size² 512x512" render "$m" --force --out "$work/r.png"
done
m="$work/m1024.png"
[ -f "$m" ] || { oiiotool "$map" --resize 1024x1024 -o "$m"; oiiotool "$m" --ch R -o "$work/g1024.png"; }
[ -f "$work/m2048.png" ] || oiiotool "$map" --resize 2048x2048 -o "$work/m2048.png"
row "bake 1024² godot --detail 2048²" bake "$m" --preset godot --detail "$work/m2048.png" --force --out "$work/b"
row "evaluate 1024² --between-texels" evaluate "$m" --between-texels --json
row "evaluate 1024² --lobes 1,2,3,4" evaluate "$m" --lobes 1,2,3,4 --json
row "evaluate 1024² --gloss" evaluate "$m" --gloss "$work/g1024.png" --json
row "render 1024² --method mixture" render "$m" --method mixture --force --out "$work/r.png"
row "render 1024² --method lean" render "$m" --method lean --force --out "$work/r.png"
row "render 1024² --size 2048x2048" render "$m" --size 2048x2048 --force --out "$work/r.png"
row "render 2048² --reference 16" render "$work/m2048.png" --reference 16 --force --out "$work/r.png"
for face in 256 512 1024 2048; do
  row "env face $face ($(basename "$envmap"))" env "$envmap" --face-size "$face" --force --out "$work/e"
done
row "env face 512 (procedural studio)" env --face-size 512 --force --out "$work/e"
