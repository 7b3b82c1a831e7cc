#!/usr/bin/env bash
# Installs the Debian 12 packages calib needs, only those that are missing; arguments name extra
# packages (scripts/run_fuzzers.sh: clang and its libFuzzer runtime).
set -euo pipefail
packages=(cmake g++ make libceres-dev libeigen3-dev libgoogle-glog-dev libgflags-dev
          libgtest-dev libgmock-dev libbenchmark-dev nlohmann-json3-dev libbz2-dev liblz4-dev
          libzstd-dev libsqlite3-dev pybind11-dev python3-dev python3-numpy librsvg2-bin "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "install_deps: installing ${missing[*]}" >&2
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
fi
