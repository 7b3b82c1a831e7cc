#!/usr/bin/env bash
# Runs the libFuzzer harnesses of tests/fuzz under ASan and UBSan.
#
#   scripts/run_fuzzers.sh [SECONDS_PER_HARNESS [RUNS]]   fuzz each harness for a bounded time
#                                                         (default 60 s; RUNS: stop after RUNS
#                                                         executions, whichever comes first)
#   scripts/run_fuzzers.sh --replay                       replay the seeds and regressions only
#
# Environment: FUZZ_HARNESSES="laser_csv mcap" picks harnesses (default: all), FUZZ_JOBS=N
# builds with N jobs (default 2). Builds in build-fuzz/ with clang++ and -DCALIB_FUZZ=ON; each
# harness runs on a copy of its seed corpus (build-fuzz/fuzz-work/<harness>/corpus), so the
# seeds in the repository stay as they are. Exits non-zero when any harness finds a crash, a
# leak, undefined behaviour or a timeout, and prints the reproducer's path.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
build="$root/build-fuzz"
replay=0
seconds=60
runs=-1
if [[ "${1:-}" == "--replay" ]]; then
  replay=1
else
  seconds="${1:-60}"
  runs="${2:--1}"
fi
harnesses=(${FUZZ_HARNESSES:-laser_tuples laser_csv laser_stream bearing_log scan_csv mcap sqlite_bag
  message_definition rosbag1 laser_calibrate})

# The project's packages, and clang with its libFuzzer and sanitizer runtimes (Debian 12:
# clang-14, libclang-rt-14-dev), each only when missing.
bash "$root/scripts/install_deps.sh" clang libclang-rt-14-dev

launcher=()
command -v ccache >/dev/null 2>&1 && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$root" -B "$build" -DCMAKE_CXX_COMPILER=clang++ -DCALIB_FUZZ=ON \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCALIB_BUILD_PYTHON=OFF -DCALIB_BUILD_BENCHMARKS=OFF \
  "${launcher[@]}" >/dev/null
targets=()
for h in "${harnesses[@]}"; do targets+=("${h}_fuzzer"); done
cmake --build "$build" -j"${FUZZ_JOBS:-2}" --target "${targets[@]}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
failed=()
for h in "${harnesses[@]}"; do
  fuzzer="$build/fuzz/${h}_fuzzer"
  seeds="$root/tests/fuzz/corpus/$h"
  regressions="$root/tests/fuzz/regressions/$h"
  work="$build/fuzz-work/$h"
  mkdir -p "$work/artifacts"
  log="$work/fuzz.log"
  if ((replay)); then
    inputs=("$seeds"/*)
    [ -d "$regressions" ] && inputs+=($(find "$regressions" -maxdepth 1 -type f))
    echo "== $h: replaying ${#inputs[@]} input(s)"
    if ! "$fuzzer" -rss_limit_mb=2048 -timeout=10 -artifact_prefix="$work/artifacts/" \
      "${inputs[@]}" >"$log" 2>&1; then
      failed+=("$h")
      tail -n 40 "$log"
    fi
    continue
  fi
  rm -rf "$work/corpus"
  mkdir -p "$work/corpus"
  cp "$seeds"/* "$work/corpus/"
  [ -d "$regressions" ] && find "$regressions" -maxdepth 1 -type f -exec cp {} "$work/corpus/" \;
  echo "== $h: fuzzing for ${seconds} s (runs: $runs)"
  start=$(date +%s)
  status=0
  "$fuzzer" "$work/corpus" -max_total_time="$seconds" -runs="$runs" -rss_limit_mb=2048 \
    -timeout=10 -print_final_stats=1 -artifact_prefix="$work/artifacts/" >"$log" 2>&1 || status=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
  echo "   ${execs:-?} executions in $(($(date +%s) - start)) s, exit $status"
  if ((status != 0)); then
    failed+=("$h")
    grep -E 'ERROR: |runtime error|SUMMARY|Test unit written to' "$log" | head -n 20 || true
    echo "   log: $log"
  fi
done
if ((${#failed[@]})); then
  echo "run_fuzzers: FAILED: ${failed[*]} (reproducers in $build/fuzz-work/<harness>/artifacts)" >&2
  exit 1
fi
echo "run_fuzzers: no crash, leak, undefined behaviour or timeout"
