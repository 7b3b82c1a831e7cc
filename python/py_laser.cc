// Laser–odometry logs from Python: the calls `calib calibrate` and `calib diagnose` make
// (tools/commands/calibrate.cc, diagnose.cc), from a path or from NumPy arrays.
#include <calib/core/bag/robot_bag.h>
#include <calib/core/laser/laser_log_builder.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/scan/scan_directory.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/tools/report/calibration_report.h>
#include <calib/tools/report/deploy_advice.h>
#include <calib/tools/report/laser_diagnose_report.h>
#include <calib/tools/report/latent_timing_report.h>

#include <optional>
#include <string>
#include <vector>

#include "py_util.h"

namespace calib::python {
namespace {

constexpr const char* kArraysSource = "arrays";

py::list LaserParamNames() {
  py::list names;
  for (const std::string& name : kLaserParamNames) names.append(name);
  return names;
}

py::array_t<double> Column(const std::vector<LaserInterval>& intervals,
                           double (*get)(const LaserInterval&)) {
  py::array_t<double> out(intervals.size());
  auto v = out.mutable_unchecked<1>();
  for (size_t k = 0; k < intervals.size(); ++k) v(k) = get(intervals[k]);
  return out;
}

// {"source", "t", "T", "phi_l", "phi_r", "sm" (N×3), "gap_before", "has_timestamps"} and, from
// raw streams, "odometry" (t, left, right) and "sensor_poses" (t, x, y, theta).
py::dict LaserLogToPython(const LaserLog& log) {
  const std::vector<LaserInterval>& iv = log.intervals;
  py::dict d;
  d["source"] = log.source;
  d["t"] = Column(iv, [](const LaserInterval& i) { return i.start_s; });
  d["T"] = Column(iv, [](const LaserInterval& i) { return i.duration_s; });
  d["phi_l"] = Column(iv, [](const LaserInterval& i) { return i.left_speed; });
  d["phi_r"] = Column(iv, [](const LaserInterval& i) { return i.right_speed; });
  Eigen::MatrixXd sm(iv.size(), 3);
  std::vector<bool> gaps(iv.size());
  for (size_t k = 0; k < iv.size(); ++k) {
    sm.row(k) = iv[k].sensor_motion.transpose();
    gaps[k] = iv[k].gap_before;
  }
  d["sm"] = py::cast(sm);
  d["gap_before"] = py::array_t<bool>(py::cast(gaps));
  d["has_timestamps"] = log.has_timestamps;
  if (!log.streams.sensor_poses.empty()) {
    Eigen::MatrixXd odometry(log.streams.odometry.size(), 3);
    for (size_t k = 0; k < log.streams.odometry.size(); ++k) {
      const EncoderSample& s = log.streams.odometry[k];
      odometry.row(k) << s.t_s, s.left_rad, s.right_rad;
    }
    Eigen::MatrixXd poses(log.streams.sensor_poses.size(), 4);
    for (size_t k = 0; k < log.streams.sensor_poses.size(); ++k) {
      const StampedPose& p = log.streams.sensor_poses[k];
      poses.row(k) << p.t_s, p.world_T_sensor.transpose();
    }
    d["odometry"] = py::cast(odometry);
    d["sensor_poses"] = py::cast(poses);
  }
  return d;
}

// Intervals from arrays, checked as the readers check records ("arrays: record k: ...").
std::vector<LaserInterval> IntervalsFromArrays(const DoubleArray& T, const DoubleArray& phi_l,
                                               const DoubleArray& phi_r, const DoubleArray& sm,
                                               const std::optional<DoubleArray>& t) {
  const py::ssize_t n = T.ndim() == 1 ? T.shape(0) : -1;
  if (n < 0) throw py::value_error("T: expected a 1-D array");
  const auto check_vector = [n](const DoubleArray& a, const char* name) {
    if (a.ndim() != 1 || a.shape(0) != n) {
      throw py::value_error(std::string(name) + ": expected a 1-D array of " + std::to_string(n) +
                            " values (the length of T)");
    }
  };
  check_vector(phi_l, "phi_l");
  check_vector(phi_r, "phi_r");
  if (t) check_vector(*t, "t");
  if (sm.ndim() != 2 || sm.shape(0) != n || sm.shape(1) != 3) {
    throw py::value_error("sm: expected an N×3 array (x, y, theta per interval) with N = " +
                          std::to_string(n) + " (the length of T)");
  }
  laser_io_internal::LogBuilder builder(kArraysSource);
  builder.Reserve(n);
  const auto s = sm.unchecked<2>();
  for (py::ssize_t k = 0; k < n; ++k) {
    LaserInterval interval;
    interval.record = static_cast<int>(k + 1);
    interval.duration_s = T.at(k);
    interval.left_speed = phi_l.at(k);
    interval.right_speed = phi_r.at(k);
    interval.sensor_motion = Pose2d(s(k, 0), s(k, 1), s(k, 2));
    if (t) interval.start_s = t->at(k);
    Check(builder.Add(std::move(interval), t.has_value()));
  }
  return Unwrap(std::move(builder).Finish("")).intervals;
}

LaserCalibrationOptions CalibrationOptions(const std::string& loss, double loss_scale,
                                           double redescending_scale = 6.0) {
  LaserCalibrationOptions options;
  options.refinement.loss = Unwrap(ParseRobustLoss(loss));
  if (!(loss_scale > 0.0)) throw py::value_error("loss_scale must be positive");
  options.refinement.loss_scale = loss_scale;
  if (!(redescending_scale >= 0.0)) {
    throw py::value_error("redescending_scale must be 0 (none) or positive");
  }
  options.refinement.redescending_scale = redescending_scale;
  return options;
}

LaserTimingOptions TimingOptions(const LaserCalibrationOptions& calibration,
                                 const std::string& timing) {
  if (timing != "auto" && timing != "stamps" && timing != "free_running" && timing != "off") {
    throw py::value_error("timing " + timing + ": expected auto, stamps, free_running or off");
  }
  LaserTimingOptions options;
  options.calibration = calibration;
  options.sensor_clock = timing;
  return options;
}

bool IsRobotInput(const std::string& path) {
  return LooksLikeRobotBag(path) || IsScanDirectory(path);
}

// The bag options from keyword arguments named like the command line's flags.
RobotBagOptions RobotOptions(const py::dict& kwargs) {
  RobotBagOptions o;
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (name == "scan_topic") {
      o.topics.scan_topic = value.cast<std::string>();
    } else if (name == "joint_state_topic") {
      o.topics.joint_state_topic = value.cast<std::string>();
    } else if (name == "odom_topic") {
      o.topics.odom_topic = value.cast<std::string>();
    } else if (name == "left_wheel_joint") {
      o.topics.left_wheel_joint = value.cast<std::string>();
    } else if (name == "right_wheel_joint") {
      o.topics.right_wheel_joint = value.cast<std::string>();
    } else if (name == "base_frame") {
      o.base_frame = value.cast<std::string>();
    } else if (name == "nominal_wheel_radius") {
      o.nominal_wheel_radius_m = value.cast<double>();
    } else if (name == "nominal_wheelbase") {
      o.nominal_wheelbase_m = value.cast<double>();
    } else if (name == "wheel_radians_per_unit") {
      o.wheel_radians_per_unit = value.cast<double>();
    } else if (name == "scan_points") {
      if (value.cast<bool>()) o.scan_points = ScanPointOptions();
    } else {
      throw py::type_error("unexpected keyword argument '" + name +
                           "' (bag options: scan_topic, joint_state_topic, odom_topic, "
                           "left_wheel_joint, right_wheel_joint, base_frame, nominal_wheel_radius, "
                           "nominal_wheelbase, wheel_radians_per_unit, scan_points)");
    }
  }
  return o;
}

void CheckBagTiming(const std::string& path, const std::string& timing) {
  if (timing == "off") {
    throw py::value_error(path +
                          ": a bag is calibrated with its timing; timing='off' applies to logs of "
                          "intervals and stream directories");
  }
}

RobotMessages ReadRobotMessages(const std::string& path) {
  return Unwrap(IsScanDirectory(path) ? ReadScanDirectory(path) : ReadRobotBag(path));
}

// The common part of every laser result: arrays, the verdict, and the report `calib calibrate`
// writes (`report`), assembled as the command line does (tools/report/calibration_report.h).
py::dict LaserResultToPython(const CalibrationReport& report) {
  const LaserCalibrationResult& r = report.laser;
  py::dict d;
  d["problem"] = "laser";
  d["params"] = LaserParamNames();
  d["estimate"] = py::cast(Eigen::VectorXd(r.estimate.ToVector()));
  d["stddev"] = py::cast(Eigen::VectorXd(r.stddev));
  d["covariance"] = py::cast(Eigen::MatrixXd(r.covariance));
  d["closed_form"] = py::cast(Eigen::VectorXd(r.closed_form.calibration.ToVector()));
  d["samples"] = r.samples;
  d["inliers"] = r.inliers;
  d["converged"] = r.converged;
  Eigen::MatrixXd noise(r.noise_sigma.size(), 3);
  for (size_t k = 0; k < r.noise_sigma.size(); ++k) noise.row(k) = r.noise_sigma[k].transpose();
  d["noise_sigma"] = py::cast(noise);
  std::vector<bool> inlier;
  for (const std::vector<bool>& log : r.is_inlier)
    inlier.insert(inlier.end(), log.begin(), log.end());
  d["is_inlier"] = py::array_t<bool>(py::cast(inlier));
  d["verdict"] = report.json["verdict"].get<std::string>();
  d["verdict_reason"] = report.json.value("verdict_reason", "");
  d["warnings"] = report.json["warnings"].get<std::vector<std::string>>();
  d["summary"] = report.summary;
  d["report"] = JsonToPython(report.json);
  return d;
}

LaserReportOptions ReportOptions(const std::string& source, const std::string& loss,
                                 const LaserCalibrationOptions& options,
                                 const RobotBagOptions* bag_options = nullptr) {
  LaserReportOptions report;
  report.input = source;
  report.loss = loss;
  report.screen = options;
  if (bag_options) {
    report.scan_points = bag_options->scan_points.has_value();
    if (bag_options->nominal_wheel_radius_m > 0.0 && bag_options->nominal_wheelbase_m > 0.0) {
      report.nominal =
          OdometryParams{bag_options->nominal_wheel_radius_m, bag_options->nominal_wheel_radius_m,
                         bag_options->nominal_wheelbase_m};
    }
  }
  return report;
}

// A raw-stream log or a bag calibrated with its timing.
py::dict StreamResult(const std::string& path, const std::string& loss,
                      const LaserCalibrationOptions& options, const LaserLog& log,
                      const LaserTimingResult& timing, const RobotBagCalibration* bag = nullptr,
                      const RobotBagOptions* bag_options = nullptr) {
  const CalibrationReport report = [&] {
    py::gil_scoped_release release;
    return LaserTimingReport(timing, log, bag, ReportOptions(path, loss, options, bag_options));
  }();
  py::dict d = LaserResultToPython(report);
  d["time_offset"] = timing.time_offset_s;
  d["time_offset_stddev"] = timing.time_offset_stddev_s;
  d["sensor_clock"] = timing.sensor_clock;
  return d;
}

py::dict IntervalResult(const std::string& source, const std::string& loss,
                        const std::vector<LaserInterval>& intervals,
                        LaserCalibrationOptions options, bool interval_jitter,
                        const std::vector<StreamTiming>& timing = {}) {
  options.interval_jitter = interval_jitter;
  LaserLog log;
  log.source = source;
  log.intervals = intervals;
  log.stream_timing = timing;
  const StatusOr<CalibrationReport> report = [&]() -> StatusOr<CalibrationReport> {
    py::gil_scoped_release release;
    LaserReportOptions report_options = ReportOptions(source, loss, options);
    ScreenClosedForms closed_forms;  // After report_options: released before the screen is awaited.
    report_options.calibration_closed_forms = closed_forms.future();
    options.closed_forms_done = closed_forms.Giver();
    report_options.started_screen = StartLaserModelScreen(log.intervals, report_options);
    CALIB_ASSIGN_OR_RETURN(const LaserCalibrationResult result, CalibrateLaser(intervals, options));
    return LaserIntervalReport(result, {&log}, report_options);
  }();
  if (!report.ok()) Raise(report.status().Prefixed(source + ": "));
  return LaserResultToPython(*report);
}

py::dict ReadLaser(const std::string& path, const std::string& format, const py::kwargs& bag) {
  if (IsRobotInput(path)) {
    const RobotBagOptions options = RobotOptions(bag);
    const RobotBagLog log = Unwrap(LaserLogFromRobotMessages(ReadRobotMessages(path), options));
    py::dict d = LaserLogToPython(log.scans.log);
    d["warnings"] = log.warnings;
    d["base_frame"] = log.base_frame;
    d["sensor_frame"] = log.sensor_frame;
    return d;
  }
  if (!bag.empty()) throw py::value_error(path + ": bag options apply to bags only");
  return LaserLogToPython(Unwrap(ReadLaserLog(path, Unwrap(ParseLaserFormat(format)))));
}

py::dict CalibrateLaserPath(const std::string& path, const std::string& format,
                            const std::string& loss, double loss_scale, const std::string& timing,
                            double redescending_scale, const py::kwargs& bag) {
  const LaserCalibrationOptions options = CalibrationOptions(loss, loss_scale, redescending_scale);
  const LaserTimingOptions timing_options = TimingOptions(options, timing);
  if (IsRobotInput(path)) {
    CheckBagTiming(path, timing);
    const RobotBagOptions bag_options = RobotOptions(bag);
    const RobotMessages messages = ReadRobotMessages(path);
    const RobotBagCalibration calibrated =
        Unwrap(CalibrateRobotMessages(messages, bag_options, timing_options));
    return StreamResult(path, loss, options, calibrated.log.scans.log, calibrated.result,
                        &calibrated, &bag_options);
  }
  if (!bag.empty()) throw py::value_error(path + ": bag options apply to bags only");
  const LaserLog log = Unwrap(ReadLaserLog(path, Unwrap(ParseLaserFormat(format))));
  const bool streams = !log.streams.sensor_poses.empty();
  if (streams && timing != "off") {
    StatusOr<LaserTimingResult> result = CalibrateLaserStreams(log.streams, timing_options);
    if (!result.ok()) Raise(result.status().Prefixed(path + ": "));
    return StreamResult(path, loss, options, log, *result);
  }
  return IntervalResult(path, loss, log.intervals, options, !streams, log.stream_timing);
}

py::dict CalibrateLaserArrays(const DoubleArray& T, const DoubleArray& phi_l,
                              const DoubleArray& phi_r, const DoubleArray& sm,
                              const std::optional<DoubleArray>& t, const std::string& loss,
                              double loss_scale, bool interval_jitter, double redescending_scale) {
  return IntervalResult(kArraysSource, loss, IntervalsFromArrays(T, phi_l, phi_r, sm, t),
                        CalibrationOptions(loss, loss_scale, redescending_scale), interval_jitter);
}

LaserDiagnosisOptions DiagnosisOptions(const std::string& loss, double loss_scale, double alpha,
                                       int max_effects, int cv_blocks,
                                       const std::optional<std::vector<std::string>>& candidates) {
  if (!(alpha > 0.0 && alpha < 1.0)) throw py::value_error("alpha must be in (0, 1)");
  if (max_effects < 0) throw py::value_error("max_effects must not be negative");
  if (cv_blocks < 2) throw py::value_error("cv_blocks must be at least 2");
  LaserDiagnosisOptions options;
  options.calibration = CalibrationOptions(loss, loss_scale);
  options.alpha = alpha;
  options.max_effects = max_effects;
  options.cv_blocks = cv_blocks;
  if (candidates) {
    options.candidates.clear();
    for (const std::string& name : *candidates) {
      options.candidates.push_back(Unwrap(ParseLaserEffect(name)));
    }
  }
  return options;
}

// The contract's diagnosis report (`report`, as `calib diagnose` writes it but without plots)
// with the base and final estimates as arrays.
py::dict Diagnose(const std::string& source, const std::vector<LaserInterval>& intervals,
                  const LaserDiagnosisOptions& options, const LaserTimingResult* timing = nullptr) {
  const StatusOr<LaserDiagnosis> result = [&] {
    py::gil_scoped_release release;
    return DiagnoseLaser(intervals, options);
  }();
  if (!result.ok()) Raise(result.status().Prefixed(source + ": "));
  nlohmann::ordered_json json = LaserDiagnosisJson(*result, source, {});
  if (timing != nullptr) {
    AddLatentTimingToDiagnosis(*timing, &json);
  }
  json["deploy"] = AdviseDeployment(json).json;
  py::dict d;
  d["problem"] = "laser";
  d["params"] = LaserParamNames();
  d["baseline_estimate"] = py::cast(Eigen::VectorXd(result->baseline.estimate.ToVector()));
  d["baseline_stddev"] = py::cast(Eigen::VectorXd(result->baseline.stddev));
  d["final_estimate"] = py::cast(Eigen::VectorXd(result->final_fit.estimate.ToVector()));
  d["final_stddev"] = py::cast(Eigen::VectorXd(result->final_fit.stddev));
  d["adopted"] = json["final"]["effects"].get<std::vector<std::string>>();
  d["findings"] = JsonToPython(json["findings"]);
  d["report"] = JsonToPython(json);
  return d;
}

py::dict DiagnoseLaserPath(const std::string& path, const std::string& format,
                           const std::string& loss, double loss_scale, const std::string& timing,
                           double alpha, int max_effects, int cv_blocks,
                           const std::optional<std::vector<std::string>>& candidates,
                           const py::kwargs& bag) {
  LaserDiagnosisOptions options =
      DiagnosisOptions(loss, loss_scale, alpha, max_effects, cv_blocks, candidates);
  const LaserTimingOptions timing_options = TimingOptions(options.calibration, timing);
  // As diagnose.cc: raw streams and bags are timed first, and the search runs on the intervals
  // between the estimated sample times.
  std::optional<LaserTimingResult> timed;
  LaserLog log;
  if (IsRobotInput(path)) {
    CheckBagTiming(path, timing);
    RobotBagCalibration calibrated =
        Unwrap(CalibrateRobotMessages(ReadRobotMessages(path), RobotOptions(bag), timing_options));
    timed = std::move(calibrated.result);
    log = std::move(calibrated.log.scans.log);
  } else {
    if (!bag.empty()) throw py::value_error(path + ": bag options apply to bags only");
    log = Unwrap(ReadLaserLog(path, Unwrap(ParseLaserFormat(format))));
    if (!log.streams.sensor_poses.empty() && timing != "off") {
      StatusOr<LaserTimingResult> result = CalibrateLaserStreams(log.streams, timing_options);
      if (!result.ok()) Raise(result.status().Prefixed(path + ": "));
      timed = std::move(result).value();
    }
  }
  if (timed) {
    StatusOr<LaserLog> at_times =
        LaserLogFromStreams(timed->timed_streams.odometry, timed->timed_streams.sensor_poses, path);
    if (!at_times.ok()) Raise(at_times.status().Prefixed(path + ": at the estimated times: "));
    log.intervals = std::move(at_times->intervals);
    options.sample_times_estimated = true;
  }
  return Diagnose(path, log.intervals, options, timed ? &*timed : nullptr);
}

py::dict DiagnoseLaserArrays(const DoubleArray& T, const DoubleArray& phi_l,
                             const DoubleArray& phi_r, const DoubleArray& sm,
                             const std::optional<DoubleArray>& t, const std::string& loss,
                             double loss_scale, double alpha, int max_effects, int cv_blocks,
                             const std::optional<std::vector<std::string>>& candidates) {
  return Diagnose(kArraysSource, IntervalsFromArrays(T, phi_l, phi_r, sm, t),
                  DiagnosisOptions(loss, loss_scale, alpha, max_effects, cv_blocks, candidates));
}

}  // namespace

void BindLaser(py::module_& m) {
  m.attr("LASER_PARAMS") = LaserParamNames();
  m.def("read_laser_log", &ReadLaser, py::arg("path"), py::arg("format") = "auto",
        "Reads a laser-odometry log: JSON tuples, CSV, a raw-stream directory, or a bag / scans "
        "directory (scans matched into sensor poses; keyword options as the command line's "
        "flags: scan_topic, joint_state_topic, odom_topic, left_wheel_joint, right_wheel_joint, "
        "base_frame, nominal_wheel_radius, nominal_wheelbase, wheel_radians_per_unit). Returns a "
        "dict of arrays: t, T, phi_l, phi_r, sm (N×3), gap_before; from streams also odometry "
        "(t, left, right) and sensor_poses (t, x, y, theta).");
  m.def("calibrate_laser", &CalibrateLaserPath, py::arg("path"), py::arg("format") = "auto",
        py::arg("loss") = "cauchy", py::arg("loss_scale") = 3.0, py::arg("timing") = "auto",
        py::arg("redescending_scale") = 6.0,
        "Calibrates a laser-odometry log as `calib calibrate` does (raw streams and bags with "
        "their timing; bag options as for read_laser_log, plus scan_points=True; "
        "redescending_scale as --redescending_scale, 0 to end under `loss`). Returns a dict: "
        "params, estimate, stddev, covariance (6×6), closed_form, samples, inliers, converged, "
        "noise_sigma, is_inlier, verdict, verdict_reason, warnings, and report (the JSON of "
        "`calib calibrate`).");
  m.def("calibrate_laser_arrays", &CalibrateLaserArrays, py::arg("T"), py::arg("phi_l"),
        py::arg("phi_r"), py::arg("sm"), py::kw_only(), py::arg("t") = py::none(),
        py::arg("loss") = "cauchy", py::arg("loss_scale") = 3.0, py::arg("interval_jitter") = true,
        py::arg("redescending_scale") = 6.0,
        "Calibrates intervals given as arrays: T (s), phi_l, phi_r (rad/s), sm (N×3: x, y, theta "
        "of the sensor displacement in the sensor frame at the start), optional t (interval "
        "starts; a jump marks a gap). Returns the dict of calibrate_laser.");
  m.def("diagnose_laser", &DiagnoseLaserPath, py::arg("path"), py::arg("format") = "auto",
        py::arg("loss") = "cauchy", py::arg("loss_scale") = 3.0, py::arg("timing") = "auto",
        py::arg("alpha") = 0.01, py::arg("max_effects") = 3, py::arg("cv_blocks") = 5,
        py::arg("candidates") = py::none(),
        "Searches a laser log for physics the model leaves out, as `calib diagnose` does. Returns "
        "a dict: params, baseline_estimate, baseline_stddev, final_estimate, final_stddev, "
        "adopted (effect names), findings, and report (the JSON of `calib diagnose`, no plots).");
  m.def("diagnose_laser_arrays", &DiagnoseLaserArrays, py::arg("T"), py::arg("phi_l"),
        py::arg("phi_r"), py::arg("sm"), py::kw_only(), py::arg("t") = py::none(),
        py::arg("loss") = "cauchy", py::arg("loss_scale") = 3.0, py::arg("alpha") = 0.01,
        py::arg("max_effects") = 3, py::arg("cv_blocks") = 5, py::arg("candidates") = py::none(),
        "diagnose_laser on intervals given as arrays (as calibrate_laser_arrays).");
}

}  // namespace calib::python
