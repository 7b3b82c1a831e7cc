#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/laser_motion.h>

#include <cmath>

namespace calib {
namespace {
constexpr double kStillRad = 1e-6;       // Below this total rotation the wheels are at rest.
constexpr double kComponentShare = 0.1;  // Share of the rotation that counts as turning/moving.
constexpr int kMinimumIntervals = 3;
}  // namespace

LaserMotionCensus CountLaserMotion(const std::vector<LaserInterval>& intervals,
                                   const std::vector<bool>* use, int num_threads) {
  constexpr size_t kMinChunk = 4096;
  std::vector<LaserMotionCensus> chunks(SplitCount(intervals.size(), kMinChunk));
  ParallelSplit(intervals.size(), num_threads, kMinChunk,
                [&](size_t chunk, size_t begin, size_t end) {
                  LaserMotionCensus& census = chunks[chunk];
                  for (size_t k = begin; k < end; ++k) {
                    if (use != nullptr && !(*use)[k]) continue;
                    ++census.total;
                    const Eigen::Vector2d rotation = IntervalWheelRotation(intervals[k]);
                    const double size = rotation.cwiseAbs().sum();
                    if (size < kStillRad) {
                      ++census.still;
                      continue;
                    }
                    const bool turns = std::abs(rotation(1) - rotation(0)) > kComponentShare * size;
                    const bool moves = std::abs(rotation(1) + rotation(0)) > kComponentShare * size;
                    if (turns && moves) {
                      ++census.arc;
                    } else if (turns) {
                      ++census.pure_rotation;
                    } else {
                      ++census.straight;
                    }
                  }
                });
  LaserMotionCensus census;  // Counts: the same in any order.
  for (const LaserMotionCensus& chunk : chunks) census.Add(chunk);
  return census;
}

std::string DescribeMissingLaserMotion(const LaserMotionCensus& census) {
  if (census.total - census.still < kMinimumIntervals) {
    return "the robot barely moves (" + std::to_string(census.total - census.still) +
           " moving intervals of " + std::to_string(census.total) +
           "): nothing can be calibrated; drive turns and arcs";
  }
  if (census.turning() < kMinimumIntervals) {
    return "the robot never turns (" + std::to_string(census.straight) + " straight intervals, " +
           std::to_string(census.turning()) +
           " turning): the wheel radii relative to the wheelbase and the sensor position are "
           "not observable; drive some turns and arcs";
  }
  if (census.translating() < kMinimumIntervals) {
    return "all intervals are pure rotations (" + std::to_string(census.pure_rotation) + " of " +
           std::to_string(census.total) +
           "): b and the sensor position are not observable; drive some arcs or straight runs";
  }
  return "";
}

}  // namespace calib
