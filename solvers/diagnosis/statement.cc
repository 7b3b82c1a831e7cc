#include <calib/core/text_format.h>
#include <calib/solvers/diagnosis/statement.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace calib {
namespace {

// "score test 12.3, p = 1e-05, 40 % of it absorbable by the base parameters".
std::string Tested(const Finding& f, const std::string& verb, double share,
                   const std::string& base) {
  return Format("score test %.1f, ", f.statistic) + PValueText(f.p_value) +
         Format(", %.0f %% of it ", 100.0 * share) + verb + " by the base " + base;
}

std::string Adopted(const Finding& f, const StatementWords& words) {
  const std::string evidence =
      std::isfinite(f.absorbed_share)
          ? Tested(f, "hidden", f.absorbed_share, words.base)
          : Tested(f, "absorbable", std::max(0.0, f.concealment), words.base);
  std::string text = words.adopted + " (" + evidence + ")";
  text += "; the base fit had absorbed it as " +
          ShiftWords(f.base_shift, f.base_shift_sigmas, words.params);
  text += Format("; modelling it cuts the held-out residual cost by %.1f %%",
                 100.0 * f.heldout_reduction);
  if (!f.location.covariate.empty()) {
    text += "; it follows " + words.covariate + WindowWords(f.location);
  }
  return text + ".";
}

std::string NotAdopted(const Finding& f, const StatementWords& words) {
  std::string text = "No " + f.name + " adopted: " +
                     Tested(f, "absorbable", std::max(0.0, f.concealment), words.base) +
                     words.estimate;
  if (f.refitted) {
    if (f.lr_p_value > f.holm_level) {
      text += "; the likelihood-ratio test did not confirm it (" + PValueText(f.lr_p_value) + ")";
    } else {
      text += Format("; the held-out blocks did not confirm it (held-out cost %+.2f %%)",
                     -100.0 * f.heldout_reduction);
    }
  }
  return text + ".";
}

}  // namespace

Eigen::VectorXd ShiftInSigmas(const Eigen::VectorXd& shift, const Eigen::VectorXd& sigma) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(shift.size());
  for (Eigen::Index i = 0; i < shift.size() && i < sigma.size(); ++i) {
    if (sigma(i) > 0.0) out(i) = shift(i) / sigma(i);
  }
  return out;
}

std::string ShiftWords(const Eigen::VectorXd& shift, const Eigen::VectorXd& sigmas,
                       const std::vector<ParamWords>& params) {
  std::vector<int> order(params.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(sigmas(a)) > std::abs(sigmas(b)); });
  std::string text;
  for (size_t rank = 0; rank < 2 && rank < order.size(); ++rank) {
    const int i = order[rank];
    if (rank > 0 && std::abs(sigmas(i)) < 1.0) break;
    if (rank > 0) text += " and ";
    text += params[i].name + Format(" %+.3g", shift(i) * params[i].scale) + params[i].suffix +
            Format(" (%.1f σ)", std::abs(sigmas(i)));
  }
  return text;
}

std::string WriteStatement(const Finding& f, const StatementWords& words) {
  if (f.no_information) {
    return "The log's motion does not excite " + f.name +
           " at all (no sensitivity): it can be neither found nor excluded.";
  }
  if (f.confounded) return words.confounded;
  return f.significant ? Adopted(f, words) : NotAdopted(f, words);
}

}  // namespace calib
