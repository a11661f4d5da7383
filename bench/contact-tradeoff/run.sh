#!/bin/sh
# contact-tradeoff: floe ADMM (tolerances 1e-2..1e-10, cold/warm) and polytope LP against
# libccd MPR and GJK+EPA on the peer's pair sets, one thread; prints the table (and CSV
# lines) to stdout. NPAIRS (default 2000) and REPS (default 3) as in the peer benchmark.
# Then: /usr/bin/python3 bench/contact-tradeoff/plot.py OUTPUT_FILE -> docs/contact-tradeoff.png
set -e
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
NPAIRS=${NPAIRS:-2000}
REPS=${REPS:-3}
cmake --build "$BUILD" --target bench_contact_tradeoff >/dev/null
OMP_NUM_THREADS=1 taskset -c 0 "$BUILD/bench/bench_contact_tradeoff" "$NPAIRS" "$REPS" 2>/dev/null \
  || OMP_NUM_THREADS=1 "$BUILD/bench/bench_contact_tradeoff" "$NPAIRS" "$REPS"
