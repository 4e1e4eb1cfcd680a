#!/usr/bin/env bash
# The speed of `burnish evaluate` against the NumPy implementation of the same metric
# (evaluate_numpy.py), measured in one run on one map: the median of RUNS runs of each, end to end
# (load, evaluation, bake timings, shading costs, report and plots for burnish; load and evaluation
# for NumPy), and burnish's own evaluation time. Figures, not a pass/fail test: the machine is shared.
#
#   core/bench/evaluate_speed.sh BURNISH MAP [POWER] [RUNS]
#
# Issue 16's case: a 1024² map, one power, mips 1-4, naive, Toksvig, LEAN, CLEAN and vMF.
set -euo pipefail
bin=$1
map=$2
power=${3:-256}
runs=${4:-3}
methods=naive,toksvig,lean,clean,vmf
here=$(cd "$(dirname "$0")" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

median() { sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
now() { date +%s.%N; }

: >"$work/burnish" && : >"$work/eval" && : >"$work/numpy"
for _ in $(seq "$runs"); do
    start=$(now)
    "$bin" evaluate "$map" --power "$power" --methods "$methods" --out "$work/out" --force --json >"$work/report.json"
    awk -v a="$(now)" -v b="$start" 'BEGIN {print a - b}' >>"$work/burnish"
    /usr/bin/python3 -c "import json; print(json.load(open('$work/report.json'))['evaluation_seconds'])" >>"$work/eval"
    start=$(now)
    /usr/bin/python3 "$here/evaluate_numpy.py" "$map" --power "$power" --methods "$methods" >/dev/null
    awk -v a="$(now)" -v b="$start" 'BEGIN {print a - b}' >>"$work/numpy"
done
b=$(median <"$work/burnish")
e=$(median <"$work/eval")
n=$(median <"$work/numpy")
echo "map $(basename "$map"), power $power, mips 1-4, $methods; median of $runs runs"
printf '| | seconds |\n| --- | ---: |\n'
printf '| burnish evaluate, end to end | %.3f |\n' "$b"
printf '| of which the evaluation | %.3f |\n' "$e"
printf '| evaluate_numpy.py, end to end | %.3f |\n' "$n"
awk -v n="$n" -v b="$b" -v e="$e" \
    'BEGIN {printf "NumPy / burnish: %.1f end to end; NumPy end to end / burnish evaluation: %.1f\n", n / b, n / e}'
