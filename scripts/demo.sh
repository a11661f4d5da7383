#!/usr/bin/env bash
# Install dependencies, build, and run the default demo scene into ./out/demo.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build -j"$(nproc)"
./build/floe run -o out/demo "$@"
