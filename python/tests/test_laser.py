import json
import os
import tempfile
import unittest

import numpy as np

import calib
from simulate import simulate

DATA = os.path.join(os.path.dirname(__file__), "..", "..", "data")


class CalibrateLaserTest(unittest.TestCase):

    def test_sample_log_within_three_sigma_of_truth(self):
        result = calib.calibrate_laser(os.path.join(DATA, "sample_laser.tuple"))
        with open(os.path.join(DATA, "sample_laser_truth.json")) as f:
            truth = json.load(f)["estimate"]
        self.assertEqual(result["params"], calib.LASER_PARAMS)
        self.assertEqual(result["covariance"].shape, (6, 6))
        np.testing.assert_allclose(np.sqrt(np.diag(result["covariance"])), result["stddev"])
        for name, value, sigma in zip(result["params"], result["estimate"], result["stddev"]):
            self.assertLess(abs(value - truth[name]), 3 * sigma, name)
        self.assertEqual(result["samples"], 2000)
        self.assertEqual(result["is_inlier"].sum(), result["inliers"])
        self.assertIn(result["verdict"], ("trusted", "check", "unreliable"))
        # The report is the JSON `calib calibrate` writes.
        report = result["report"]
        self.assertEqual(report["problem"], "laser")
        self.assertEqual(report["verdict"], result["verdict"])
        self.assertAlmostEqual(report["estimate"]["b"], result["estimate"][2])

    def test_exact_recovery_from_noise_free_arrays(self):
        truth = np.array([0.031, 0.029, 0.27, 0.12, -0.04, 0.4])
        T, phi_l, phi_r, sm = simulate(truth)
        result = calib.calibrate_laser_arrays(T, phi_l, phi_r, sm)
        np.testing.assert_allclose(result["estimate"], truth, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(result["closed_form"], truth, rtol=1e-9, atol=1e-12)
        self.assertEqual(result["samples"], len(T))

    def test_redescending_scale_names_the_last_loss_and_is_checked(self):
        path = os.path.join(DATA, "sample_laser.tuple")
        tukey = calib.calibrate_laser(path)
        cauchy = calib.calibrate_laser(path, redescending_scale=0.0)
        self.assertEqual(tukey["report"]["loss_stages"], "cauchy, then tukey (6)")
        self.assertEqual(cauchy["report"]["loss_stages"], "cauchy")
        for name, a, b, sigma in zip(tukey["params"], tukey["estimate"], cauchy["estimate"],
                                     tukey["stddev"]):
            self.assertLess(abs(a - b), sigma, name)  # Few slips: the two losses agree.
        log = calib.read_laser_log(path)
        with self.assertRaisesRegex(ValueError, "redescending_scale must be 0"):
            calib.calibrate_laser_arrays(log["T"], log["phi_l"], log["phi_r"], log["sm"],
                                         redescending_scale=-1.0)

    def test_read_laser_log_round_trip_through_arrays(self):
        log = calib.read_laser_log(os.path.join(DATA, "sample_laser.tuple"))
        self.assertEqual(log["sm"].shape, (2000, 3))
        from_file = calib.calibrate_laser(os.path.join(DATA, "sample_laser.tuple"))
        from_arrays = calib.calibrate_laser_arrays(log["T"], log["phi_l"], log["phi_r"], log["sm"])
        np.testing.assert_allclose(from_arrays["estimate"], from_file["estimate"], rtol=1e-12)

    def test_missing_file_raises_with_its_name(self):
        with self.assertRaises(OSError) as raised:
            calib.calibrate_laser("no_such_robot.tuple")
        self.assertIn("no_such_robot.tuple", str(raised.exception))

    def test_bad_record_raises_with_file_and_line(self):
        with tempfile.TemporaryDirectory() as directory:
            path = os.path.join(directory, "bad.csv")
            with open(path, "w") as f:
                f.write("T,phi_l,phi_r,sm_x,sm_y,sm_theta\n1,0,0,0,0,0\n-1,0,0,0,0,0\n")
            with self.assertRaises(ValueError) as raised:
                calib.read_laser_log(path)
        self.assertIn("bad.csv:3", str(raised.exception))
        self.assertIn("T must be positive", str(raised.exception))

    def test_bad_arrays_raise_naming_the_argument(self):
        T, phi_l, phi_r, sm = simulate(np.array([0.03, 0.03, 0.3, 0, 0, 0]), n=10)
        with self.assertRaisesRegex(ValueError, "sm: expected an N×3 array"):
            calib.calibrate_laser_arrays(T, phi_l, phi_r, sm[:, :2])
        T[4] = 0.0
        with self.assertRaisesRegex(ValueError, "arrays: record 5: T must be positive"):
            calib.calibrate_laser_arrays(T, phi_l, phi_r, sm)

    def test_motion_that_cannot_determine_the_parameters_raises(self):
        T, phi_l, phi_r, sm = simulate(np.array([0.03, 0.03, 0.3, 0.1, 0, 0]), n=50, kinds=(0,))
        with self.assertRaisesRegex(ValueError, "arrays: the robot never turns"):
            calib.calibrate_laser_arrays(T, phi_l, phi_r, sm)


    def test_verdict_points_to_diagnose_as_the_command_line_does(self):
        result = calib.calibrate_laser(os.path.join(DATA, "diagnose", "lateral_slip.tuple"))
        self.assertEqual(result["verdict"], "check")
        self.assertIn("calib diagnose", result["verdict_reason"])
        self.assertIn("lateral_slip", result["report"]["model_screen"]["effects"])
        self.assertIn("odometry drift", result["summary"])


class RobotRecordingTest(unittest.TestCase):

    def assert_within_three_sigma(self, result, truth_path):
        with open(truth_path) as f:
            truth = json.load(f)["estimate"]
        for name, value, sigma in zip(result["params"], result["estimate"], result["stddev"]):
            self.assertLess(abs(value - truth[name]), 3 * sigma, name)

    def test_bag_read_and_calibrated_within_three_sigma(self):
        bag = os.path.join(DATA, "bags", "sim_robot_zstd.mcap")
        log = calib.read_laser_log(bag)  # Scans matched into sensor poses.
        self.assertEqual(log["sensor_poses"].shape[1], 4)
        self.assertEqual(log["sm"].shape, (len(log["T"]), 3))
        result = calib.calibrate_laser(bag)
        self.assertIn("recording", result["report"])
        self.assert_within_three_sigma(result, os.path.join(DATA, "bags", "sim_robot_truth.json"))
        with self.assertRaisesRegex(TypeError, "scan_topc"):
            calib.read_laser_log(bag, scan_topc="/scan")

    def test_raw_streams_read_and_calibrated_with_their_timing(self):
        directory = os.path.join(DATA, "timing", "clean")
        log = calib.read_laser_log(directory)
        self.assertEqual(log["odometry"].shape[1], 3)
        result = calib.calibrate_laser(directory)
        self.assertEqual(result["report"]["timing"]["treatment"], "latent_times")
        self.assert_within_three_sigma(result, os.path.join(directory, "truth.json"))


class DiagnoseLaserTest(unittest.TestCase):

    def test_finds_the_lateral_slip(self):
        path = os.path.join(DATA, "diagnose", "lateral_slip.tuple")
        with open(os.path.join(DATA, "diagnose", "lateral_slip_truth.json")) as f:
            slip = json.load(f)["effects"]["lateral_slip"]
        diagnosis = calib.diagnose_laser(path)
        self.assertEqual(diagnosis["adopted"], ["lateral_slip"])
        finding = next(f for f in diagnosis["findings"] if f["effect"] == "lateral_slip")
        self.assertTrue(finding["significant"])
        self.assertLess(abs(finding["value"] - slip), 3 * finding["stddev"])
        self.assertEqual(diagnosis["final_estimate"].shape, (6,))
        self.assertEqual(diagnosis["report"]["final"]["effects"], ["lateral_slip"])


if __name__ == "__main__":
    unittest.main()
