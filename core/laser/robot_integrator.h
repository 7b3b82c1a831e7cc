#ifndef CALIB_CORE_LASER_ROBOT_INTEGRATOR_H_
#define CALIB_CORE_LASER_ROBOT_INTEGRATOR_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/laser/wheel_profile.h>
#include <calib/core/se2.h>

#include <vector>

// The laser simulator's robot motion with the diagnosis effects (not part of the API).
namespace calib {
namespace laser_sim_internal {

// The robot's motion over each scan window [t_k + δ, t_{k+1} + δ] (δ = effects.time_offset_s),
// in the robot frame at the window's start, with the slips and the radius change of
// options.effects; `boundaries` are t_0 … t_N on the odometry clock.
std::vector<Pose2d> IntegrateRobotMotions(const LaserSimOptions& options,
                                          const WheelProfile& profile,
                                          const std::vector<double>& boundaries);

}  // namespace laser_sim_internal
}  // namespace calib

#endif  // CALIB_CORE_LASER_ROBOT_INTEGRATOR_H_
