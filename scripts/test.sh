#!/usr/bin/env bash
# Install dependencies, build (warnings are errors), and run the whole test suite with
# ctest. FLOE_SANITIZE=1 builds into build-asan with AddressSanitizer + UBSan.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
# the layers first (seconds): no folder includes from a folder above it
python3 scripts/check_layers.py
if [[ "${FLOE_SANITIZE:-0}" == 1 ]]; then
  dir=build-asan; flags=(-DFLOE_SANITIZE=ON -DFLOE_BUILD_BENCH=OFF)
else
  # the normal pass builds MPI too (core/parallel; its tests run under mpirun)
  dir=build; flags=(-DFLOE_WITH_MPI=ON)
fi
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DFLOE_WERROR=ON "${flags[@]}"
cmake --build "$dir" -j"$(nproc)"
# ctest runs as many tests at once as there are cores, and tests run threaded (OpenMP): threads
# that wait at a barrier sleep instead of spinning, or two spinning tests starve each other
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
ctest --test-dir "$dir" --output-on-failure -j"$(nproc)"
