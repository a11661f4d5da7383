#!/bin/sh
# run.sh - floe k-d tree vs nanoflann 1.4.3: build both benchmarks, run them on the same
# points (N uniform in [0,1)^3, radius for 30 neighbours, leaf 10 and 20), print both
# result lines and the ratios floe/nanoflann (time ratios: below 1 means floe is faster).
# Environment: BUILD (CMake build dir for floe, default build-bench), REPS (default 3),
# NS (default "100000 1000000"), LEAVES (default "10 20"), FLOE_DIRECT=1 to compile
# core/base/kdtree.c directly with gcc instead of building the floe library with CMake.
set -eu
cd "$(dirname "$0")/../.."
BUILD=${BUILD:-build-bench}
REPS=${REPS:-3}
NS=${NS:-"100000 1000000"}
LEAVES=${LEAVES:-"10 20"}
bash scripts/install-deps.sh --bench   # g++, libnanoflann-dev (idempotent)
mkdir -p "$BUILD/kdtree"
PEER="$BUILD/kdtree/nanoflann_bench"
g++ -O3 -march=native -std=c++17 -o "$PEER" bench/kdtree/nanoflann_bench.cpp

FLOE=""
if [ "${FLOE_DIRECT:-0}" != 1 ]; then
  if cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=Release -DFLOE_NATIVE=ON -DFLOE_BUILD_BENCH=ON \
        -DFLOE_BUILD_TESTS=OFF -DFLOE_BUILD_EXAMPLES=OFF >"$BUILD/kdtree/cmake.log" 2>&1 &&
     cmake --build "$BUILD" --target bench_kdtree -j2 >>"$BUILD/kdtree/cmake.log" 2>&1; then
    FLOE="$BUILD/bench/bench_kdtree"
  else
    echo "note: CMake build of bench_kdtree failed (see $BUILD/kdtree/cmake.log); compiling kdtree.c directly" >&2
  fi
fi
if [ -z "$FLOE" ]; then
  FLOE="$BUILD/kdtree/kdtree_bench"
  gcc -O3 -march=native -std=c11 -Icore/base -o "$FLOE" bench/kdtree/kdtree_bench.c core/base/kdtree.c -lm
fi

LOG="$BUILD/kdtree/results.txt"
: >"$LOG"
for n in $NS; do
  for leaf in $LEAVES; do
    "$FLOE" "$n" "$leaf" "$REPS" | tee -a "$LOG"
    "$PEER" "$n" "$leaf" "$REPS" | tee -a "$LOG"
  done
done

echo
echo "ratios floe / nanoflann (time; < 1 = floe faster), memory in bytes per point:"
awk '
{ kv["lib"] = $1; for (i = 2; i <= NF; i++) { split($i, a, "="); kv[a[1]] = a[2] }
  key = kv["N"] " " kv["leaf"]
  if (kv["lib"] == "floe_kdtree") { fb[key] = kv["build_s"]; fq[key] = kv["query_s"]; fs[key] = kv["query_sorted_s"]; fm[key] = kv["mem_bytes_per_point"]; fc[key] = kv["checksum"] }
  else { nb[key] = kv["build_s"]; nq[key] = kv["query_s"]; ns[key] = kv["query_sorted_s"]; nm[key] = kv["mem_bytes_per_point"]; nc[key] = kv["checksum"]; order[++cnt] = key }
}
END {
  printf "%-8s %-5s %-13s %-20s %-20s %-11s %s\n", "N", "leaf", "build", "query random order", "query tree order", "mem floe", "mem nanoflann"
  for (j = 1; j <= cnt; j++) {
    k = order[j]; split(k, p, " ")
    printf "%-8s %-5s %-13.3f %-20.3f %-20.3f %-11s %s%s\n", p[1], p[2], fb[k] / nb[k], fq[k] / nq[k], fs[k] / ns[k], fm[k], nm[k], (fc[k] == nc[k] ? "" : "  (checksums differ)")
  }
}' "$LOG"
