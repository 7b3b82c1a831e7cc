#ifndef CALIB_CORE_ENCODER_SAMPLE_H_
#define CALIB_CORE_ENCODER_SAMPLE_H_

namespace calib {

// One reading of the wheel encoders: cumulative wheel rotations (rad, positive when the wheel
// drives the robot forward) at time t_s. Both problems read these from an odometry.csv.
struct EncoderSample {
  double t_s = 0.0;
  double left_rad = 0.0;
  double right_rad = 0.0;
  int line = 0;  // 1-based line in odometry.csv (0: not from a file).
};

}  // namespace calib

#endif  // CALIB_CORE_ENCODER_SAMPLE_H_
