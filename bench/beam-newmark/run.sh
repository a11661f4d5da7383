#!/usr/bin/env bash
# bench/beam-newmark: 004 §5 beam, explicit against implicit Newmark-beta at element sizes
# 0.05 (3 repetitions), 0.025, 0.014 (7,740 elements, the size of 004's 7,676) and 0.01;
# at the two finest sizes the explicit run stops early and its total is estimated from
# its median step (as 004 Table 1 does). Builds floe in build-bench (Release).
# Output: out/beam-newmark/ (VTU + CSV crack patterns), the log on stdout.
# THREADS (default 1): the solver's threads (floe_newmark_set_threads takes OMP_NUM_THREADS);
# the figures in bench/RESULTS.md before session 24 are one thread.
set -euo pipefail
export OMP_NUM_THREADS=${THREADS:-1}
cd "$(dirname "$0")/../.."
cmake -S . -B build-bench -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_BENCH=ON >/dev/null
cmake --build build-bench -j2 --target bench_beam_newmark >/dev/null
B=build-bench/bench/bench_beam_newmark
O=out/beam-newmark
for r in 1 2 3; do echo "== h=0.05 rep $r $(uptime)"; $B --h 0.05 --out $O/h0.05_r$r; done
echo "== h=0.025 $(uptime)"; $B --h 0.025 --out $O/h0.025
echo "== h=0.014 $(uptime)"; $B --h 0.014 --explicit-t-end 0.05 --out $O/h0.014
echo "== h=0.01 $(uptime)"; $B --h 0.01 --explicit-t-end 0.01 --out $O/h0.01
for h in 0.025 0.014 0.01; do
  echo "== crack patterns h=$h"
  python3 bench/beam-newmark/compare.py $O/h$h/bonds_explicit_h$h.csv $O/h$h/bonds_implicit_h$h.csv 0.005 0.01
done
