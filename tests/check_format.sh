#!/usr/bin/env bash
# Fails (listing the files) when a tracked C++ file is not in the style of the root .clang-format.
set -u
cd "$(dirname "$0")/.." || exit 2
bad=$(git ls-files '*.h' '*.cpp' | while read -r f; do
  clang-format --dry-run --Werror "$f" >/dev/null 2>&1 || echo "$f"
done)
if [ -n "$bad" ]; then
  printf 'not in clang-format style (run clang-format -i on them):\n%s\n' "$bad"
  exit 1
fi
echo "all C++ files in clang-format style"
