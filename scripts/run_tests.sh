#!/usr/bin/env bash
# Builds everything, runs the benchmark's quick mode as a smoke test (its tables go to
# build/bench_quick.txt), then the test suite, then the sanitizer suite
# (scripts/run_sanitized_tests.sh; CALIB_SKIP_SANITIZERS=1 leaves it out).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
./build/bin/calib_bench --quick --json build/bench_quick.json > build/bench_quick.txt
echo "calib_bench --quick: $(tail -n 1 build/bench_quick.txt)"
(cd build && ctest --output-on-failure -j"$(nproc 2>/dev/null || echo 2)" --timeout 900)
if [ "${CALIB_SKIP_SANITIZERS:-0}" != 1 ]; then
  bash scripts/run_sanitized_tests.sh
fi
