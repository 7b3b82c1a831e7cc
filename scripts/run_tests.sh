#!/usr/bin/env bash
# Builds everything and runs the test suite (and the benchmark's quick smoke run).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
cd build
ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" --timeout 900
