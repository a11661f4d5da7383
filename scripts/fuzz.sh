#!/usr/bin/env bash
# Build the libFuzzer scene fuzzer (fuzz/fuzz_scene.c) with clang, AddressSanitizer and
# UndefinedBehaviorSanitizer into build-fuzz, and run it for N seconds (default 60) on a
# corpus seeded from examples/*/scene.yaml and tests/scenes/*.yaml (kept in
# build-fuzz/corpus between runs). Crashes, leaks, timeouts and out-of-memory inputs are
# written to build-fuzz/artifacts/ and make the script fail. docs/robustness.md records runs.
#   scripts/fuzz.sh [SECONDS] [extra libFuzzer flags...]
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-60}"
shift || true
if ! command -v clang >/dev/null 2>&1 || ! command -v clang++ >/dev/null 2>&1; then
  echo "fuzz.sh: clang is needed (scripts/install-deps.sh installs it)" >&2
  exit 1
fi
dir=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLOE_FUZZ=ON -DFLOE_SANITIZE=ON \
  -DFLOE_NATIVE=OFF -DFLOE_BUILD_TESTS=OFF -DFLOE_BUILD_EXAMPLES=OFF -DFLOE_BUILD_BENCH=OFF >/dev/null
cmake --build "$dir" -j"${FLOE_FUZZ_JOBS:-$(nproc)}" --target fuzz_scene
mkdir -p "$dir/corpus" "$dir/artifacts"
for f in examples/*/scene.yaml tests/scenes/*.yaml; do
  cp -n "$f" "$dir/corpus/seed_$(echo "$f" | tr '/' '_')" 2>/dev/null || true
done
# scene meshes are read relative to the working directory: run where no file is found
cd "$dir"
ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=1" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
  ./fuzz_scene -max_total_time="$secs" -timeout=20 -rss_limit_mb=3072 -max_len=8192 \
  -dict=../fuzz/scene.dict -artifact_prefix=artifacts/ -print_final_stats=1 "$@" corpus
