"""Calibrates a laser-odometry log from Python: python3 python/example.py [LOG]"""
import os
import sys

import calib

path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(
    os.path.dirname(__file__), "..", "data", "sample_laser.tuple")
try:
    result = calib.calibrate_laser(path)  # Also: calibrate_laser_arrays(T, phi_l, phi_r, sm).
    diagnosis = calib.diagnose_laser(path)
except (OSError, ValueError, RuntimeError) as error:
    sys.exit(f"error: {error}")  # The message names the file, line and what is wrong.

for name, value, sigma in zip(result["params"], result["estimate"], result["stddev"]):
    print(f"{name:>12} = {value:10.6f} ± {sigma:.6f}")
print(f"verdict: {result['verdict']} ({result['verdict_reason']})")
for warning in result["warnings"]:
    print(f"warning: {warning}")
print("effects the model leaves out:", ", ".join(diagnosis["adopted"]) or "none found")
