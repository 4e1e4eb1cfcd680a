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
  local root="$1" bad=0 file folder inc target ok a
  [ -d "$root/core/src" ] || { echo "check_layers: no core/src under $root" >&2; return 2; }
  # Core's folders.
  for folder in "$root"/core/src/* "$root"/core/include/burnish/core/*; do
    [ -d "$folder" ] || continue
    local name; name=$(basename "$folder")
    if [ -z "$(allowed "$name")" ]; then
      echo "check_layers: core folder '$name' has no place in the order (add it to tests/check_layers.sh)"
      bad=1
      continue
    fi
    while IFS= read -r -d '' file; do
      while IFS= read -r inc; do
        target=""
        if [[ "$inc" =~ ^\#include[[:space:]]*\<burnish/core/([a-z_]+)/ ]]; then
          target="${BASH_REMATCH[1]}"
        elif [[ "$inc" =~ ^\#include[[:space:]]*\"([a-z_]+)/ ]]; then
          target="${BASH_REMATCH[1]}"
          case " $concerns " in *" $target "*) ;; *) target="" ;; esac
        fi
        [ -n "$target" ] || continue
        ok=0
        for a in $(allowed "$name"); do [ "$a" = "$target" ] && ok=1; done
        if [ "$ok" = 0 ]; then
          echo "${file#"$root"/} -> $inc (core/$name may include only: $(allowed "$name"))"
          bad=1
        fi
      done < <(grep -E '^#include' "$file")
    done < <(find "$folder" -type f \( -name '*.h' -o -name '*.cpp' \) -print0)
  done
  # Between the layers.
  local hits
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
