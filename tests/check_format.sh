#!/usr/bin/env bash
# Fails (listing the files) when a tracked C++ file is not in the style of the root .clang-format.
# One clang-format process reads many files (one per file took ten times as long).
set -u
cd "$(dirname "$0")/.." || exit 2
command -v clang-format >/dev/null || { echo "check_format: clang-format not found" >&2; exit 2; }
out=$(git ls-files -z '*.h' '*.cpp' | xargs -0 -r clang-format --dry-run --Werror 2>&1)
status=$?
bad=$(printf '%s\n' "$out" | grep -oE '^[^:]+:[0-9]+:[0-9]+: error: code should be clang-formatted' | cut -d: -f1 | sort -u)
if [ -n "$bad" ]; then
  printf 'not in clang-format style (run clang-format -i on them):\n%s\n' "$bad"
  exit 1
fi
if [ "$status" != 0 ]; then
  printf 'clang-format failed:\n%s\n' "$out"
  exit 1
fi
echo "all C++ files in clang-format style"
