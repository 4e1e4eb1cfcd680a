#!/usr/bin/env bash
# Includes run one way. Between the layers: app → render → core (core includes neither render, app, Qt
# nor OpenGL; render includes neither app nor Qt). Inside core, folder by folder:
#
#   util → io → shading → prefilter → bake → eval → jobs,   env beside bake: util, io, shading, prefilter
#
# a folder includes only itself and the folders before it (env: itself, util, io, shading, prefilter;
# nothing but env includes env). Both kinds of include count: <burnish/core/F/…> and a private header
# "F/…" of src/F. Prints every back arrow as `file -> include` and exits 1 when there is one.
#
#   tests/check_layers.sh [ROOT]      ROOT: the source tree (default: this script's repository)
#   tests/check_layers.sh --self-test plants a back include in a copy of core/ and expects a failure
set -uo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"

# The folders each core folder may include, itself first.
allowed() {
  case "$1" in
    util) echo "util" ;;
    io) echo "io util" ;;
    shading) echo "shading util io" ;;
    prefilter) echo "prefilter util io shading" ;;
    bake) echo "bake util io shading prefilter" ;;
    eval) echo "eval util io shading prefilter bake" ;;
    jobs) echo "jobs util io shading prefilter bake eval" ;;
    env) echo "env util io shading prefilter" ;;
    *) echo "" ;;
  esac
}
concerns="util io shading prefilter bake eval jobs env"

check() {
  local root="$1" bad=0 hits
  [ -d "$root/core/src" ] || { echo "check_layers: no core/src under $root" >&2; return 2; }
  # Core's folders: every include line of every file, read in one pass.
  local table="" c
  for c in $concerns; do table+="$c=$(allowed "$c" | tr ' ' ,);"; done
  hits=$(cd "$root/core" && grep -rnE --include='*.h' --include='*.cpp' '^#include' src include/burnish/core |
    awk -v table="$table" -v concerns=" $concerns " '
      BEGIN { n = split(table, rows, ";"); for (i = 1; i <= n; i++) if (rows[i] != "") {
                split(rows[i], kv, "="); allowed[kv[1]] = kv[2] } }
      {
        split($0, parts, ":"); file = parts[1]
        folder = file; sub(/^src\//, "", folder); sub(/^include\/burnish\/core\//, "", folder); sub(/\/.*/, "", folder)
        line = substr($0, length(parts[1]) + length(parts[2]) + 3)
        if (!(folder in allowed)) { unknown[folder] = 1; next }
        target = ""
        if (match(line, /^#include[ \t]*<burnish\/core\/[a-z_]+\//)) {
          target = substr(line, RSTART, RLENGTH); sub(/.*<burnish\/core\//, "", target); sub(/\/$/, "", target)
        } else if (match(line, /^#include[ \t]*"[a-z_]+\//)) {
          target = substr(line, RSTART, RLENGTH); sub(/.*"/, "", target); sub(/\/$/, "", target)
          if (index(concerns, " " target " ") == 0) target = ""
        }
        if (target == "") next
        if (index("," allowed[folder] ",", "," target ",") == 0)
          printf "core/%s -> %s (core/%s may include only: %s)\n", file, line, folder, allowed[folder]
      }
      END { for (f in unknown) printf "check_layers: core folder %s has no place in the order (add it to tests/check_layers.sh)\n", f }')
  [ -n "$hits" ] && { echo "$hits"; bad=1; }
  # Between the layers.
  hits=$(grep -rnE '^#include[[:space:]]*[<"](burnish/(render|app)/|Q[A-Za-z]+[>/.]|epoxy/|GL/|EGL/)' \
    "$root/core/src" "$root/core/include" 2>/dev/null)
  [ -n "$hits" ] && { echo "core includes a layer above it or a GUI library:"; echo "${hits//"$root"\//}"; bad=1; }
  if [ -d "$root/render" ]; then
    hits=$(grep -rnE '^#include[[:space:]]*[<"](burnish/app/|Q[A-Za-z]+[>/.])' "$root/render" 2>/dev/null)
    [ -n "$hits" ] && { echo "render includes the app or Qt:"; echo "${hits//"$root"\//}"; bad=1; }
  fi
  return $bad
}

if [ "${1:-}" = "--self-test" ]; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  mkdir -p "$tmp/core"
  cp -r "$here/core/src" "$here/core/include" "$tmp/core/"
  check "$tmp" >/dev/null || { echo "check_layers --self-test: the tree as it is fails"; check "$tmp"; exit 1; }
  # A back arrow of each kind: a public header, a private one, and a layer.
  fail=0
  for plant in 'io/image_io.cpp:#include <burnish/core/bake/export.h>' \
               'shading/color.cpp:#include "eval/lobe_values.h"' \
               'prefilter/gloss.cpp:#include <burnish/core/env/cube.h>' \
               'util/files.cpp:#include <QFile>'; do
    f="$tmp/core/src/${plant%%:*}"
    cp "$f" "$f.orig"
    printf '%s\n' "${plant#*:}" >> "$f"
    if check "$tmp" >/dev/null; then
      echo "check_layers --self-test: '${plant#*:}' in ${plant%%:*} was not caught"
      fail=1
    fi
    mv "$f.orig" "$f"
  done
  [ "$fail" = 0 ] && echo "check_layers --self-test: every planted back include was caught"
  exit $fail
fi

root="${1:-$here}"
check "$root"
status=$?
[ "$status" = 0 ] && echo "check_layers: every include runs one way (util → io → shading → prefilter → bake → eval → jobs; env beside bake)"
exit $status
