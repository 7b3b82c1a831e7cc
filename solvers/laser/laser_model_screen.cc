#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/laser/laser_model_screen.h>

#include <cctype>

namespace calib {
namespace {

std::string Lowered(std::string sentence) {
  if (!sentence.empty()) sentence[0] = static_cast<char>(std::tolower(sentence[0]));
  return sentence;
}

}  // namespace

StatusOr<LaserModelScreen> ScreenLaserModel(const std::vector<LaserInterval>& intervals,
                                            const LaserCalibrationOptions& calibration,
                                            bool sample_times_estimated) {
  LaserDiagnosisOptions options;
  options.calibration = calibration;
  options.calibration.progress = nullptr;
  options.max_effects = 0;
  options.screen_only = true;
  // Stamp jitter is calibrate's own business (its interval-jitter treatment).
  options.timing_candidates = false;
  options.sample_times_estimated = sample_times_estimated;
  CALIB_ASSIGN_OR_RETURN(const LaserDiagnosis diagnosis, DiagnoseLaser(intervals, options));
  LaserModelScreen screen;
  for (const LaserFinding& f : diagnosis.findings) {
    if (f.score_significant && !f.confounded) screen.effects.push_back(f.name);
  }
  // The binned-means tests over few intervals per bin false-alarm on clean simulated logs (3 of 3
  // at 60 intervals, 1 of 3 at 200, none of 3 at 1000): below this their finding is not used.
  constexpr size_t kMinStructureIntervals = 500;
  if (diagnosis.structure_before.found && intervals.size() >= kMinStructureIntervals) {
    // "The residuals still depend on …: a mismatch that the adopted model does not explain."
    screen.structure = diagnosis.structure_before.statement;
    const std::string adopted = "the adopted model";
    const size_t at = screen.structure.find(adopted);
    if (at != std::string::npos) screen.structure.replace(at, adopted.size(), "the base model");
  }
  screen.flagged = !screen.effects.empty() || !screen.structure.empty();
  if (!screen.flagged) return screen;
  std::string what;
  for (const std::string& name : screen.effects) what += (what.empty() ? "" : ", ") + name;
  screen.warning = "the base model leaves something out: " +
                   (what.empty() ? std::string() : "the score tests point to " + what + "; ") +
                   (screen.structure.empty() ? std::string() : Lowered(screen.structure) + " ") +
                   "Run `calib diagnose` on this log to find which physics, and how much it moves "
                   "the calibration.";
  return screen;
}

}  // namespace calib
