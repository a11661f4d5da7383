#!/bin/bash
# bench/integrators/run.sh [BUILD_DIR] [REPEATS] - error against CPU time per integrator and
# time-step factor (bench_integrators) -> results/integrators.csv, docs/integrators.png and the
# markdown table printed for bench/RESULTS.md.
set -e
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-$here/../../build}
reps=${2:-3}
mkdir -p "$here/results"
"$build/bench/bench_integrators" "$reps" | grep '^csv,' > "$here/results/integrators.csv"
/usr/bin/python3 "$here/plot.py" "$here/results/integrators.csv" "$here/../../docs/integrators.png"
