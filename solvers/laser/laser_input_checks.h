#ifndef CALIB_SOLVERS_LASER_LASER_INPUT_CHECKS_H_
#define CALIB_SOLVERS_LASER_LASER_INPUT_CHECKS_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/censi_consensus.h>

#include <memory>
#include <string>

// Input mistakes that a calibration would turn into a confident wrong number, told apart from the
// data before calibrating. The closed form (Censi et al. 2008) is fitted to the log as given;
// when it finds no robot (no positive radii and wheelbase, or a wheel larger than the wheelbase:
// the scan rotations far too large for the wheels' rotations), it is fitted to each other
// reading of the log (left and right swapped, one or both wheels negated, θ in degrees), and the
// reading that is a robot is what the log means (the closest fit, by the median xy misfit
// |ℓ ⊕ s − o ⊕ ℓ| over the median |s_xy|, when several are; a reading must also give a wheelbase
// a robot has). When the log as given is a robot, its sizes are checked: a wheel no robot has
// says the wheel readings or the lengths are in another unit (ticks, degrees, turns;
// millimetres); a wheel larger than the wheelbase that no reading explains, wheel turns.
namespace calib {

struct LaserInputCheckOptions {
  double smallest_radius_m = 0.003;   // Below: wheel readings in ticks or degrees.
  double largest_radius_m = 3.0;      // Above, with a plausible wheelbase: readings in turns.
  double largest_wheelbase_m = 20.0;  // Above: lengths in millimetres.
  // Above: the scan rotations are too large for the wheels' (r/b of robots is about 0.03–0.5).
  double largest_radius_over_wheelbase = 1.5;
  // False: only the readings (swapped, negated wheels; θ in degrees) are checked, not the sizes
  // (a robot's bag warns about its wheel unit itself).
  bool check_sizes = true;
  // How the messages name the wheel readings (empty: phi_l, phi_r or the odometry.csv columns).
  std::string left_name, right_name;
  // When not null, receives the consensus screen of the log as given (censi_consensus.h) when the
  // check computed it on every interval (logs up to 50 000 intervals), for the calibration to
  // reuse (LaserCalibrationOptions::consensus_screen); else left as it is.
  std::shared_ptr<const ConsensusScreen>* consensus_screen = nullptr;
};

// Ok when the log reads as the contract says; otherwise InvalidInput naming log.source, what
// looks wrong (with the figures that show it) and what to do. Every finding is a guess about
// the input, so none is corrected here: the user fixes the file or says its unit
// (ScaleWheelReadings). A log the closed form cannot fit in any reading passes: the calibration
// then says what is missing.
Status CheckLaserInput(const LaserLog& log, const LaserInputCheckOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_INPUT_CHECKS_H_
