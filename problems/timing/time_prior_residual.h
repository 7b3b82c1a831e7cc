#ifndef CALIB_PROBLEMS_TIMING_TIME_PRIOR_RESIDUAL_H_
#define CALIB_PROBLEMS_TIMING_TIME_PRIOR_RESIDUAL_H_

#include <ceres/sized_cost_function.h>

namespace calib {

// The prior of a latent time correction: r = (δ − τ)/σ with τ a common offset (the block
// `offset`), or r = δ/σ without one. Linear, so its Jacobian is written out. σ is held by pointer
// so that a re-estimated jitter applies without rebuilding the problem; it must outlive the cost.
class TimePriorWithOffset : public ceres::SizedCostFunction<1, 1, 1> {
 public:
  explicit TimePriorWithOffset(const double* sigma_s) : sigma_(sigma_s) {}
  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    residual[0] = (parameters[0][0] - parameters[1][0]) / *sigma_;
    if (jacobians != nullptr) {
      if (jacobians[0] != nullptr) jacobians[0][0] = 1.0 / *sigma_;
      if (jacobians[1] != nullptr) jacobians[1][0] = -1.0 / *sigma_;
    }
    return true;
  }

 private:
  const double* sigma_;
};

class TimePrior : public ceres::SizedCostFunction<1, 1> {
 public:
  explicit TimePrior(const double* sigma_s) : sigma_(sigma_s) {}
  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    residual[0] = parameters[0][0] / *sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) jacobians[0][0] = 1.0 / *sigma_;
    return true;
  }

 private:
  const double* sigma_;
};

// A sample's stamp under a free-running clock (t0, P, a) and a common offset τ: the time
// t = t0 + P·n + a·u² of sample n lies τ from its stamp s with the pick-up scatter σ,
// r = (t − s − τ)/σ. Linear; σ held by pointer like TimePriorWithOffset's.
class ClockStampPrior : public ceres::SizedCostFunction<1, 3, 1> {
 public:
  ClockStampPrior(double stamp_s, double index, double curvature, const double* sigma_s)
      : stamp_(stamp_s), index_(index), curvature_(curvature), sigma_(sigma_s) {}
  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    const double* c = parameters[0];
    residual[0] = (c[0] + c[1] * index_ + c[2] * curvature_ - stamp_ - parameters[1][0]) / *sigma_;
    if (jacobians != nullptr) {
      if (jacobians[0] != nullptr) {
        jacobians[0][0] = 1.0 / *sigma_;
        jacobians[0][1] = index_ / *sigma_;
        jacobians[0][2] = curvature_ / *sigma_;
      }
      if (jacobians[1] != nullptr) jacobians[1][0] = -1.0 / *sigma_;
    }
    return true;
  }

 private:
  double stamp_, index_, curvature_;
  const double* sigma_;
};

// The prior of a free-running clock's curvature a (the block (t0, P, a)): r = a/σ_a. A real
// oscillator's rate error is constant over a log (it is in P); curvature is aging, a millisecond
// at most, and left free it trades against misassigned sample indices.
class ClockDriftPrior : public ceres::SizedCostFunction<1, 3> {
 public:
  explicit ClockDriftPrior(double sigma_s) : sigma_(sigma_s) {}
  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    residual[0] = parameters[0][2] / sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      jacobians[0][0] = 0.0;
      jacobians[0][1] = 0.0;
      jacobians[0][2] = 1.0 / sigma_;
    }
    return true;
  }

 private:
  double sigma_;
};

// The period P of a free-running clock (the block (t0, P, a)) as pick-up stamps pin it:
// r = (P − P0)/σ_P. The motion alone leaves P a few σ_P·10³ loose and bends it with what the
// wheel angles between polls miss.
class ClockPeriodPrior : public ceres::SizedCostFunction<1, 3> {
 public:
  ClockPeriodPrior(double period_s, double sigma_s) : period_(period_s), sigma_(sigma_s) {}
  bool Evaluate(double const* const* parameters, double* residual,
                double** jacobians) const override {
    residual[0] = (parameters[0][1] - period_) / sigma_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      jacobians[0][0] = 0.0;
      jacobians[0][1] = 1.0 / sigma_;
      jacobians[0][2] = 0.0;
    }
    return true;
  }

 private:
  double period_, sigma_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_TIMING_TIME_PRIOR_RESIDUAL_H_
