#include <calib/tools/report/verdict.h>

#include <algorithm>

namespace calib {
namespace {

void AddUnique(const std::string& sentence, std::vector<std::string>* out) {
  if (std::find(out->begin(), out->end(), sentence) == out->end()) out->push_back(sentence);
}

}  // namespace

Verdict JudgeResult(const VerdictInputs& inputs) {
  Verdict verdict;
  for (const std::string& warning : inputs.warnings) AddUnique(warning, &verdict.warnings);
  std::vector<std::string> untreated;  // Streams whose stamps are not sample times.
  if (inputs.streams != nullptr) {
    for (const StreamTiming& stream : *inputs.streams) {
      if (stream.stamps_are_sample_times) continue;
      untreated.push_back(stream.source.empty() ? stream.stream : stream.source);
      const std::string what = inputs.timing_treated
                                   ? ": its stamps are pick-up times, not sample times; the "
                                     "calibration modelled their offset and scatter"
                                   : ": its stamps are pick-up times, not sample times; taken as "
                                     "sample times they bias the wheel radii and wheelbase, and "
                                     "the boundary-jitter treatment reduces but does not remove "
                                     "that bias, so the result is unreliable";
      AddUnique(untreated.back() + what, &verdict.warnings);
    }
  }
  for (const std::string& sentence : inputs.disagreements) AddUnique(sentence, &verdict.warnings);

  for (const std::string& sentence : inputs.unreliable) AddUnique(sentence, &verdict.warnings);
  if (!inputs.converged) {
    verdict.verdict = "unreliable";
    verdict.reason = "the refinement did not converge";
  } else if (!inputs.unreliable.empty()) {
    verdict.verdict = "unreliable";
    verdict.reason = inputs.unreliable.front();
  } else if (!untreated.empty() && !inputs.timing_treated) {
    verdict.verdict = "unreliable";
    verdict.reason = "the stamps of " + untreated.front() + " are not the sample times";
  } else if (!inputs.disagreements.empty()) {
    // A model the totals reject may still be close (the Censi sets: a travel asymmetry of 2 %).
    verdict.verdict = "check";
    verdict.reason =
        "the calibrated wheel model disagrees with the sensor's totals, a check that needs no "
        "timing: the estimate is likely biased";
  } else if (!inputs.model_screen.empty()) {
    verdict.verdict = "check";
    verdict.reason =
        "the residuals show physics the model leaves out: run `calib diagnose` before using "
        "the numbers";
  } else if (!verdict.warnings.empty()) {
    verdict.verdict = "check";
    verdict.reason = "read the warnings before using the numbers";
  } else {
    verdict.verdict = "trusted";
    verdict.reason = "no check found a problem";
  }
  if (!inputs.model_screen.empty()) {
    AddUnique(inputs.model_screen, &verdict.warnings);
    verdict.model_screen = inputs.model_screen;
    if (verdict.reason.find("calib diagnose") == std::string::npos) {
      verdict.reason +=
          "; the residuals also show physics the model leaves out: run `calib "
          "diagnose`";
    }
  }
  return verdict;
}

std::string AddVerdict(const Verdict& verdict, nlohmann::ordered_json* json) {
  (*json)["verdict"] = verdict.verdict;
  (*json)["verdict_reason"] = verdict.reason;
  (*json)["warnings"] = verdict.warnings;
  const std::string screen =
      verdict.model_screen.empty() ? "" : "  warning: " + verdict.model_screen + "\n";
  return screen + "  verdict: " + verdict.verdict + " (" + verdict.reason + ")\n";
}

}  // namespace calib
