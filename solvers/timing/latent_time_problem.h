#ifndef CALIB_SOLVERS_TIMING_LATENT_TIME_PROBLEM_H_
#define CALIB_SOLVERS_TIMING_LATENT_TIME_PROBLEM_H_

#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/core/timing/sample_clock.h>
#include <calib/core/timing/stream_samples.h>
#include <calib/core/timing/wheel_angle_spline.h>
#include <calib/problems/laser/laser_latent_time_residual.h>
#include <calib/solvers/common/arrow_terms.h>
#include <calib/solvers/common/band_arrow_solver.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/laser/laser_refinement.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <array>
#include <memory>
#include <vector>

// The laser calibration with latent sample times as one sparse Ceres problem: the six parameters,
// the sensor sample times (stamp + δ_k with a prior N(τ, σ_s²), or a free-running clock
// t0 + P·n + a·u², each within N(τ, σ_s²) of its stamp), and the encoder sample times (stamp + η_j,
// prior N(0, σ_e²)) of the samples that bracket a sensor sample. Each latent touches the one or two
// intervals at its time: ordered by time, the latent block of the normal equations is banded and
// the six parameters and the clock border it (an arrow). Solve() exploits that, and Linearize()
// exposes it for the jitter estimate and the covariance.
namespace calib {

enum class SensorClockModel { kStamps, kFreeRunning };

// The refinement stops once a step gains less than this (whitened χ²/2): the estimate then moved by
// about a tenth of its σ (as LaserRefinementSettings). The rounds that only re-estimate the noise
// scales stop at the looser one.
inline constexpr double kLatentCostTolerance = 0.005;
inline constexpr double kLatentRoundCostTolerance = 0.2;
// Those rounds also stop once the six parameters and the clock have settled to this many σ (their
// information with the latents marginalised), while latents far from them may still creep.
inline constexpr double kLatentRoundGlobalStep = 0.05;
// And after at most this many iterations: a latent far out on an outlier can creep for dozens more
// while the globals hardly move.
inline constexpr int kLatentRoundMaxIterations = 6;
// The final solve also stops once two steps in a row move the globals by less than this (σ): a
// 10⁵-interval pick-up log then takes 38 iterations in all instead of 59, its estimates within
// 0.04 σ. (At 0.03 σ it stopped 0.23 σ short in b on a 10⁴-scan log whose globals crept by 0.02 σ a
// step.)
inline constexpr double kLatentGlobalStep = 0.01;

// Jitter σ's are searched in [kJitterFloor, period]: below 0.1 ms no log can tell them from 0.
inline constexpr double kJitterFloor = 1e-4;

// Prior σ of the clock's curvature a (problems/timing/time_prior_residual.h, ClockDriftPrior).
inline constexpr double kClockDriftSigmaS = 1e-3;

// The centred cubic's RMS error over the RMS spread of the two one-sided ones, for a jump of the
// acceleration at a uniformly random place between polls (where the cubic errs most; on smooth
// stretches the spread is small as well).
inline constexpr double kAngleErrorPerSpread = 0.43;

struct LatentTimeState {
  LaserCalibration calibration;
  Eigen::Vector3d noise_sigma = Eigen::Vector3d::Ones();  // Scan noise (x, y, θ).
  double offset_s = 0.0;                                  // τ (stamp model).
  SampleClock clock;                                      // Clock model.
  std::vector<double> clock_index;                        // n_k per sample (clock model).
  std::vector<double> sensor_latent;   // δ_k per sample: t_k = stamp_k + δ_k (stamp model).
  std::vector<double> encoder_latent;  // η_j per encoder sample.
  double sensor_sigma_s = 0.0;         // Prior σ of δ_k − τ.
  double encoder_sigma_s = 0.0;        // Prior σ of η_j; 0: encoder stamps are times.
  std::vector<int> bracket;            // Per sample: the encoder samples j, j + 1 around it.
  // The clock's indices were named by pick-up stamps (FitPickUpClock): exact, never re-assigned.
  bool clock_indices_named = false;
  // Their period as a prior N(P0, σ²) on the clock's P (σ = 0: none).
  double period_prior_s = 0.0;
  double period_prior_sigma_s = 0.0;
};

// The Gauss–Newton information of the interval residuals (robustified) at the current point,
// split into the global parameters (tangent space) and the latents ordered by time.
struct LatentLinearization {
  int num_globals = 0;
  int offset_global = -1;     // Column of τ among the globals (stamp model), or −1.
  Eigen::MatrixXd h_gg;       // G × G.
  Eigen::MatrixXd h_lg;       // L × G.
  Eigen::MatrixXd h_ll_band;  // (w + 1) × L, band(d, i) = H(i + d, i).
  Eigen::VectorXd b_l;        // Jᵀr, latent part.
  // The same latent pieces per residual component c (x, y, θ), whitened by `noise_sigma`, so that
  // the evidence can be evaluated at another scan noise (rows scale by noise_sigma(c)/σ_c).
  std::array<Eigen::MatrixXd, 3> h_ll_band_c;
  std::array<Eigen::VectorXd, 3> b_l_c;
  Eigen::Vector3d rr_c = Eigen::Vector3d::Zero();  // Σ r_c² (whitened, loss-corrected).
  Eigen::Vector3d noise_sigma = Eigen::Vector3d::Ones();
  int num_intervals = 0;
  Eigen::VectorXd latent_value;  // Current latent values.
  std::vector<bool> latent_is_sensor;
  std::vector<int> latent_owner;  // Sample or encoder index.
  Eigen::Matrix3d odometry_plus_jacobian = Eigen::Matrix3d::Identity();
  LossCorrectionSums loss_sums;  // Over the interval residuals.
  double data_cost = 0.0;        // Ceres cost of the interval residuals (½Σρ).
  // Clock model: Σr² and count of the stamp prior (t − s − τ)/σ_s, a part of the evidence that
  // the latents' does not hold (the stamp model has it in its sensor latents' prior).
  double stamp_prior_chi2 = 0.0;
  int stamp_prior_count = 0;
  // Linearize(true) only: each interval's gradient contribution Jᵀr (loss applied), for a
  // sandwich covariance. Its globals' part (intervals × G; the clock model's stamp priors added to
  // the row of their sample's interval) and its latents' (column among the latents and value, −1
  // past the last); `latent_row`: the interval whose row takes each latent's prior.
  static constexpr int kMaxIntervalLatents = 8;
  struct LatentScore {
    int latent = -1;
    double value = 0.0;
    double angle[4] = {0.0, 0.0, 0.0, 0.0};  // Jᵀ·∂r/∂(end angle w), as angle_globals.
    double row[3] = {0.0, 0.0, 0.0};         // J's rows (x, y, θ) in this column, as row_globals.
  };
  Eigen::MatrixXd score_globals;
  std::vector<std::array<LatentScore, kMaxIntervalLatents>> score_latents;
  std::vector<int> latent_row;
  // The same projections of the residual's derivatives by its four end angles (start left,
  // start right, end left, end right) instead of r, where the wheel angles come from the cubic
  // between polls; the interval's first sample; and per sample the σ of its interpolated left and
  // right angles and its segment (the encoder sample before it).
  std::array<Eigen::MatrixXd, 4> angle_globals;
  // The interval's whitened, loss-corrected Jacobian rows (x, y, θ) in the globals' columns.
  std::array<Eigen::MatrixXd, 3> row_globals;
  std::vector<int> interval_sample;
  struct AngleSpread {
    double left_rad = 0.0, right_rad = 0.0;
    int segment = -1;
  };
  std::vector<AngleSpread> sample_angle;
};

class LatentTimeProblem {
 public:
  LatentTimeProblem(const StreamSamples& data, SensorClockModel model, const LatentTimeState& state,
                    const LaserRefinementOptions& options, bool estimate_offset);
  ~LatentTimeProblem();
  LatentTimeProblem(const LatentTimeProblem&) = delete;
  LatentTimeProblem& operator=(const LatentTimeProblem&) = delete;

  // Levenberg–Marquardt on the band-plus-arrow normal equations (solvers/common/band_arrow_solver),
  // until a step gains less than `cost_tolerance` (whitened χ²/2; relative below 1e-6) or, when
  // `global_step_tolerance` is positive, two steps in a row move the globals by less than it (σ);
  // at most `max_iterations` when positive, else the refinement options' limit.
  Status Solve(BandArrowSummary* summary, double cost_tolerance = kLatentCostTolerance,
               double global_step_tolerance = 0.0, int max_iterations = 0);
  // New noise scales for the next solve, in place (the residuals hold pointers to them): the scan
  // noise, and the jitters of the latents the problem has (a jitter of 0 must stay 0 and a
  // positive one positive, else the problem must be rebuilt).
  Status SetNoiseScales(const Eigen::Vector3d& noise_sigma, double sensor_sigma_s,
                        double encoder_sigma_s);
  // The same problem by Ceres' own LM and sparse Cholesky: the reference for the solver above.
  Status SolveWithCeres(ceres::Solver::Summary* summary,
                        double cost_tolerance = kLatentCostTolerance);
  LatentTimeState state() const;
  // The latent time of sample k and of encoder sample j.
  double SampleTime(int k) const;
  double EncoderTime(int j) const;
  // True when every sample's time still lies between its bracketing encoder times (else the
  // problem must be rebuilt from state() with new brackets).
  bool BracketsHold() const;
  // The brackets of the current latent times (for a rebuilt problem).
  std::vector<int> Brackets() const;
  // Per sample, the σ of its wheel angles on the cubic between polls: kAngleErrorPerSpread times
  // the spread of the two one-sided cubics (RateSide) at its time; empty with the line.
  std::vector<LatentLinearization::AngleSpread> AngleSpreads() const;
  // Unwhitened errors of the intervals, in data.interval_start order.
  std::vector<Eigen::Vector3d> Errors() const;
  // `with_scores`: also each interval's gradient contribution (LatentLinearization::score_*).
  StatusOr<LatentLinearization> Linearize(bool with_scores = false) const;
  size_t num_intervals() const { return interval_functions_.size(); }
  const ceres::LossFunction* loss() const { return loss_.get(); }

 private:
  // A latent time's block, in time order (stamp order: the latent times keep it up to a few σ),
  // which makes the latent block of the normal equations banded.
  struct LatentRef {
    double stamp_s;
    int owner;  // Sample or encoder index.
    bool sensor;
    double* value;
  };
  std::vector<LatentRef> LatentOrder() const;
  void AddIntervals();
  Status CheckPositive() const;
  SolverSettings Settings(double cost_tolerance) const;
  // The samples at the ends of the intervals (those the clock model's stamp prior covers).
  std::vector<int> ClockSamples() const;
  LatentTimeEnd MakeEnd(int k, std::vector<double*>* blocks, std::vector<int>* sizes) const;
  void AddResidual(ceres::CostFunction* cost, const ceres::LossFunction* loss,
                   const std::vector<double*>& blocks);
  // The parameter blocks of interval i.
  double* const* IntervalBlocks(size_t i) const {
    return terms_.values.data() + terms_.first_value[i];
  }
  int NumIntervalBlocks(size_t i) const {
    return terms_.first_value[i + 1] - terms_.first_value[i];
  }

  const StreamSamples& data_;
  SensorClockModel model_;
  LatentTimeState state_;
  LaserRefinementOptions options_;
  bool estimate_offset_;
  std::unique_ptr<ceres::LossFunction> loss_;
  // The blocks and residuals (intervals first, then the priors), for the band-arrow solver and,
  // as a reference, Ceres; the cost functions and the odometry's manifold are owned here.
  ArrowTerms terms_;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs_;
  std::unique_ptr<ceres::Manifold> odometry_manifold_;
  std::unique_ptr<Eigen::Matrix3d> sqrt_information_;
  double odometry_[3];
  double base_T_sensor_[3];
  double offset_ = 0.0;
  double clock_[3] = {0.0, 0.0, 0.0};
  std::vector<char> sensor_used_, encoder_used_;
  std::vector<WheelRates> encoder_rates_;
  std::vector<const ceres::CostFunction*> interval_functions_;  // terms_' first residuals.
  BandArrowSolver solver_;                                      // Built at the first solve.
  bool solver_built_ = false;
};

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_LATENT_TIME_PROBLEM_H_
