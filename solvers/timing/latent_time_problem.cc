#include <calib/problems/laser/laser_latent_time_cost.h>
#include <calib/problems/positive_manifold.h>
#include <calib/problems/timing/time_prior_residual.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/timing/latent_time_problem.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace calib {
LatentTimeProblem::LatentTimeProblem(const StreamSamples& data, SensorClockModel model,
                                     const LatentTimeState& state,
                                     const LaserRefinementOptions& options, bool estimate_offset)
    : data_(data),
      model_(model),
      state_(state),
      options_(options),
      estimate_offset_(estimate_offset) {
  state_.sensor_latent.resize(data.samples.size(), 0.0);
  state_.encoder_latent.resize(data.encoders.size(), 0.0);
  state_.clock_index.resize(data.samples.size(), 0.0);
  if (state_.bracket.size() != data.samples.size()) {
    state_.bracket.clear();
    for (const StreamSample& sample : data.samples) state_.bracket.push_back(sample.bracket);
  }
  loss_ = MakeLossFunction(options.loss, options.loss_scale);
  sqrt_information_ =
      std::make_unique<Eigen::Matrix3d>(state.noise_sigma.cwiseInverse().asDiagonal());
  const LaserParamVector v = state.calibration.ToVector();
  for (int i = 0; i < 3; ++i) {
    odometry_[i] = v(i);
    base_T_sensor_[i] = v(3 + i);
  }
  offset_ = state.offset_s;
  clock_[0] = state.clock.t0_s;
  clock_[1] = state.clock.period_s;
  clock_[2] = state.clock.drift_s;
  odometry_manifold_ = std::make_unique<PositiveManifold<3>>();
  terms_.AddBlock(odometry_, 3, odometry_manifold_.get());
  terms_.AddBlock(base_T_sensor_, 3);
  if (model == SensorClockModel::kFreeRunning) terms_.AddBlock(clock_, 3);
  sensor_used_.assign(data.samples.size(), 0);
  encoder_used_.assign(data.encoders.size(), 0);
  // The wheel rates at each encoder sample, at the encoder times this problem starts from: held
  // fixed while it is solved (the polish builds the problem again from the rounds' times).
  if (CubicBetweenPolls(data.encoder_period_s)) {
    const auto time_s = [&](size_t j) { return data.encoders[j].t_s + state_.encoder_latent[j]; };
    encoder_rates_.reserve(data.encoders.size());
    for (size_t j = 0; j < data.encoders.size(); ++j) {
      encoder_rates_.push_back(WheelRatesAt(data.encoders, j, time_s));
    }
  }
  AddIntervals();
}

LatentTimeProblem::~LatentTimeProblem() = default;

void LatentTimeProblem::AddResidual(ceres::CostFunction* cost, const ceres::LossFunction* loss,
                                    const std::vector<double*>& blocks) {
  costs_.emplace_back(cost);
  terms_.AddResidual(cost, loss, blocks);
}

LatentTimeEnd LatentTimeProblem::MakeEnd(int k, std::vector<double*>* blocks,
                                         std::vector<int>* sizes) const {
  const auto block_index = [&](double* block, int size) {
    const auto it = std::find(blocks->begin(), blocks->end(), block);
    if (it != blocks->end()) return static_cast<int>(it - blocks->begin());
    blocks->push_back(block);
    sizes->push_back(size);
    return static_cast<int>(blocks->size()) - 1;
  };
  const StreamSample& sample = data_.samples[k];
  LatentTimeEnd end;
  end.stamp_s = sample.stamp_s;
  if (model_ == SensorClockModel::kFreeRunning) {
    end.clock = true;
    end.index = state_.clock_index[k];
    end.curvature = state_.clock.Curvature(end.index);
    end.time_block = block_index(const_cast<double*>(clock_), 3);
  } else if (state_.sensor_sigma_s > 0.0) {
    end.time_block = block_index(const_cast<double*>(&state_.sensor_latent[k]), 1);
  } else {
    end.stamp_s += state_.offset_s;
  }
  for (int i = 0; i < 2; ++i) {
    const EncoderSample& e = data_.encoders[state_.bracket[k] + i];
    end.encoder_stamp_s[i] = e.t_s;
    end.left_rad[i] = e.left_rad;
    end.right_rad[i] = e.right_rad;
    if (state_.encoder_sigma_s > 0.0) {
      end.encoder_block[i] =
          block_index(const_cast<double*>(&state_.encoder_latent[state_.bracket[k] + i]), 1);
    }
  }
  // Without rates (dense polls), both ends of the segment take its secant between the stamps: the
  // line, up to the few % the latent encoder times move it.
  const double secant_s = end.encoder_stamp_s[1] - end.encoder_stamp_s[0];
  for (int i = 0; i < 2; ++i) {
    const int j = state_.bracket[k] + i;
    end.left_rate[i] = encoder_rates_.empty() ? (end.left_rad[1] - end.left_rad[0]) / secant_s
                                              : encoder_rates_[j].left;
    end.right_rate[i] = encoder_rates_.empty() ? (end.right_rad[1] - end.right_rad[0]) / secant_s
                                               : encoder_rates_[j].right;
  }
  return end;
}

void LatentTimeProblem::AddIntervals() {
  static_assert(sizeof(double) == 8);
  for (const int k : data_.interval_start) {
    std::vector<double*> blocks = {odometry_, base_T_sensor_};
    std::vector<int> sizes = {3, 3};
    const LatentTimeEnd start = MakeEnd(k, &blocks, &sizes);
    const LatentTimeEnd end = MakeEnd(k + 1, &blocks, &sizes);
    std::vector<double> left, right;
    for (int j = state_.bracket[k] + 1; j <= state_.bracket[k + 1]; ++j) {
      left.push_back(data_.encoders[j].left_rad);
      right.push_back(data_.encoders[j].right_rad);
    }
    const Pose2d measured =
        Between(data_.samples[k].world_T_sensor, data_.samples[k + 1].world_T_sensor);
    ceres::CostFunction* cost = LaserLatentTimeCost::Create(
        Pose2d(measured(0), measured(1), WrapAngle(measured(2))), sqrt_information_.get(), start,
        end, std::move(left), std::move(right), sizes);
    AddResidual(cost, loss_.get(), blocks);
    interval_functions_.push_back(cost);
    for (double* block : blocks) {
      if (block >= state_.sensor_latent.data() &&
          block < state_.sensor_latent.data() + state_.sensor_latent.size()) {
        sensor_used_[block - state_.sensor_latent.data()] = 1;
      } else if (block >= state_.encoder_latent.data() &&
                 block < state_.encoder_latent.data() + state_.encoder_latent.size()) {
        encoder_used_[block - state_.encoder_latent.data()] = 1;
      }
    }
  }
  for (const LatentRef& latent : LatentOrder()) terms_.AddBlock(latent.value, 1);
  // Priors: δ_k ~ N(τ, σ_s²) (τ fixed at its value unless estimated), η_j ~ N(0, σ_e²).
  if (model_ == SensorClockModel::kStamps && state_.sensor_sigma_s > 0.0) {
    terms_.AddBlock(&offset_, 1, nullptr, !estimate_offset_);
    for (size_t k = 0; k < sensor_used_.size(); ++k) {
      if (!sensor_used_[k]) continue;
      AddResidual(new TimePriorWithOffset(&state_.sensor_sigma_s), nullptr,
                  {&state_.sensor_latent[k], &offset_});
    }
  }
  if (model_ == SensorClockModel::kFreeRunning) {
    AddResidual(new ClockDriftPrior(kClockDriftSigmaS), nullptr, {clock_});
    if (state_.period_prior_sigma_s > 0.0) {
      AddResidual(new ClockPeriodPrior(state_.period_prior_s, state_.period_prior_sigma_s), nullptr,
                  {clock_});
    }
    // The stamps: each sample's clock time lies τ from its stamp, with the pick-up scatter σ_s.
    if (state_.sensor_sigma_s > 0.0) {
      terms_.AddBlock(&offset_, 1, nullptr, !estimate_offset_);
      for (const int k : ClockSamples()) {
        const double n = state_.clock_index[k];
        AddResidual(new ClockStampPrior(data_.samples[k].stamp_s, n, state_.clock.Curvature(n),
                                        &state_.sensor_sigma_s),
                    nullptr, {clock_, &offset_});
      }
    }
  }
  for (size_t j = 0; j < encoder_used_.size(); ++j) {
    if (!encoder_used_[j]) continue;
    AddResidual(new TimePrior(&state_.encoder_sigma_s), nullptr, {&state_.encoder_latent[j]});
  }
}

SolverSettings LatentTimeProblem::Settings(double cost_tolerance) const {
  SolverSettings settings;
  // For Ceres: each latent touches the one or two intervals at its time, sparse normal equations
  // with SuiteSparse's fill-reducing ordering (Schur elimination does not apply, latents share
  // residuals with each other).
  settings.linear_solver = ceres::SPARSE_NORMAL_CHOLESKY;
  settings.max_iterations = options_.max_iterations;
  settings.num_threads = options_.num_threads;
  settings.function_tolerance =
      std::min(1e-6, cost_tolerance / std::max<size_t>(1, interval_functions_.size()));
  settings.gradient_tolerance = 1e-12;
  settings.parameter_tolerance = 1e-10;
  return settings;
}

Status LatentTimeProblem::SetNoiseScales(const Eigen::Vector3d& noise_sigma, double sensor_sigma_s,
                                         double encoder_sigma_s) {
  if ((sensor_sigma_s > 0.0) != (state_.sensor_sigma_s > 0.0) ||
      (encoder_sigma_s > 0.0) != (state_.encoder_sigma_s > 0.0) ||
      !(noise_sigma.array() > 0.0).all()) {
    return Status::Internal("the timing-aware problem cannot take these noise scales in place");
  }
  state_.noise_sigma = noise_sigma;
  *sqrt_information_ = noise_sigma.cwiseInverse().asDiagonal();
  state_.sensor_sigma_s = sensor_sigma_s;
  state_.encoder_sigma_s = encoder_sigma_s;
  return Status::Ok();
}

Status LatentTimeProblem::Solve(BandArrowSummary* summary, double cost_tolerance,
                                double global_step_tolerance, int max_iterations) {
  if (!solver_built_) {
    std::vector<double*> latents;
    for (const LatentRef& latent : LatentOrder()) latents.push_back(latent.value);
    CALIB_RETURN_IF_ERROR(solver_.Build(latents, terms_));
    solver_built_ = true;
  }
  const SolverSettings settings = Settings(cost_tolerance);
  BandArrowOptions band;
  band.max_iterations = settings.max_iterations;
  band.num_threads = settings.num_threads;
  band.function_tolerance = settings.function_tolerance;
  band.gradient_tolerance = settings.gradient_tolerance;
  band.parameter_tolerance = settings.parameter_tolerance;
  band.global_step_tolerance = global_step_tolerance;
  if (max_iterations > 0) band.max_iterations = std::min(band.max_iterations, max_iterations);
  CALIB_RETURN_IF_ERROR(solver_.Solve(band, "the timing-aware refinement", summary));
  return CheckPositive();
}

Status LatentTimeProblem::SolveWithCeres(ceres::Solver::Summary* summary, double cost_tolerance) {
  const std::unique_ptr<ceres::Problem> problem = terms_.ToProblem();
  CALIB_RETURN_IF_ERROR(calib::Solve(Settings(cost_tolerance), "the timing-aware refinement",
                                     problem.get(), summary));
  return CheckPositive();
}

Status LatentTimeProblem::CheckPositive() const {
  if (!(odometry_[0] > 0.0 && odometry_[1] > 0.0 && odometry_[2] > 0.0)) {
    return Status::NotObservable(
        "the timing-aware refinement drove a wheel radius or the wheelbase to a non-positive "
        "value");
  }
  return Status::Ok();
}

std::vector<LatentTimeProblem::LatentRef> LatentTimeProblem::LatentOrder() const {
  std::vector<LatentRef> order;
  if (model_ == SensorClockModel::kStamps && state_.sensor_sigma_s > 0.0) {
    for (size_t k = 0; k < sensor_used_.size(); ++k) {
      if (!sensor_used_[k]) continue;
      order.push_back({data_.samples[k].stamp_s, static_cast<int>(k), true,
                       const_cast<double*>(&state_.sensor_latent[k])});
    }
  }
  for (size_t j = 0; j < encoder_used_.size(); ++j) {
    if (!encoder_used_[j]) continue;
    order.push_back({data_.encoders[j].t_s, static_cast<int>(j), false,
                     const_cast<double*>(&state_.encoder_latent[j])});
  }
  std::stable_sort(order.begin(), order.end(), [](const LatentRef& a, const LatentRef& b) {
    return a.stamp_s < b.stamp_s || (a.stamp_s == b.stamp_s && a.owner < b.owner);
  });
  return order;
}

std::vector<int> LatentTimeProblem::ClockSamples() const {
  std::vector<char> used(data_.samples.size(), 0);
  for (const int k : data_.interval_start) used[k] = used[k + 1] = 1;
  std::vector<int> samples;
  for (size_t k = 0; k < used.size(); ++k) {
    if (used[k]) samples.push_back(static_cast<int>(k));
  }
  return samples;
}

LatentTimeState LatentTimeProblem::state() const {
  LatentTimeState s = state_;
  LaserParamVector v;
  v << odometry_[0], odometry_[1], odometry_[2], base_T_sensor_[0], base_T_sensor_[1],
      WrapAngle(base_T_sensor_[2]);
  s.calibration = LaserCalibration::FromVector(v);
  s.offset_s = offset_;
  s.clock.t0_s = clock_[0];
  s.clock.period_s = clock_[1];
  s.clock.drift_s = clock_[2];
  if (model_ == SensorClockModel::kStamps && state_.sensor_sigma_s <= 0.0) {
    std::fill(s.sensor_latent.begin(), s.sensor_latent.end(), offset_);
  }
  return s;
}

double LatentTimeProblem::SampleTime(int k) const {
  const StreamSample& sample = data_.samples[k];
  if (model_ == SensorClockModel::kFreeRunning) {
    const double n = state_.clock_index[k];
    return clock_[0] + clock_[1] * n + clock_[2] * state_.clock.Curvature(n);
  }
  return sample.stamp_s + (state_.sensor_sigma_s > 0.0 ? state_.sensor_latent[k] : offset_);
}

double LatentTimeProblem::EncoderTime(int j) const {
  return data_.encoders[j].t_s + (state_.encoder_sigma_s > 0.0 ? state_.encoder_latent[j] : 0.0);
}

std::vector<int> LatentTimeProblem::Brackets() const {
  std::vector<double> times(data_.encoders.size());
  for (size_t j = 0; j < times.size(); ++j) times[j] = EncoderTime(static_cast<int>(j));
  std::vector<int> brackets(data_.samples.size());
  const int last = static_cast<int>(times.size()) - 2;
  for (size_t k = 0; k < brackets.size(); ++k) {
    const int after = static_cast<int>(
        std::upper_bound(times.begin(), times.end(), SampleTime(static_cast<int>(k))) -
        times.begin());
    brackets[k] = std::clamp(after - 1, 0, last);
  }
  return brackets;
}

std::vector<LatentLinearization::AngleSpread> LatentTimeProblem::AngleSpreads() const {
  std::vector<LatentLinearization::AngleSpread> spreads;
  if (encoder_rates_.empty()) return spreads;
  const auto time_s = [&](size_t j) { return EncoderTime(static_cast<int>(j)); };
  const size_t m = data_.encoders.size();
  std::vector<WheelRates> forward(m), backward(m);
  for (size_t j = 0; j < m; ++j) {
    forward[j] = WheelRatesAt(data_.encoders, j, time_s, RateSide::kForward);
    backward[j] = WheelRatesAt(data_.encoders, j, time_s, RateSide::kBackward);
  }
  spreads.resize(data_.samples.size());
  for (size_t k = 0; k < spreads.size(); ++k) {
    const int j = state_.bracket[k];
    const double t = SampleTime(static_cast<int>(k)), e0 = time_s(j), e1 = time_s(j + 1);
    const EncoderSample &a = data_.encoders[j], &b = data_.encoders[j + 1];
    const double left =
        HermiteWheelAngle(t, e0, e1, a.left_rad, b.left_rad, forward[j].left, forward[j + 1].left) -
        HermiteWheelAngle(t, e0, e1, a.left_rad, b.left_rad, backward[j].left,
                          backward[j + 1].left);
    const double right = HermiteWheelAngle(t, e0, e1, a.right_rad, b.right_rad, forward[j].right,
                                           forward[j + 1].right) -
                         HermiteWheelAngle(t, e0, e1, a.right_rad, b.right_rad, backward[j].right,
                                           backward[j + 1].right);
    spreads[k] = {kAngleErrorPerSpread * std::abs(left), kAngleErrorPerSpread * std::abs(right), j};
  }
  return spreads;
}

bool LatentTimeProblem::BracketsHold() const {
  for (size_t j = 0; j + 1 < data_.encoders.size(); ++j) {
    if (!(EncoderTime(static_cast<int>(j) + 1) > EncoderTime(static_cast<int>(j)))) return false;
  }
  return Brackets() == state_.bracket;
}

std::vector<Eigen::Vector3d> LatentTimeProblem::Errors() const {
  std::vector<Eigen::Vector3d> errors;
  errors.reserve(interval_functions_.size());
  const Eigen::Matrix3d l_inv = sqrt_information_->inverse();
  for (size_t i = 0; i < interval_functions_.size(); ++i) {
    Eigen::Vector3d r = Eigen::Vector3d::Constant(NAN);
    interval_functions_[i]->Evaluate(IntervalBlocks(i), r.data(), nullptr);
    errors.push_back(l_inv * r);
  }
  return errors;
}

}  // namespace calib
