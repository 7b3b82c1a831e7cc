#!/usr/bin/env bash
# Installs calib into a scratch prefix, builds examples/consumer against it with
# find_package(calib), and runs it on a log.
set -euo pipefail
source_dir=$1 binary_dir=$2 log=$3
prefix="$binary_dir/consumer-test/install"
rm -rf "$binary_dir/consumer-test"
cmake --install "$binary_dir" --prefix "$prefix" >/dev/null
cmake -S "$source_dir/examples/consumer" -B "$binary_dir/consumer-test/build" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$binary_dir/consumer-test/build" >/dev/null
out=$("$binary_dir/consumer-test/build/calib_consumer" "$log")
echo "$out"
grep -q "^b = " <<<"$out"
