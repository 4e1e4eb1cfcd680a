#!/usr/bin/env bash
# Runs one libFuzzer target from its seed corpus for a fixed time and fails on any finding.
#
#   tests/fuzz/run.sh --target BIN --corpus SEEDS --work DIR [--seconds N] [--seed S]
#   tests/fuzz/run.sh --all BUILD_DIR [--seconds N] [--seed S]  # every target of a build, in turn
#
# --seed fixes libFuzzer's random seed, so a run mutates the same inputs in the same order and a
# rerun reproduces it (CTest passes BURNISH_FUZZ_SEED: CI's verdict does not depend on the luck of
# the draw); without it each run draws a fresh seed, which the long runs that look for new findings
# want. The seed in use is in the log's first lines ("Seed: S").
#
# SEEDS (the repository's corpus) is only read: new inputs go to DIR/corpus, a reproducer of a
# finding to DIR/crash-*, and the log to DIR/log.txt. The long run the project documents is
# `tests/fuzz/run.sh --all build-asan --seconds 3600`; a finding's reproducer belongs in
# tests/fuzz/corpus/<target>/ once fixed, so every later run replays it.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
seconds=30
target="" corpus="" work="" all="" seed=""
while [ $# -gt 0 ]; do
  case "$1" in
    --target) target="$2"; shift 2 ;;
    --corpus) corpus="$2"; shift 2 ;;
    --work) work="$2"; shift 2 ;;
    --seconds) seconds="$2"; shift 2 ;;
    --all) all="$2"; shift 2 ;;
    --seed) seed="$2"; shift 2 ;;
    *) echo "run.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done

if [ -n "$all" ]; then
  status=0
  for bin in "$all"/fuzz/fuzz_*; do
    [ -x "$bin" ] || continue
    name="$(basename "$bin")"; name="${name#fuzz_}"
    "$0" --target "$bin" --corpus "$here/corpus/$name" --work "$all/fuzz/$name" --seconds "$seconds" \
      ${seed:+--seed "$seed"} || status=1
  done
  exit $status
fi

[ -x "$target" ] && [ -d "$corpus" ] && [ -n "$work" ] || { echo "run.sh: need --target, --corpus and --work" >&2; exit 2; }
rm -rf "$work/corpus"
mkdir -p "$work/corpus"
# Leaks inside third-party libraries are suppressed as in the other sanitizer tests; a finding
# stops the run (libFuzzer's exit code is non-zero) and leaves its input as crash-*, leak-*,
# timeout-* or oom-* in $work.
export ASAN_OPTIONS="${ASAN_OPTIONS:-}:detect_leaks=1:allocator_may_return_null=1"
# The repository's suppressions (tests/lsan.supp) as CTest passes them, also when run by hand: without
# them OpenImageIO's per-reader error strings are reported as a leak after a failed read.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$here/../lsan.supp:print_suppressions=0}"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
set +e
"$target" "$work/corpus" "$corpus" -max_total_time="$seconds" -timeout=20 -rss_limit_mb=3072 \
  ${seed:+-seed="$seed"} -max_len=65536 -artifact_prefix="$work/" -print_final_stats=1 >"$work/log.txt" 2>&1
rc=$?
set -e
runs=$(grep -Eo 'stat::number_of_executed_units: *[0-9]+' "$work/log.txt" | grep -Eo '[0-9]+$' || echo 0)
used=$(grep -Eo 'Seed: [0-9]+' "$work/log.txt" | head -n 1 | grep -Eo '[0-9]+' || echo "?")
echo "fuzz $(basename "$target"): seed ${used}, ${seconds} s, ${runs} runs, corpus $(ls "$work/corpus" | wc -l) new inputs, exit $rc"
if [ $rc -ne 0 ]; then
  tail -n 60 "$work/log.txt"
  ls "$work" | grep -E '^(crash|leak|timeout|oom|slow-unit)-' || true
fi
exit $rc
