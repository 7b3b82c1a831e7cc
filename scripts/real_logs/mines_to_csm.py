#!/usr/bin/env python3
"""A Paris-Mines rover log (CoreSLAM / BreezySLAM examples, expN.dat) as a CSM laser log (bz2).

Each line of the Mines log is one scan: token 0 the time (µs), tokens 2 and 3 the left and right
wheel counters (2000 a turn), tokens 24 on the 682 ranges (mm, 0: no echo) of a Hokuyo URG-04LX.
The URG-04LX measures steps 44…725 of 1024 a turn, counter-clockwise, step 384 straight ahead, one
turn in 100 ms: the log's ranges are beams at (i + 44 − 384)·2π/1024 rad. (CoreSLAM spreads them
over ±120°, 0.2 % wider.) Counters and ranges are written as logged; the time as [s, µs].

Usage: mines_to_csm.py expN.dat expN.log.bz2
Then:  calib calibrate --input expN.log.bz2 --ticks_per_rev 2000 --lidar_rotation_period 0.1
"""
import bz2
import json
import math
import sys

BEAMS = 682
FIRST_RANGE_TOKEN = 24
STEP_RAD = 2.0 * math.pi / 1024.0
FIRST_STEP, FRONT_STEP = 44, 384


def records(path):
    min_theta = (FIRST_STEP - FRONT_STEP) * STEP_RAD
    max_theta = min_theta + (BEAMS - 1) * STEP_RAD
    for number, line in enumerate(open(path), start=1):
        tokens = line.split()
        if len(tokens) < FIRST_RANGE_TOKEN + BEAMS:
            print('%s line %d: %d tokens, a scan needs %d: left out' %
                  (path, number, len(tokens), FIRST_RANGE_TOKEN + BEAMS), file=sys.stderr)
            continue
        us = int(tokens[0])
        ranges = [int(float(v)) for v in tokens[FIRST_RANGE_TOKEN:FIRST_RANGE_TOKEN + BEAMS]]
        yield {
            'nrays': BEAMS,
            'min_theta': round(min_theta, 12),
            'max_theta': round(max_theta, 12),
            'timestamp': [us // 1000000, us % 1000000],
            'left': int(tokens[2]),
            'right': int(tokens[3]),
            'readings': [None if mm < 20 else mm / 1000.0 for mm in ranges],
        }


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    lines = [json.dumps(r, separators=(',', ':')) for r in records(sys.argv[1])]
    with bz2.open(sys.argv[2], 'wt') as out:
        out.write('\n'.join(lines) + '\n')
    print('%s: %d scans' % (sys.argv[2], len(lines)))


if __name__ == '__main__':
    main()
