#!/usr/bin/env bash
# Peak memory of `burnish bake` per texel of the input, for every preset (figures, not pass/fail):
# a map resized to SIZE² (default 2048) is baked with each preset's defaults (full chain, the
# preset's format), the peak resident set measured by GNU time. The bake's memory check
# (bakeBytesPerTexel in core/src/jobs/bake_job.cpp) must stay above these figures: the test
# BakeMemory.EstimateCoversTheMeasuredPeaksAndRefusesWhatCannotFit holds them (update it when they move).
#
#   core/bench/bake_memory.sh BURNISH_BINARY NORMAL_MAP [SIZE]
set -euo pipefail
bin="$1" map="$2" size="${3:-2048}"
command -v oiiotool >/dev/null || { echo "bake_memory: oiiotool not found (Debian: openimageio-tools)" >&2; exit 2; }
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
oiiotool "$map" --resize "${size}x${size}" -o "$work/map.png"
texels=$((size * size))
# The process's own footprint (code, libraries): what a 1x1 bake peaks at.
oiiotool "$map" --resize 1x1 -o "$work/one.png"
base=$(/usr/bin/time -f %M "$bin" bake "$work/one.png" --preset godot --allow-implausible --out "$work/one" 2>&1 >/dev/null | tail -1)
printf "%-12s %10s %14s\n" preset "peak MB" "bytes/texel"
printf "%-12s %10.1f %14s\n" "(1x1)" "$(echo "$base / 1024" | bc -l)" "-"
for preset in $("$bin" bake --help | sed -n '/^Presets/,/^Methods/p' | grep -E '^  [a-z]' | awk '{print $1}'); do
  kb=$(/usr/bin/time -f %M "$bin" bake "$work/map.png" --preset "$preset" --force --out "$work/$preset" 2>&1 >/dev/null | tail -1)
  printf "%-12s %10.1f %14.1f\n" "$preset" "$(echo "$kb / 1024" | bc -l)" "$(echo "($kb - $base) * 1024 / $texels" | bc -l)"
done
