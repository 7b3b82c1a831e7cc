// Bearing logs (Martinelli) from Python: the calls `calib calibrate` and `calib diagnose` make on a
// bearing log directory.
#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/tools/report/bearing_diagnose_report.h>
#include <calib/tools/report/calibration_report.h>
#include <calib/tools/report/deploy_advice.h>

#include <string>
#include <vector>

#include "py_util.h"

namespace calib::python {
namespace {

template <size_t N>
py::list Names(const std::array<const char*, N>& names) {
  py::list out;
  for (const char* name : names) out.append(name);
  return out;
}

// {"source", "wheel_radius", "wheelbase", "initial_distance": None or {"run", "meters"},
//  "runs": [{"id", "odometry": M×3 (t, left, right), "bearings": K×2 (t, bearing)}]}
py::dict BearingLogToPython(const BearingLog& log) {
  py::dict d;
  d["source"] = log.source;
  d["wheel_radius"] = log.meta.wheel_radius_m;
  d["wheelbase"] = log.meta.wheelbase_m;
  d["initial_distance"] = py::none();
  if (log.meta.initial_distance) {
    py::dict distance;
    distance["run"] = log.meta.initial_distance->run;
    distance["meters"] = log.meta.initial_distance->meters;
    d["initial_distance"] = distance;
  }
  py::list runs;
  for (const BearingRun& run : log.runs) {
    Eigen::MatrixXd odometry(run.odometry.size(), 3);
    for (size_t k = 0; k < run.odometry.size(); ++k) {
      odometry.row(k) << run.odometry[k].t_s, run.odometry[k].left_rad, run.odometry[k].right_rad;
    }
    Eigen::MatrixXd bearings(run.bearings.size(), 2);
    for (size_t k = 0; k < run.bearings.size(); ++k) {
      bearings.row(k) << run.bearings[k].t_s, run.bearings[k].bearing_rad;
    }
    py::dict r;
    r["id"] = run.id;
    r["odometry"] = py::cast(odometry);
    r["bearings"] = py::cast(bearings);
    runs.append(r);
  }
  d["runs"] = runs;
  return d;
}

BearingCalibrationOptions CalibrationOptions(const std::string& loss, double loss_scale) {
  BearingCalibrationOptions options;
  options.adjustment.loss = Unwrap(ParseRobustLoss(loss));
  if (!(loss_scale > 0.0)) throw py::value_error("loss_scale must be positive");
  options.adjustment.loss_scale = loss_scale;
  options.adjustment.num_threads = 2;
  return options;
}

py::dict CalibrateBearingPath(const std::string& path, const std::string& loss, double loss_scale) {
  const BearingCalibrationOptions options = CalibrationOptions(loss, loss_scale);
  const BearingLog log = Unwrap(ReadBearingLog(path));
  const StatusOr<BearingCalibrationResult> result = [&] {
    py::gil_scoped_release release;
    return CalibrateBearing(log, options);
  }();
  if (!result.ok()) Raise(result.status());
  const BearingCalibrationResult& r = *result;
  const CalibrationReport calibration = BearingCalibrationReport(r, log, path, loss);
  const nlohmann::ordered_json& report = calibration.json;

  py::dict d;
  d["problem"] = "bearing";
  d["params"] = Names(kBearingParamNames);
  d["estimate"] = py::cast(Eigen::VectorXd(ToVector(r.estimate)));
  d["stddev"] = py::cast(Eigen::VectorXd(r.stddev));
  d["covariance"] = py::cast(Eigen::MatrixXd(r.covariance));
  if (r.has_metric) {
    d["metric_params"] = Names(kBearingMetricNames);
    d["metric_estimate"] = py::cast(Eigen::VectorXd(ToVector(r.metric)));
    d["metric_stddev"] = py::cast(Eigen::VectorXd(r.metric_stddev));
    d["metric_covariance"] = py::cast(Eigen::MatrixXd(r.metric_covariance));
  }
  d["samples"] = r.samples;
  d["inliers"] = r.inliers;
  d["converged"] = r.converged;
  d["verdict"] = report["verdict"].get<std::string>();
  d["verdict_reason"] = report.value("verdict_reason", "");
  d["warnings"] = report["warnings"].get<std::vector<std::string>>();
  d["summary"] = calibration.summary;
  d["report"] = JsonToPython(report);
  return d;
}

py::dict DiagnoseBearingPath(const std::string& path, const std::string& loss, double loss_scale,
                             double alpha, int cv_blocks) {
  if (!(alpha > 0.0 && alpha < 1.0)) throw py::value_error("alpha must be in (0, 1)");
  if (cv_blocks < 2) throw py::value_error("cv_blocks must be at least 2");
  BearingDiagnosisOptions options;
  options.calibration = CalibrationOptions(loss, loss_scale);
  options.alpha = alpha;
  options.cv_blocks = cv_blocks;
  const BearingLog log = Unwrap(ReadBearingLog(path));
  const StatusOr<BearingDiagnosis> result = [&] {
    py::gil_scoped_release release;
    return DiagnoseBearing(log, options);
  }();
  if (!result.ok()) Raise(result.status());
  nlohmann::ordered_json json = BearingDiagnosisJson(*result, path, {});
  json["deploy"] = AdviseDeployment(json).json;
  py::dict d;
  d["problem"] = "bearing";
  d["params"] = Names(kBearingParamNames);
  d["baseline_estimate"] = py::cast(Eigen::VectorXd(ToVector(result->baseline.estimate)));
  d["baseline_stddev"] = py::cast(Eigen::VectorXd(result->baseline.stddev));
  d["final_estimate"] = py::cast(Eigen::VectorXd(ToVector(result->final_fit.estimate)));
  d["final_stddev"] = py::cast(Eigen::VectorXd(result->final_fit.stddev));
  d["adopted"] = json["final"]["effects"].get<std::vector<std::string>>();
  d["findings"] = JsonToPython(json["findings"]);
  d["report"] = JsonToPython(json);
  return d;
}

}  // namespace

void BindBearing(py::module_& m) {
  m.attr("BEARING_PARAMS") = Names(kBearingParamNames);
  m.def(
      "read_bearing_log",
      [](const std::string& path) { return BearingLogToPython(Unwrap(ReadBearingLog(path))); },
      py::arg("path"),
      "Reads a bearing log directory (odometry.csv, bearings.csv, meta.json): a dict with "
      "wheel_radius, wheelbase, initial_distance and runs, each with id, odometry (t, left, "
      "right) and bearings (t, bearing).");
  m.def("calibrate_bearing", &CalibrateBearingPath, py::arg("path"), py::arg("loss") = "cauchy",
        py::arg("loss_scale") = 3.0,
        "Calibrates a bearing log directory as `calib calibrate` does. Returns a dict: params "
        "(phi, psi, eta, delta, xi), estimate, stddev, covariance (5×5), with an initial "
        "distance metric_params, metric_estimate, metric_stddev, metric_covariance; samples, "
        "inliers, converged, verdict, verdict_reason, warnings, report.");
  m.def("diagnose_bearing", &DiagnoseBearingPath, py::arg("path"), py::arg("loss") = "cauchy",
        py::arg("loss_scale") = 3.0, py::arg("alpha") = 0.01, py::arg("cv_blocks") = 5,
        "Tests a bearing log for a time offset, as `calib diagnose` does: the dict of "
        "diagnose_laser.");
}

}  // namespace calib::python
