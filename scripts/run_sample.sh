#!/usr/bin/env bash
# Builds the tool and calibrates the sample log shipped in data/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh calib
./build/bin/calib calibrate --input data/sample_laser.tuple --output build/sample_result.json
echo "JSON result: build/sample_result.json"
