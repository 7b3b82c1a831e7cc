#!/usr/bin/env bash
# Installs calib into a scratch prefix, builds examples/consumer against it with
# find_package(calib), runs it on a log, and checks that the report it writes through
# calib::report is the one `calib calibrate` writes (but for the timings). The README's "From C++"
# block must be examples/consumer/readme_example.cc, which prints the library's message on failure.
set -euo pipefail
source_dir=$1 binary_dir=$2 log=$3
scratch="$binary_dir/consumer-test"
prefix="$scratch/install"
rm -rf "$scratch"
cmake --install "$binary_dir" --prefix "$prefix" >/dev/null
cmake -S "$source_dir/examples/consumer" -B "$scratch/build" \
  -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$scratch/build" >/dev/null
out=$("$scratch/build/calib_consumer" "$log" "$scratch/consumer.json")
echo "$out"
grep -q "^b = " <<<"$out"
"$binary_dir/bin/calib" calibrate --quiet --input "$log" --output "$scratch/calib.json"
# "seconds" is the last member of the report.
diff <(sed '/"seconds"/,$d' "$scratch/consumer.json") <(sed '/"seconds"/,$d' "$scratch/calib.json")

diff <(sed -n '/^## From C++/,/^## /p' "$source_dir/README.md" | sed -n '/^```cpp$/,/^```$/p' | sed '1d;$d') \
  "$source_dir/examples/consumer/readme_example.cc"
"$scratch/build/calib_readme_example" "$log" | grep -q "^b = "
if "$scratch/build/calib_readme_example" "$scratch/no_such.tuple" 2>"$scratch/error.txt"; then
  echo "readme_example: a missing log did not fail" >&2
  exit 1
fi
grep -q "no_such.tuple" "$scratch/error.txt"
