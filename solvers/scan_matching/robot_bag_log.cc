#include <calib/core/bag/encoder_messages.h>
#include <calib/core/bag/wheel_angles.h>
#include <calib/core/scan/self_returns.h>
#include <calib/core/text_format.h>
#include <calib/solvers/laser/laser_input_checks.h>
#include <calib/solvers/scan_calibration/robot_scan_points.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>

#include <algorithm>
#include <cstdio>
#include <limits>
#include <set>
#include <unordered_map>

namespace calib {
namespace {

std::set<std::string> TfFrames(const RobotMessages& bag) {
  std::set<std::string> frames;
  for (const auto* list : {&bag.tf_static, &bag.tf}) {
    for (const TransformStamped& t : *list) {
      for (std::string f : {t.parent_frame, t.child_frame}) {
        if (!f.empty() && f[0] == '/') f = f.substr(1);
        frames.insert(f);
      }
    }
  }
  return frames;
}

std::string BaseFrame(const RobotMessages& bag, const RobotBagOptions& options) {
  if (!options.base_frame.empty()) return options.base_frame;
  const std::set<std::string> frames = TfFrames(bag);
  for (const char* name : {"base_link", "base_footprint"}) {
    if (frames.count(name)) return name;
  }
  for (const auto& [topic, messages] : bag.odometry) {
    if (!messages.empty() && !messages.front().child_frame_id.empty()) {
      return messages.front().child_frame_id;
    }
  }
  return "base_link";
}

// The wheel angles from the counts of a raw encoder topic: per turn, the user's count
// (wheel_radians_per_unit from --ticks_per_rev) or the known type's.
Status EncoderAngles(const RobotMessages& bag, const RobotBagOptions& options, RobotBagLog* out,
                     WheelAngleStream* wheels) {
  const PickedTopics& t = out->topics;
  const RawTopic& topic = bag.raw.at(t.encoder_topic);
  const EncoderMessageType* known = FindEncoderMessageType(topic.type);
  const std::string where = bag.source + " " + t.encoder_topic;
  double radians_per_tick = options.wheel_radians_per_unit;
  if (radians_per_tick == 1.0) {
    if (known == nullptr) {
      return Status::InvalidInput(where + " (" + topic.type +
                                  "): its encoder counts need the counts per wheel turn: give "
                                  "--ticks_per_rev");
    }
    radians_per_tick = 2.0 * M_PI / known->ticks_per_turn;
  }
  CALIB_ASSIGN_OR_RETURN(
      *wheels, WheelAnglesFromEncoderTopic(topic, t.left_encoder_field, t.right_encoder_field,
                                           where, radians_per_tick));
  out->wheel_source = t.encoder_topic + " (" + t.left_encoder_field + ", " + t.right_encoder_field +
                      Format(": %.6g counts a turn)", 2.0 * M_PI / radians_per_tick);
  if (wheels->counter_wraps > 0) {
    out->warnings.push_back("the encoder counters of " + t.encoder_topic + " wrapped " +
                            std::to_string(wheels->counter_wraps) +
                            " time(s): unwrapped by their range");
  }
  return Status::Ok();
}

// A JointState topic in raw counts (a CSM log's encoders): per turn, the user's count or the one
// its source implies; any other topic in the unit the flags give (radians by default).
StatusOr<double> JointRadiansPerUnit(const RobotMessages& bag, const std::string& topic,
                                     const RobotBagOptions& options) {
  const auto counts = bag.joint_counts_per_turn.find(topic);
  if (counts == bag.joint_counts_per_turn.end() || options.wheel_radians_per_unit != 1.0) {
    return options.wheel_radians_per_unit;
  }
  if (!(counts->second > 0.0)) {
    return Status::InvalidInput(bag.source + " " + topic +
                                ": the wheels are encoder counts, and the log does not say how "
                                "many make a wheel turn: give --ticks_per_rev");
  }
  return 2.0 * M_PI / counts->second;
}

std::string CountsNote(const RobotMessages& bag, const std::string& topic,
                       double radians_per_unit) {
  if (!bag.joint_counts_per_turn.count(topic)) return "";
  return Format(": %.6g counts a turn", 2.0 * M_PI / radians_per_unit) +
         (radians_per_unit == 2.0 * M_PI / bag.joint_counts_per_turn.at(topic) &&
                  !bag.counts_per_turn_source.empty()
              ? ", " + bag.counts_per_turn_source + "; --ticks_per_rev for another robot"
              : "");
}

Status WheelAngles(const RobotMessages& bag, const RobotBagOptions& options, RobotBagLog* out,
                   WheelAngleStream* wheels) {
  const PickedTopics& t = out->topics;
  if (!t.joint_state_topic.empty()) {
    CALIB_ASSIGN_OR_RETURN(const double radians_per_unit,
                           JointRadiansPerUnit(bag, t.joint_state_topic, options));
    CALIB_ASSIGN_OR_RETURN(
        *wheels, WheelAnglesFromJointStates(bag.joint_states.at(t.joint_state_topic), t.left_joint,
                                            t.right_joint, bag.source + " " + t.joint_state_topic,
                                            radians_per_unit));
    out->wheel_source = t.joint_state_topic + " (" + t.left_joint + ", " + t.right_joint +
                        (wheels->from_velocities ? ": velocities integrated" : "") +
                        CountsNote(bag, t.joint_state_topic, radians_per_unit) + ")";
    if (wheels->from_velocities) {
      out->warnings.push_back(
          "the JointState messages carry the wheels' velocities but no positions: the wheel "
          "angles are the velocities integrated over the stamps, whose errors (and the stamps' "
          "jitter) add up along the log; record the joint positions if the driver has them");
    }
    if (wheels->unwrapped_turns > 0) {
      out->warnings.push_back("the wheel joints are reported wrapped into (−π, π]: " +
                              std::to_string(wheels->unwrapped_turns) +
                              " whole turns were added back");
    }
    return Status::Ok();
  }
  if (!t.encoder_topic.empty()) return EncoderAngles(bag, options, out, wheels);
  if (options.wheel_radians_per_unit != 1.0) {
    return Status::InvalidInput(bag.source +
                                ": the wheel angles' unit applies to JointState "
                                "positions, but the wheels come from the Odometry topic " +
                                t.odom_topic);
  }
  if (!(options.nominal_wheel_radius_m > 0.0) || !(options.nominal_wheelbase_m > 0.0)) {
    return Status::InvalidInput(
        bag.source + ": the wheel angles come from the Odometry topic " + t.odom_topic +
        " (no JointState names the wheels), which needs the nominal values its driver used: "
        "give --nominal_wheel_radius and --nominal_wheelbase (the calibration then returns "
        "corrections to them)");
  }
  CALIB_ASSIGN_OR_RETURN(
      *wheels,
      WheelAnglesFromOdometry(bag.odometry.at(t.odom_topic), options.nominal_wheel_radius_m,
                              options.nominal_wheelbase_m, bag.source + " " + t.odom_topic));
  out->wheels_from_odometry = true;
  out->wheel_source = t.odom_topic + " (the driver's odometry through the nominal wheels)";
  return Status::Ok();
}

// Radii far from any robot's say the wheel angles were not in radians.
std::optional<std::string> WheelUnitWarning(const LaserCalibrationResult& result) {
  const OdometryParams& o = result.estimate.odometry;
  const double radius_m = 0.5 * (o.left_radius_m + o.right_radius_m);
  char text[96];
  std::snprintf(text, sizeof(text), "the calibrated wheel radius is %.4g mm", 1e3 * radius_m);
  if (radius_m < 0.003) {
    return std::string(text) +
           ": are the wheel angles in degrees or encoder counts? Give their unit "
           "(--wheel_angle_unit deg or ticks:N for N counts per turn)";
  }
  if (radius_m > 3.0) {
    return std::string(text) +
           ": are the wheel angles in turns, or not the wheels' at all? Give their unit "
           "(--wheel_angle_unit)";
  }
  return std::nullopt;
}

// Swapped or sign-reversed wheel joints, named before the calibration fails on them (the unit
// is WheelUnitWarning's).
Status CheckWheelReadings(const RobotBagLog& log) {
  if (log.wheels_from_odometry) return Status::Ok();
  LaserInputCheckOptions check;
  check.check_sizes = false;
  check.left_name = "the left wheel joint '" + log.topics.left_joint + "'";
  check.right_name = "the right wheel joint '" + log.topics.right_joint + "'";
  return CheckLaserInput(log.scans.log, check);
}

}  // namespace

SweepStarts ScanSweepStarts(const std::vector<LaserScan>& scans, const LaserTimingResult& timing) {
  SweepStarts starts;
  starts.offset_s = timing.time_offset_s;
  if (timing.time_offset_stddev_s > 0.25 * timing.sensor_period_s) return starts;
  std::unordered_map<int64_t, double> time_of_line;  // The timing names a sample by its line.
  for (size_t k = 0; k < timing.sample_line.size() && k < timing.sample_time_s.size(); ++k) {
    time_of_line[timing.sample_line[k]] = timing.sample_time_s[k];
  }
  starts.start_s.assign(scans.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t i = 0; i < scans.size(); ++i) {
    const auto it = time_of_line.find(scans[i].record + 1);
    if (it != time_of_line.end()) starts.start_s[i] = it->second;
  }
  return starts;
}

LaserScan MirroredScan(const LaserScan& scan) {
  LaserScan out = scan;
  out.angle_min_rad = -scan.angle_min_rad;
  out.angle_increment_rad = -scan.angle_increment_rad;
  return out;
}

StatusOr<RobotBagLog> LaserLogFromRobotMessages(const RobotMessages& bag,
                                                const RobotBagOptions& options) {
  RobotBagLog out;
  CALIB_ASSIGN_OR_RETURN(out.topics, PickRobotTopics(bag, options.topics));
  WheelAngleStream wheels;
  CALIB_RETURN_IF_ERROR(WheelAngles(bag, options, &out, &wheels));
  std::vector<LaserScan> scans = bag.scans.at(out.topics.scan_topic);
  for (LaserScan& scan : scans) scan.stamp_s += options.sensor_time_offset_s;
  out.sensor_frame = scans.empty() ? "" : scans.front().frame_id;
  out.base_frame = BaseFrame(bag, options);
  const StatusOr<PlanarMounting> mounting = MountingFromTf(bag, out.base_frame, out.sensor_frame);
  ScanLogOptions scan_options;
  scan_options.matching = options.matching;
  for (const double r : bag.restarts_s) {
    scan_options.restarts_s.push_back(r + options.sensor_time_offset_s);
  }
  scan_options.keep_unmatched = options.keep_unmatched;
  if (mounting.ok()) {
    out.nominal_mounting = *mounting;
    scan_options.nominal_base_T_sensor = mounting->base_T_sensor;
    if (mounting->upside_down) {
      for (LaserScan& scan : scans) scan = MirroredScan(scan);
      out.mirrored = true;
      out.warnings.push_back("tf mounts '" + out.sensor_frame +
                             "' upside down: its scans were "
                             "mirrored so that they turn counter-clockwise like the base");
    }
  } else if (!bag.tf.empty() || !bag.tf_static.empty()) {
    out.warnings.push_back("tf gives no transform from '" + out.base_frame + "' to '" +
                           out.sensor_frame +
                           "': the nominal mounting is unknown (the calibration does not need "
                           "it); if the sensor is mounted upside down, its scans are mirrored");
  }
  if (options.calibrated) {
    scan_options.nominal = options.calibrated->odometry;
    scan_options.nominal_base_T_sensor = options.calibrated->base_T_sensor;
    scan_options.sweep_starts = options.calibrated_sweep_starts;
  } else if (options.nominal_wheel_radius_m > 0.0 && options.nominal_wheelbase_m > 0.0) {
    scan_options.nominal =
        OdometryParams{options.nominal_wheel_radius_m, options.nominal_wheel_radius_m,
                       options.nominal_wheelbase_m};
  }
  const std::string wheel_topic =
      out.wheels_from_odometry ? out.topics.odom_topic : out.topics.joint_state_topic;
  const ScanLogNames names{bag.source, bag.source + " " + wheel_topic,
                           bag.source + " " + out.topics.scan_topic};
  out.beam_timing = options.beam_timing;
  if (!out.beam_timing && options.check_beam_timing && options.calibrated) {
    out.beam_timing = CheckBeamTiming(scans, wheels.samples,
                                      {scan_options.nominal, scan_options.nominal_base_T_sensor},
                                      scan_options.sweep_starts, names.scans);
  }
  if (out.beam_timing && out.beam_timing->changed) {
    for (LaserScan& scan : scans) scan = WithBeamTiming(scan, out.beam_timing->chosen);
    out.warnings.push_back(out.beam_timing->warning);
  }
  CALIB_ASSIGN_OR_RETURN(out.scans, LaserLogFromScans(scans, wheels.samples, names, scan_options));
  out.warnings.insert(out.warnings.end(), out.scans.warnings.begin(), out.scans.warnings.end());
  return out;
}

namespace {

bool FullCircle(const LaserScan& scan) {
  const double increment = std::abs(scan.angle_increment_rad);
  return scan.ranges_m.size() > 2 &&
         increment * scan.ranges_m.size() >= 2.0 * M_PI - 0.5 * increment;
}

// The passes of a long log before its last, which only have to de-skew that one, are calibrated
// on this many scans from its start (300 s at 10 Hz).
constexpr size_t kFirstPassScans = 3000;

// Each pass de-skews the sweeps through the previous pass's calibration, and inherits a share of
// its error: in fast turns (0.5 rad per 0.1 s sweep) the second pass still had sensor_x 4σ off,
// following the first pass's skewed scans. Passes run until no parameter moves by more than
// kSettledSigmas of its σ, at most kMaxPasses.
constexpr int kMaxPasses = 8;
static_assert(kMaxPasses >= 5, "an unsettled run needs three de-skewed passes for its spread");
constexpr double kSettledSigmas = 0.1;
constexpr double kRecheckSigmas = 1.0;

// The largest move of a parameter between two calibrations, in σ of the later one.
double MovedSigmas(const LaserCalibrationResult& before, const LaserCalibrationResult& after) {
  return (after.estimate.ToVector() - before.estimate.ToVector())
      .cwiseQuotient(after.stddev)
      .cwiseAbs()
      .maxCoeff();
}

// One pass: match `bag` (de-skewed through options.calibrated when set), then calibrate.
Status CalibratePass(const RobotMessages& bag, const RobotBagOptions& options,
                     const LaserTimingOptions& timing, RobotBagCalibration* out) {
  CALIB_ASSIGN_OR_RETURN(out->log, LaserLogFromRobotMessages(bag, options));
  CALIB_RETURN_IF_ERROR(CheckWheelReadings(out->log));
  CALIB_ASSIGN_OR_RETURN(out->result, CalibrateLaserStreams(out->log.scans.log.streams, timing));
  return Status::Ok();
}

// The next pass de-skews through `calibration`.
void DeskewThrough(const LaserCalibration& calibration, const std::vector<LaserScan>& scans,
                   const RobotBagCalibration& last, RobotBagOptions* options) {
  options->calibrated = calibration;
  options->calibrated_sweep_starts = ScanSweepStarts(scans, last.result);
}

// The de-skewed passes; when they do not settle, their estimates' spread from pass to pass.
struct DeskewedPasses {
  int passes = 1;
  bool settled = false;
  double moved_sigmas = 0.0;  // The last pass's largest move.
  std::vector<LaserParamVector> estimates;
};

// Passes after the first until one moves no parameter by kSettledSigmas. On a real log they may
// not settle: which scans fail and which beams pair switch with the de-skewing, and the estimate
// steps between a few states (a Mines rover's log: b by ±4 mm, 1–2 σ, pass after pass). Then the
// last pass is de-skewed through the mean of the passes before it but the first de-skewed one.
Status RunDeskewedPasses(const RobotMessages& probe, const std::vector<LaserScan>& scans,
                         const LaserTimingOptions& timing, RobotBagOptions* deskewed,
                         RobotBagCalibration* out, DeskewedPasses* run) {
  const bool forced_timing = deskewed->beam_timing.has_value();
  while (!run->settled && run->passes < kMaxPasses - 1) {
    DeskewThrough(out->result.calibration.estimate, scans, *out, deskewed);
    const LaserCalibrationResult before = out->result.calibration;
    // The beams' timing is judged again while the calibration it goes through still moves by
    // kRecheckSigmas between passes: the first pass matched skewed sweeps, and its calibration and
    // timing can be far off (a slower logger's clock not yet found put the sweeps ~65 ms early,
    // where a 30 % longer sweep closed them best). Then it is kept.
    const bool recheck =
        !forced_timing && (run->passes == 1 || !(run->moved_sigmas < kRecheckSigmas));
    deskewed->beam_timing = recheck ? std::nullopt : out->log.beam_timing;
    CALIB_RETURN_IF_ERROR(CalibratePass(probe, *deskewed, timing, out));
    ++run->passes;
    run->moved_sigmas = MovedSigmas(before, out->result.calibration);
    run->settled = run->moved_sigmas < kSettledSigmas;
    run->estimates.push_back(out->result.calibration.estimate.ToVector());
  }
  if (run->settled) return Status::Ok();
  LaserParamVector mean = LaserParamVector::Zero();
  for (size_t k = 1; k < run->estimates.size(); ++k) mean += run->estimates[k];
  mean /= static_cast<double>(run->estimates.size() - 1);
  DeskewThrough(LaserCalibration::FromVector(mean), scans, *out, deskewed);
  deskewed->beam_timing = out->log.beam_timing;
  CALIB_RETURN_IF_ERROR(CalibratePass(probe, *deskewed, timing, out));
  ++run->passes;
  return Status::Ok();
}

// The passes' spread (all de-skewed passes but the first, and the last) joins the covariance: the
// result is one draw of the states they step between.
std::string WidenByPassSpread(const DeskewedPasses& run, LaserCalibrationResult* result) {
  std::vector<LaserParamVector> draws(run.estimates.begin() + 1, run.estimates.end());
  draws.push_back(result->estimate.ToVector());
  LaserParamVector mean = LaserParamVector::Zero();
  for (const LaserParamVector& d : draws) mean += d;
  mean /= static_cast<double>(draws.size());
  LaserParamMatrix spread = LaserParamMatrix::Zero();
  for (const LaserParamVector& d : draws) spread += (d - mean) * (d - mean).transpose();
  spread /= static_cast<double>(draws.size() - 1);
  const double largest = spread.diagonal().cwiseSqrt().cwiseQuotient(result->stddev).maxCoeff();
  result->covariance += spread;
  result->stddev = result->covariance.diagonal().cwiseSqrt();
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer),
                "the de-skewed matching passes had not settled after %d (the last moved a "
                "parameter by %.2f σ; from pass to pass they scatter by up to %.2f σ): the last "
                "pass was de-skewed through their mean, and the σ include their scatter",
                run.passes, run.moved_sigmas, largest);
  return buffer;
}

// The matching and the two-stage calibration (passes until settled where the scans sweep).
StatusOr<RobotBagCalibration> CalibrateTwoStage(const RobotMessages& bag,
                                                const RobotBagOptions& options,
                                                const LaserTimingOptions& timing) {
  CALIB_ASSIGN_OR_RETURN(const PickedTopics topics, PickRobotTopics(bag, options.topics));
  const std::vector<LaserScan>& scans = bag.scans.at(topics.scan_topic);
  // A full circle without beam times may still sweep: the check of its timing decides.
  bool sweeps = options.check_beam_timing && !scans.empty() && FullCircle(scans.front());
  for (const LaserScan& scan : scans) sweeps = sweeps || scan.time_increment_s != 0.0;
  const bool long_log = sweeps && scans.size() > 2 * kFirstPassScans;
  RobotMessages start;
  if (long_log) {
    start.source = bag.source;
    start.topics = bag.topics;
    start.joint_states = bag.joint_states;
    start.odometry = bag.odometry;
    start.tf = bag.tf;
    start.tf_static = bag.tf_static;
    start.scans[topics.scan_topic].assign(scans.begin(), scans.begin() + kFirstPassScans);
  }
  const RobotMessages& probe = long_log ? start : bag;
  RobotBagCalibration out;
  CALIB_RETURN_IF_ERROR(CalibratePass(probe, options, timing, &out));
  if (!sweeps) return out;
  RobotBagOptions deskewed = options;
  DeskewedPasses run;
  CALIB_RETURN_IF_ERROR(RunDeskewedPasses(probe, scans, timing, &deskewed, &out, &run));
  if (long_log) {
    DeskewThrough(out.result.calibration.estimate, scans, out, &deskewed);
    CALIB_RETURN_IF_ERROR(CalibratePass(bag, deskewed, timing, &out));
    ++run.passes;
  }
  out.log.matching_passes = run.passes;
  if (!run.settled) out.log.warnings.push_back(WidenByPassSpread(run, &out.result.calibration));
  return out;
}

// The two-stage route failed on `why`: the scan points alone, from the bag's matched log (kept
// however few its matches) and the nominal wheels.
StatusOr<RobotBagCalibration> ScanPointsAlone(const RobotMessages& bag,
                                              const RobotBagOptions& options, const Status& why) {
  RobotBagOptions keep = options;
  keep.keep_unmatched = true;
  StatusOr<RobotBagLog> log = LaserLogFromRobotMessages(bag, keep);
  if (!log.ok()) return why;
  CALIB_RETURN_IF_ERROR(CheckWheelReadings(*log));
  return CalibrateOnScanPointsAlone(bag, options, std::move(log).value(), why);
}

StatusOr<RobotBagCalibration> CalibrateMasked(const RobotMessages& bag,
                                              const RobotBagOptions& options,
                                              const LaserTimingOptions& timing) {
  StatusOr<RobotBagCalibration> two_stage = CalibrateTwoStage(bag, options, timing);
  if (!two_stage.ok()) {
    const StatusCode code = two_stage.status().code();
    const bool data_short = code == StatusCode::kInvalidInput || code == StatusCode::kNotObservable;
    if (!options.scan_points || !data_short) return two_stage.status();
    return ScanPointsAlone(bag, options, two_stage.status());
  }
  RobotBagCalibration out = std::move(two_stage).value();
  if (const std::optional<std::string> units = WheelUnitWarning(out.result.calibration)) {
    out.log.warnings.push_back(*units);
  }
  if (options.scan_points) {
    StatusOr<ScanPointCalibration> refined =
        RefineRobotOnScanPoints(bag, out, *options.scan_points);
    if (refined.ok()) {
      out.scan_points = std::move(refined).value();
    } else {
      out.scan_point_warnings.push_back("the refinement on the scan points failed (" +
                                        refined.message() + "): the two-stage result stands");
    }
  }
  return out;
}

// The recording with its self-returns masked, when it has any (else nullopt: use it as it is),
// and what was done, for the notes.
std::optional<RobotMessages> WithoutSelfReturns(const RobotMessages& bag,
                                                const RobotBagOptions& options,
                                                std::vector<std::string>* notes) {
  if (!bag.restarts_s.empty()) {
    notes->push_back(std::to_string(bag.restarts_s.size() + 1) +
                     " logs joined into one recording: the scan matching starts again at each");
  }
  if (!options.mask_self_returns) return std::nullopt;
  const StatusOr<PickedTopics> topics = PickRobotTopics(bag, options.topics);
  if (!topics.ok()) return std::nullopt;
  const std::vector<LaserScan>& scans = bag.scans.at(topics->scan_topic);
  const SelfReturns self = FindSelfReturns(scans);
  if (self.beams.empty()) return std::nullopt;
  notes->push_back(self.Describe(static_cast<int>(scans.size())));
  RobotMessages masked = bag;
  MaskBeams(self.beams, &masked.scans[topics->scan_topic]);
  return masked;
}

}  // namespace

// The reported calibration (the scan points' when refined) against the walls, and the nominal
// wheels' when given.
WallCheck WallsUnder(const RobotMessages& bag, const RobotBagOptions& options,
                     const RobotBagCalibration& calibration) {
  const OdometryParams& calibrated = calibration.scan_points
                                         ? calibration.scan_points->estimate.odometry
                                         : calibration.result.calibration.estimate.odometry;
  const Eigen::Matrix3d covariance =
      (calibration.scan_points ? calibration.scan_points->covariance
                               : calibration.result.calibration.covariance)
          .topLeftCorner<3, 3>();
  std::optional<OdometryParams> nominal;
  if (options.nominal_wheel_radius_m > 0.0 && options.nominal_wheelbase_m > 0.0) {
    nominal = OdometryParams{options.nominal_wheel_radius_m, options.nominal_wheel_radius_m,
                             options.nominal_wheelbase_m};
  }
  const RobotBagLog& log = calibration.log;
  return CheckAgainstWalls(bag.scans.at(log.topics.scan_topic), log.mirrored,
                           log.scans.log.streams.odometry, calibrated, nominal,
                           calibration.result.time_offset_s, covariance);
}

StatusOr<RobotBagCalibration> CalibrateRobotMessages(const RobotMessages& recording,
                                                     const RobotBagOptions& options,
                                                     const LaserTimingOptions& timing) {
  std::vector<std::string> notes;
  const std::optional<RobotMessages> masked = WithoutSelfReturns(recording, options, &notes);
  const RobotMessages& bag = masked ? *masked : recording;
  StatusOr<RobotBagCalibration> calibrated = CalibrateMasked(bag, options, timing);
  if (calibrated.ok()) {
    std::vector<std::string>& out = calibrated->log.notes;
    out.insert(out.begin(), notes.begin(), notes.end());
    calibrated->log.walls = WallsUnder(bag, options, *calibrated);
  }
  return calibrated;
}

}  // namespace calib
