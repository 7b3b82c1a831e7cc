#include <calib/core/laser/laser_log_io.h>
#include <calib/core/order_statistic.h>
#include <calib/core/se2.h>
#include <calib/core/text_format.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <calib/solvers/laser/laser_input_checks.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace calib {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The misfit's pass runs in chunks of at least this many intervals (ParallelSplit).
constexpr size_t kMinChunk = 500;

// The readings of a log tried against the one given.
enum Reading { kAsGiven, kSwapped, kLeftNegated, kRightNegated, kBothNegated, kThetaDegrees };
constexpr int kNumReadings = 6;

struct Fit {
  bool ok = false;
  double misfit = std::numeric_limits<double>::infinity();
  LaserCalibration calibration;
};

double Median(std::vector<double> v) { return UpperMedian(&v); }

Fit FitClosedForm(const std::vector<LaserInterval>& intervals, ConsensusScreen* screen = nullptr) {
  // Screened, so that a handful of glitches cannot make a log look like another reading.
  const StatusOr<CensiClosedFormResult> closed = CensiClosedFormScreened(intervals, screen);
  Fit fit;
  if (!closed.ok()) return fit;
  const LaserCalibration& cal = closed->calibration;
  std::vector<double> error_xy(intervals.size()), motion_xy(intervals.size());
  ParallelSplit(intervals.size(), CensiClosedFormOptions{}.num_threads, kMinChunk,
                [&](size_t, size_t begin, size_t end) {
                  for (size_t k = begin; k < end; ++k) {
                    const LaserInterval& interval = intervals[k];
                    const Pose2d o =
                        IntervalRobotMotion(cal.odometry.left_radius_m, cal.odometry.right_radius_m,
                                            cal.odometry.wheelbase_m, interval);
                    // e = ℓ ⊕ s − o ⊕ ℓ (§III-B), in the robot frame.
                    const Pose2d e = Compose(cal.base_T_sensor, interval.sensor_motion) -
                                     Compose(o, cal.base_T_sensor);
                    error_xy[k] = e.head<2>().norm();
                    motion_xy[k] = interval.sensor_motion.head<2>().norm();
                  }
                });
  const double scale = Median(motion_xy);
  if (!(scale > 0.0)) return fit;
  fit.ok = true;
  fit.misfit = Median(error_xy) / scale;
  fit.calibration = cal;
  return fit;
}

// The wheel columns as `reading` takes them.
std::vector<LaserInterval> ReadWheels(std::vector<LaserInterval> intervals, Reading reading) {
  const double left_sign = reading == kLeftNegated || reading == kBothNegated ? -1.0 : 1.0;
  const double right_sign = reading == kRightNegated || reading == kBothNegated ? -1.0 : 1.0;
  for (LaserInterval& interval : intervals) {
    if (reading == kSwapped) std::swap(interval.left_speed, interval.right_speed);
    interval.left_speed *= left_sign;
    interval.right_speed *= right_sign;
    for (WheelStep& step : interval.steps) {
      if (reading == kSwapped) std::swap(step.left_rad, step.right_rad);
      step.left_rad *= left_sign;
      step.right_rad *= right_sign;
    }
  }
  return intervals;
}

// θ read as degrees: each interval's rotation, or (raw streams) every pose's heading before the
// intervals are formed, since the headings also rotate the displacements into the sensor frame.
Fit FitThetaInDegrees(const LaserLog& log) {
  if (log.streams.sensor_poses.empty()) {
    std::vector<LaserInterval> intervals = log.intervals;
    for (LaserInterval& interval : intervals) interval.sensor_motion(2) *= kPi / 180.0;
    return FitClosedForm(intervals);
  }
  std::vector<StampedPose> poses = log.streams.sensor_poses;
  for (StampedPose& pose : poses) pose.world_T_sensor(2) *= kPi / 180.0;
  const StatusOr<LaserLog> reread = LaserLogFromStreams(log.streams.odometry, poses, log.source);
  return reread.ok() ? FitClosedForm(reread->intervals) : Fit();
}

struct Names {
  std::string left, right, wheels, theta, xy;  // The columns, as the user knows them.
};

Names ColumnNames(const LaserLog& log, const LaserInputCheckOptions& options) {
  Names names = {"phi_l", "phi_r", "phi_l and phi_r", "sm_theta", "sm_x and sm_y"};
  if (!log.streams.sensor_poses.empty()) {
    names = {"the left column of odometry.csv", "the right column of odometry.csv",
             "the left and right columns of odometry.csv", "the theta column of sensor_poses.csv",
             "the x and y columns of sensor_poses.csv"};
  }
  if (!options.left_name.empty() && !options.right_name.empty()) {
    names.left = options.left_name;
    names.right = options.right_name;
    names.wheels = names.left + " and " + names.right;
  }
  return names;
}

std::string Mm(double metres) { return Format("%.4g mm", 1e3 * metres); }

std::string Deg(double radians) { return Format("%.1f°", radians * 180.0 / kPi); }

// "r_l 20.07 mm, r_r 20.16 mm, b 85.82 mm".
std::string Sizes(const LaserCalibration& cal) {
  return "r_l " + Mm(cal.odometry.left_radius_m) + ", r_r " + Mm(cal.odometry.right_radius_m) +
         ", b " + Mm(cal.odometry.wheelbase_m);
}

// The rotation per wheel rotation, r/b (the closed form's J21, J22): a wheel larger than the
// wheelbase turns no robot.
double RadiusOverWheelbase(const LaserCalibration& cal) {
  const OdometryParams& o = cal.odometry;
  return 0.5 * (o.left_radius_m + o.right_radius_m) / o.wheelbase_m;
}

bool Plausible(const Fit& fit, const LaserInputCheckOptions& options) {
  return fit.ok && RadiusOverWheelbase(fit.calibration) <= options.largest_radius_over_wheelbase;
}

// Another reading must also give a wheelbase a robot has (the wheel readings' unit does not
// change it; the radius it leaves to CheckSizes).
bool PlausibleReading(const Fit& fit, const LaserInputCheckOptions& options) {
  return Plausible(fit, options) &&
         fit.calibration.odometry.wheelbase_m <= options.largest_wheelbase_m;
}

// Why the log as given is not what it means.
std::string AsGiven(const Fit& given) {
  if (!given.ok) return "as given, no positive radii and wheelbase fit it";
  return Format("as given, the wheel radius would be %.3g times the wheelbase (",
                RadiusOverWheelbase(given.calibration)) +
         Sizes(given.calibration) + "), which no robot has";
}

std::string WheelSignMessage(const LaserLog& log, const Names& names, Reading reading,
                             const Fit* fits, const LaserInputCheckOptions& options) {
  const Fit& fit = fits[reading];
  const Fit& given = fits[kAsGiven];
  if (reading == kLeftNegated || reading == kRightNegated) {
    const std::string& column = reading == kLeftNegated ? names.left : names.right;
    const char* wheel = reading == kLeftNegated ? "left" : "right";
    return log.source + ": the " + wheel + " wheel's readings have the wrong sign: with " + column +
           " negated the log fits a differential-drive robot (" + Sizes(fit.calibration) + "); " +
           AsGiven(given) + ". Negate " + column +
           ", so that positive wheel speeds drive the robot forward";
  }
  // Swapped wheels, both wheels negated and a scanner upside down are the same data up to the
  // sensor's heading (by π) and the radii's labels: name both, with the heading each implies.
  const Fit& swapped = fits[kSwapped];
  const Fit& negated = fits[kBothNegated];
  std::string text = log.source + ": the wheels turn the robot the wrong way";
  const bool both =
      Plausible(swapped, options) && Plausible(negated, options) &&
      std::max(swapped.misfit, negated.misfit) < 1.5 * std::min(swapped.misfit, negated.misfit);
  if (both || reading == kSwapped) {
    text += ": with " + names.wheels + " swapped the log fits a robot (" +
            Sizes(swapped.calibration) + ", the sensor heading " +
            Deg(swapped.calibration.base_T_sensor(2)) + ")";
  }
  if (both) text += ", and equally";
  if (both || reading == kBothNegated) {
    text += " with both negated (" + Sizes(negated.calibration) + ", the sensor heading " +
            Deg(negated.calibration.base_T_sensor(2)) +
            "): positive wheel speeds would drive it backward";
  }
  text += "; " + AsGiven(given) + ". ";
  if (both) {
    text +=
        "The data cannot tell these apart (nor from a scanner mounted upside down); the sensor's "
        "heading can: swap the left and right wheels, or negate both, accordingly";
  } else {
    text += reading == kSwapped ? "Swap the left and right wheels"
                                : "Negate both wheels, so that positive speeds drive forward";
  }
  return text;
}

std::string ThetaDegreesMessage(const LaserLog& log, const Names& names, const Fit* fits) {
  const Fit& fit = fits[kThetaDegrees];
  const Fit& given = fits[kAsGiven];
  std::string text = log.source + ": " + names.theta +
                     " looks like degrees, not radians: read as degrees the log fits a "
                     "differential-drive robot (" +
                     Sizes(fit.calibration) + "); " + AsGiven(given);
  if (log.streams.sensor_poses.empty()) {
    const auto large =
        std::count_if(log.intervals.begin(), log.intervals.end(),
                      [](const LaserInterval& i) { return std::abs(i.sensor_motion(2)) > kPi; });
    if (large > 0) {
      text += Format(", and %d of %d intervals turn by more than π, which no interval can",
                     static_cast<int>(large), static_cast<int>(log.intervals.size()));
    }
  }
  return text + ". Convert " + names.theta + " to radians";
}

// Sizes no robot has: the unit of the wheel readings or of the lengths.
Status CheckSizes(const LaserLog& log, const Names& names, const LaserCalibration& cal,
                  const LaserInputCheckOptions& options) {
  const double radius = 0.5 * (cal.odometry.left_radius_m + cal.odometry.right_radius_m);
  const double wheelbase = cal.odometry.wheelbase_m;
  if (wheelbase > options.largest_wheelbase_m) {
    return Status::InvalidInput(
        log.source +
        Format(": the wheelbase comes out at %.4g m and the wheel radius at %.4g m", wheelbase,
               radius) +
        ", which no robot has: " + names.xy +
        " look like millimetres, not metres (the fit scales every length with them). Convert "
        "them to metres");
  }
  if (radius < options.smallest_radius_m) {
    return Status::InvalidInput(
        log.source + ": the wheel radius comes out at " + Format("%.4g", 1e3 * radius) +
        " mm, which no wheel has: " + names.wheels +
        " look like encoder ticks (or degrees), not radians. Give --ticks_per_rev N, the ticks "
        "per wheel turn (--wheel_angle_unit deg for degrees): the radius is then " +
        Format("%.4g", 1e3 * radius) + " mm × N/2π (N = 1024 gives " +
        Mm(radius * 1024 / (2 * kPi)) + ", N = 4096 gives " + Mm(radius * 4096 / (2 * kPi)) + ")");
  }
  if (radius > options.largest_radius_m) {
    return Status::InvalidInput(
        log.source + Format(": the wheel radius comes out at %.4g m", radius) +
        ", which no wheel has, while the wheelbase (" + Mm(wheelbase) +
        ") is plausible: " + names.wheels +
        " look like wheel turns, not radians. Give --ticks_per_rev 1 (or convert them to "
        "radians)");
  }
  return Status::Ok();
}

// No reading explains a log whose wheels turn the robot too little for the scans: the sizes
// may say why; else wheel turns instead of radians (r/b 2π times too large) are the usual cause.
Status CheckRotationScale(const LaserLog& log, const Names& names, const Fit& given,
                          const LaserInputCheckOptions& options) {
  CALIB_RETURN_IF_ERROR(CheckSizes(log, names, given.calibration, options));
  return Status::InvalidInput(log.source + ": " + AsGiven(given) +
                              Format(": the scan rotations are %.3g times those of a wheel as "
                                     "large as the wheelbase. Are ",
                                     RadiusOverWheelbase(given.calibration)) +
                              names.wheels +
                              " wheel turns, not radians? Then give --ticks_per_rev 1 (or convert "
                              "them to radians)");
}

// The readings compare by closed forms and a median misfit, which an evenly spread subset of
// this many intervals gives as well as a million do (at a twentieth of the time on huge logs).
constexpr size_t kCheckedIntervals = 50000;

}  // namespace

Status CheckLaserInput(const LaserLog& log, const LaserInputCheckOptions& options) {
  if (log.intervals.empty()) return Status::Ok();
  std::vector<LaserInterval> subset;
  if (log.intervals.size() > kCheckedIntervals) {
    subset = EveryNthInterval(log.intervals,
                              (log.intervals.size() + kCheckedIntervals - 1) / kCheckedIntervals);
  }
  const std::vector<LaserInterval>& checked = subset.empty() ? log.intervals : subset;
  // Durations in ms scale the wheel rotation (speed × T) as ticks would: said first, as such.
  std::vector<double> ends = {0.0};
  for (const LaserInterval& in : checked) ends.push_back(ends.back() + in.duration_s);
  CALIB_RETURN_IF_ERROR(CheckStampUnit(ends, log.source + " (the intervals' T, summed)", "T"));
  Fit fits[kNumReadings];
  ConsensusScreen screen;
  fits[kAsGiven] = FitClosedForm(checked, &screen);
  if (options.consensus_screen != nullptr && subset.empty()) {
    *options.consensus_screen = std::make_shared<const ConsensusScreen>(std::move(screen));
  }
  const Names names = ColumnNames(log, options);
  const Fit& given = fits[kAsGiven];
  if (Plausible(given, options)) {
    return options.check_sizes ? CheckSizes(log, names, given.calibration, options) : Status::Ok();
  }
  // The log as given is no robot: the reading that is one (the closest fit among several) is
  // what it means.
  for (const Reading reading : {kSwapped, kLeftNegated, kRightNegated, kBothNegated}) {
    fits[reading] = FitClosedForm(ReadWheels(checked, reading));
  }
  fits[kThetaDegrees] = FitThetaInDegrees(log);
  int best = -1;
  for (int r = kSwapped; r < kNumReadings; ++r) {
    if (PlausibleReading(fits[r], options) && (best < 0 || fits[r].misfit < fits[best].misfit)) {
      best = r;
    }
  }
  if (best < 0) {
    const bool scale = given.ok && options.check_sizes;
    return scale ? CheckRotationScale(log, names, given, options) : Status::Ok();
  }
  const Reading reading = static_cast<Reading>(best);
  return Status::InvalidInput(reading == kThetaDegrees
                                  ? ThetaDegreesMessage(log, names, fits)
                                  : WheelSignMessage(log, names, reading, fits, options));
}

}  // namespace calib
