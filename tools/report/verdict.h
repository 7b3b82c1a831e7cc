#ifndef CALIB_TOOLS_REPORT_VERDICT_H_
#define CALIB_TOOLS_REPORT_VERDICT_H_

#include <calib/core/timing/stamp_timing.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// The contract's "verdict" and "warnings" of `calib calibrate`, one rule for both problems:
//   unreliable — the fit did not converge, the data cannot support the answer (most samples
//                gross, inliers that do not determine it), or a stream's stamps are not sample
//                times and the problem has no validated treatment for it;
//   check      — any other warning (the timing-free consistency check disagrees, the model
//                screen finds physics the model leaves out, weak observability, modelled
//                timing, outliers, ...);
//   trusted    — nothing to say.
namespace calib {

struct VerdictInputs {
  bool converged = true;
  std::vector<std::string> warnings;       // The result's own sentences.
  std::vector<std::string> disagreements;  // Failed consistency checks (→ check).
  std::vector<std::string> unreliable;     // Why the numbers cannot be relied on (→ unreliable).
  const std::vector<StreamTiming>* streams = nullptr;
  // True when the calibration models stamps that are not sample times well enough to trust
  // (the bearing problem's offset and jitter); false for the laser problem, whose latent-time
  // calibration of raw streams is not validated yet.
  bool timing_treated = false;
  // The model screen's sentence (solvers/laser/laser_model_screen.h) when it found physics the
  // model leaves out: the verdict is at best "check", and it says to run `calib diagnose`.
  std::string model_screen;
};

struct Verdict {
  std::string verdict;  // "trusted", "check" or "unreliable".
  std::vector<std::string> warnings;
  std::string reason;        // One sentence: why this verdict.
  std::string model_screen;  // Printed under the verdict line when not empty.
};

Verdict JudgeResult(const VerdictInputs& inputs);

// Sets json["verdict"], json["verdict_reason"] and json["warnings"], and returns the summary's
// verdict line.
std::string AddVerdict(const Verdict& verdict, nlohmann::ordered_json* json);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_VERDICT_H_
