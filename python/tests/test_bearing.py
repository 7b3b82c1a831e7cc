import json
import os
import unittest

import numpy as np

import calib

SAMPLE = os.path.join(os.path.dirname(__file__), "..", "..", "data", "sample_bearing")


class BearingTest(unittest.TestCase):

    def test_read_sample(self):
        log = calib.read_bearing_log(SAMPLE)
        self.assertEqual(log["wheel_radius"], 0.3)
        self.assertEqual(log["initial_distance"], {"run": 2, "meters": 1.0})
        self.assertEqual(len(log["runs"]), 3)
        self.assertEqual(log["runs"][0]["odometry"].shape[1], 3)
        self.assertEqual(log["runs"][0]["bearings"].shape[1], 2)

    def test_sample_within_three_sigma_of_truth(self):
        result = calib.calibrate_bearing(SAMPLE)
        with open(os.path.join(SAMPLE, "truth.json")) as f:
            truth = json.load(f)["estimate"]
        self.assertEqual(result["params"], calib.BEARING_PARAMS)
        self.assertEqual(result["covariance"].shape, (5, 5))
        for names, values, sigmas in (
            (result["params"], result["estimate"], result["stddev"]),
            (result["metric_params"], result["metric_estimate"], result["metric_stddev"]),
        ):
            for name, value, sigma in zip(names, values, sigmas):
                self.assertGreater(sigma, 0, name)
                self.assertLess(abs(value - truth[name]), 3 * sigma, name)
        self.assertEqual(result["report"]["problem"], "bearing")
        self.assertIn(result["verdict"], ("trusted", "check", "unreliable"))

    def test_missing_directory_raises_with_its_name(self):
        with self.assertRaises(OSError) as raised:
            calib.calibrate_bearing(os.path.join(SAMPLE, "no_such_run"))
        self.assertIn("no_such_run", str(raised.exception))


if __name__ == "__main__":
    unittest.main()
