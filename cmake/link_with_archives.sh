#!/bin/bash
# The link launcher of `calib` (tools/CMakeLists.txt, CALIB_STATIC_DEPENDENCIES): runs the link
# with every shared library CMake named by path (Ceres' dependencies, zstd, lz4, bz2) replaced by
# its static archive where one lies beside it, and what those archives need appended (the
# compiler's runtime archives where it has them, -static-libstdc++). `calib` then loads 6 shared
# libraries instead of 30 and starts ~5 ms sooner (a fifth of a run on the authors' real sets). Only the executable: the tests and the Python module
# (archives that are not position-independent cannot go into a shared object) keep the shared
# libraries. If the link with archives fails, the link as CMake wrote it runs instead.
#
# Usage: link_with_archives.sh NEEDED -- LINK COMMAND...   (NEEDED: ':'-separated paths)
set -u
needed=$1
shift
[ "${1:-}" = "--" ] && shift

# libunwind's archive is not position-independent; it stays shared.
archive_of() {
  local dir=${1%/*} base=${1##*/}
  local archive="$dir/${base%%.so*}.a"
  [ "${base%%.so*}" != libunwind ] && [ -f "$archive" ] && echo "$archive"
}

args=()
for arg in "$@"; do
  case "$arg" in
    /*/lib*.so | /*/lib*.so.[0-9]*)
      if archive=$(archive_of "$arg"); then
        args+=("$archive")
        continue
      fi
      ;;
  esac
  args+=("$arg")
done
IFS=: read -ra extra <<<"$needed"

if errors=$("${args[@]}" "${extra[@]}" 2>&1); then
  [ -n "$errors" ] && echo "$errors" >&2
  exit 0
fi
echo "calib: the link with static archives failed; linking with the shared libraries" >&2
exec "$@"
