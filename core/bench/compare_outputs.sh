#!/usr/bin/env bash
# Output comparison for refactors and speed changes (figures, not pass/fail in CI): run one
# `burnish` binary over the real maps of ../shared/data and write every output into a folder,
# then compare two such folders file by file.
#
#   core/bench/compare_outputs.sh run BURNISH_BINARY OUT_DIR   # bake sets, evaluations, renders, env
#   core/bench/compare_outputs.sh bake BURNISH_BINARY OUT_DIR  # the bake sets only
#   core/bench/compare_outputs.sh diff OLD_DIR NEW_DIR         # exit 0 when every output is the same
#
# `run` writes: every preset's default set for each map of ../shared/data/normal-maps; every
# method in every format for one map; `evaluate --json` at three powers, and with the box and
# gaussian kernels and error maps at one power, on two maps; `render` of the default scene for
# every method, with environment lighting and the reference; `env` of both environments.
# Timings (any JSON key naming seconds, ns or a median of timed runs) are removed from the JSON,
# so what is compared is what the program computed.
# `diff` compares bytes; PNGs whose bytes differ are compared by pixel (idiff) and listed apart.
set -uo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
data="${BURNISH_DATA:-$root/../shared/data}"
command -v jq >/dev/null || { echo "compare_outputs: jq not found (Debian: jq)" >&2; exit 2; }

# Drops timing keys from a JSON file in place.
untime() {
  jq -S 'walk(if type == "object" then with_entries(select(.key | test("(?i)seconds|_ns|nsPer|ns_per|timing|median") | not)) else . end)' \
    "$1" > "$1.tmp" && mv "$1.tmp" "$1"
}

run() {
  local bin="$1" out="$2"
  [ -x "$bin" ] || { echo "compare_outputs: $bin is not executable" >&2; exit 2; }
  mkdir -p "$out"
  local maps=("$data"/normal-maps/*.png)
  local presets methods
  presets=$("$bin" bake --help | sed -n '/^Presets/,/^Methods/p' | grep -E '^  [a-z]' | awk '{print $1}')
  methods=$("$bin" bake --help | sed -n '/^Methods/,/^Formats/p' | grep -E '^  [a-z]' | awk '{print $1}')
  mkdir -p "$out/bake" "$out/formats"
  for map in "${maps[@]}"; do
    local stem; stem=$(basename "$map" .png)
    for p in $presets; do
      "$bin" bake "$map" --preset "$p" --out "$out/bake/$stem/$p" >/dev/null 2>"$out/bake/$stem.$p.err" ||
        echo "failed" >> "$out/bake/$stem.$p.err"
    done
  done
  local one="${maps[0]}"
  for m in $methods; do
    for f in png8 png16 tga exr-half exr-float tiff16 tiff-float dds; do
      # The method's own preset where there is one (lean, clean, toksvig-map), else blackops.
      local p=blackops
      if grep -qx "$m" <<< "$presets"; then p="$m"; fi
      "$bin" bake "$one" --preset "$p" --method "$m" --format "$f" --out "$out/formats/$m-$f" >/dev/null \
        2>"$out/formats/$m-$f.err" || echo "failed" >> "$out/formats/$m-$f.err"
    done
  done
  # Every DDS compression on the methods' own presets.
  for p in $presets; do
    for c in bc3 bc4 bc5 rgba8 rgba16f; do
      "$bin" bake "$one" --preset "$p" --format dds --compression "$c" --allow-8bit --out "$out/formats/$p-dds-$c" \
        >/dev/null 2>"$out/formats/$p-dds-$c.err" || echo "failed" >> "$out/formats/$p-dds-$c.err"
    done
  done
  find "$out/bake" "$out/formats" -name bake.json | while read -r j; do untime "$j"; done
  [ "$bakeOnly" = 1 ] && { echo "compare_outputs: $(find "$out" -type f | wc -l) files in $out"; return; }
  mkdir -p "$out/evaluate"
  for map in "${maps[0]}" "${maps[2]:-${maps[0]}}"; do
    local stem; stem=$(basename "$map" .png)
    "$bin" evaluate "$map" --power 64 --power 256 --power 1024 --bake-runs 1 \
      --json --out "$out/evaluate/$stem" > "$out/evaluate/$stem.json" 2>"$out/evaluate/$stem.err"
    "$bin" evaluate "$map" --power 256 --kernels box,gaussian --bake-runs 1 --error-maps \
      --json --out "$out/evaluate/$stem-kernels" > "$out/evaluate/$stem-kernels.json" 2>"$out/evaluate/$stem-kernels.err"
    untime "$out/evaluate/$stem.json"
    untime "$out/evaluate/$stem-kernels.json"
    find "$out/evaluate/$stem" "$out/evaluate/$stem-kernels" -name '*.json' | while read -r j; do untime "$j"; done
    # Markdown reports carry timings in their text, and the error-against-cost plot has measured
    # shading time on its axis; the JSON above holds the same figures without the timings.
    find "$out/evaluate/$stem" "$out/evaluate/$stem-kernels" \( -name '*.md' -o -name '*error-vs-cost.png' \) -delete
  done
  mkdir -p "$out/render"
  for m in $methods; do
    "$bin" render "${maps[1]:-${maps[0]}}" --method "$m" --size 256x256 --out "$out/render/$m.png" \
      >/dev/null 2>"$out/render/$m.err"
    "$bin" render --method "$m" --size 256x256 --env "$data/environments/studio.exr" \
      --out "$out/render/$m-env.exr" >/dev/null 2>"$out/render/$m-env.err"
  done
  "$bin" render "${maps[1]:-${maps[0]}}" --reference 16 --size 256x256 --out "$out/render/reference.png" \
    >/dev/null 2>"$out/render/reference.err"
  mkdir -p "$out/env"
  for e in "$data"/environments/*.exr; do
    local stem; stem=$(basename "$e" .exr)
    "$bin" env "$e" --out "$out/env/$stem" --face-size 64 >/dev/null 2>"$out/env/$stem.err"
    find "$out/env/$stem" -name '*.json' | while read -r j; do untime "$j"; done
  done
  echo "compare_outputs: $(find "$out" -type f | wc -l) files in $out"
}

diffdirs() {
  local a="$1" b="$2" same=0 pixels=0 differ=0
  local list; list=$( (cd "$a" && find . -type f; cd "$b" && find . -type f) | sort -u)
  while read -r f; do
    if [ ! -f "$a/$f" ] || [ ! -f "$b/$f" ]; then
      echo "only in one: $f"; differ=$((differ + 1))
    elif cmp -s "$a/$f" "$b/$f"; then
      same=$((same + 1))
    elif [[ "$f" == *.png ]] && idiff -a "$a/$f" "$b/$f" >/dev/null 2>&1; then
      pixels=$((pixels + 1))
    else
      echo "differs: $f"; differ=$((differ + 1))
    fi
  done <<< "$list"
  echo "compare_outputs: $same byte-identical, $pixels pixel-identical PNGs, $differ different"
  [ "$differ" -eq 0 ]
}

case "${1:-}" in
  run) bakeOnly=0 run "$2" "$3" ;;
  bake) bakeOnly=1 run "$2" "$3" ;;
  diff) diffdirs "$2" "$3" ;;
  *) sed -n '2,14p' "$0" >&2; exit 2 ;;
esac
