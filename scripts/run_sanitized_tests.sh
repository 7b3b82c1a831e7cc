#!/usr/bin/env bash
# The sanitizer suite: builds calib and its tests with AddressSanitizer (with LeakSanitizer) and
# UndefinedBehaviorSanitizer into build-asan/ (gcc, -O1 -g1, NDEBUG as in Release) and runs them;
# a memory error, a leak or undefined behaviour aborts the test that shows it. The command-line
# tests run the sanitized build-asan/bin/calib, so its bad-input and output paths are covered too.
#
# By default only the tests labelled `sanitize` (CALIB_SANITIZE_TESTS in tests/CMakeLists.txt:
# readers, core, residuals, report writers, the consensus screen, the command line's bad-input
# battery) are built and run, so that CI
# (scripts/run_tests.sh) stays within its time limit. Left out, as too slow under the sanitizers
# for CI: the solver sweeps over the Censi recordings (censi_data_test, the diagnosis data
# tests), the command-line tests that calibrate many logs (bags, deploy, diagnose, plots,
# output failures), the Monte Carlo and coverage studies (calibrate_laser_test, laser_consistency_test,
# the timing and scan-point calibrations), the Python bindings (an ASan runtime cannot be loaded
# into an uninstrumented python3) and the find_package consumer test (it builds a project of its
# own, without the sanitizer flags). `--all` builds and runs every other test (the Python module
# and the benchmarks stay off).
set -euo pipefail
cd "$(dirname "$0")/.."
scope=sanitize
if [ "${1:-}" = "--all" ]; then scope=all; fi
bash scripts/install_deps.sh
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Release -DCALIB_SANITIZE=address,undefined \
  -DCALIB_BUILD_PYTHON=OFF -DCALIB_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
jobs=$(nproc 2>/dev/null || echo 2)
# LeakSanitizer works here (no ptrace restriction in the way); a leak fails the test.
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
export UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
if [ "$scope" = all ]; then
  cmake --build build-asan -j"$jobs"
  labels=(-E '^consumer_find_package$')
else
  cmake --build build-asan -j"$jobs" --target calib calib_sanitize_tests
  labels=(-L sanitize)
fi
cd build-asan
ctest --output-on-failure -j"$jobs" --timeout 1800 "${labels[@]}"
