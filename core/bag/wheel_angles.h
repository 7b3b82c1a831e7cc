#ifndef CALIB_CORE_BAG_WHEEL_ANGLES_H_
#define CALIB_CORE_BAG_WHEEL_ANGLES_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/status.h>

#include <string>
#include <vector>

// The cumulative wheel angles (the encoder stream of the laser calibration) from a bag's
// messages. Each sample keeps its message's header stamp (its log time when the stamp is unset)
// and, in `line`, its record index for messages.
namespace calib {

struct WheelAngleStream {
  std::vector<EncoderSample> samples;
  int unwrapped_turns = 0;   // Whole turns added where a wrapped joint angle jumped by ~2π.
  int skipped_messages = 0;  // Messages that carry neither wheel (other joints' states).
  int half_messages = 0;     // Messages that carry one wheel only: not used.
  // The messages carry no positions: the angles are their velocities integrated (trapezoids).
  bool from_velocities = false;
  int counter_wraps = 0;  // Encoder counters that wrapped (WheelAnglesFromEncoderTopic).
};

// From the positions of two joints of a sensor_msgs/JointState topic, in radians after
// multiplying by radians_per_unit (π/180 for degrees, 2π/N for raw counts of N per turn). A joint
// reported wrapped into (−π, π] or [0, 2π) (every position within it, and steps of more than half
// a turn) is unwrapped. Messages without positions but with a velocity per name (drivers that
// publish only speeds) give the angles by integrating the velocities over the stamps; a stream
// that mixes the two is refused.
StatusOr<WheelAngleStream> WheelAnglesFromJointStates(const std::vector<JointState>& messages,
                                                      const std::string& left_joint,
                                                      const std::string& right_joint,
                                                      const std::string& where,
                                                      double radians_per_unit = 1.0);

// From a nav_msgs/Odometry topic that the robot's driver integrated with its nominal wheel radius
// and wheelbase: each step between two poses, taken as an arc (chord, heading change, direction
// of travel), gives the nominal wheel angles back, so that the calibration returns corrections to
// the nominal values. Where every pose is zero (a driver that only fills the twist), the twist is
// integrated instead (trapezoids).
// From the counts in two integer fields of a robot's own encoder message (a raw topic), in
// radians after multiplying by radians_per_tick (2π over the counts per wheel turn). A counter
// that wraps (any integer field narrower than 64 bits) is unwrapped: a step of more than half its
// range is a wrap. Each sample's time is the message's header stamp, else its log time. The
// message definition is the bag's, else, for a known type (encoder_messages.h), calib's own.
StatusOr<WheelAngleStream> WheelAnglesFromEncoderTopic(const RawTopic& topic,
                                                       const std::string& left_field,
                                                       const std::string& right_field,
                                                       const std::string& where,
                                                       double radians_per_tick);

StatusOr<WheelAngleStream> WheelAnglesFromOdometry(const std::vector<Odometry>& messages,
                                                   double nominal_wheel_radius_m,
                                                   double nominal_wheelbase_m,
                                                   const std::string& where);

}  // namespace calib

#endif  // CALIB_CORE_BAG_WHEEL_ANGLES_H_
