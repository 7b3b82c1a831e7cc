#include <calib/solvers/timing/latent_error_covariance.h>

#include <algorithm>

namespace calib {
namespace {

// Row i of a per-interval projection with the latents following: g_i − Σ_l value(l)·X(l).
template <typename Value>
Eigen::VectorXd ProfileRow(const Eigen::MatrixXd& globals, size_t i, const LatentLinearization& lin,
                           const Eigen::MatrixXd& latent_gain, Value value) {
  Eigen::VectorXd v = globals.row(static_cast<Eigen::Index>(i)).transpose();
  for (const LatentLinearization::LatentScore& l : lin.score_latents[i]) {
    if (l.latent >= 0) v -= value(l) * latent_gain.row(l.latent).transpose();
  }
  return v;
}

Status NeedScores(const LatentLinearization& lin, const Eigen::MatrixXd& projection) {
  const size_t rows = lin.interval_sample.size();
  if (lin.score_latents.size() != rows || projection.rows() != static_cast<Eigen::Index>(rows)) {
    return Status::Internal("the errors' covariance needs the intervals' scores (Linearize(true))");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<Eigen::MatrixXd> LatentAngleCovariance(const LatentLinearization& lin,
                                                const LatentCovariance& covariance) {
  const Eigen::Index g = covariance.globals.rows();
  if (lin.sample_angle.empty()) return Eigen::MatrixXd(Eigen::MatrixXd::Zero(g, g));
  CALIB_RETURN_IF_ERROR(NeedScores(lin, lin.angle_globals[0]));
  int segments = 0;
  for (const LatentLinearization::AngleSpread& s : lin.sample_angle) {
    segments = std::max(segments, s.segment + 1);
  }
  // Per segment and wheel, Σ σ·J̃ᵀ·∂r/∂α over its samples' ends.
  Eigen::MatrixXd moved = Eigen::MatrixXd::Zero(g, 2 * segments);
  for (size_t i = 0; i < lin.interval_sample.size(); ++i) {
    for (int w = 0; w < 4; ++w) {
      const LatentLinearization::AngleSpread& s =
          lin.sample_angle[lin.interval_sample[i] + (w >= 2 ? 1 : 0)];
      if (s.segment < 0) continue;
      const auto angle = [w](const LatentLinearization::LatentScore& l) { return l.angle[w]; };
      moved.col(2 * s.segment + w % 2) +=
          (w % 2 == 0 ? s.left_rad : s.right_rad) *
          ProfileRow(lin.angle_globals[w], i, lin, covariance.latent_gain, angle);
    }
  }
  const Eigen::MatrixXd& c = covariance.globals;
  return Eigen::MatrixXd(c * (moved * moved.transpose()) * c);
}

bool NeighbourCorrelation::PoseErrors() const {
  return pairs >= 30 && correlation(0, 0) < -0.25 && correlation(1, 1) < -0.25;
}

NeighbourCorrelation NeighbourErrorCorrelation(const std::vector<Eigen::Vector3d>& errors,
                                               const Eigen::Vector3d& noise_sigma,
                                               const std::vector<int>& interval_start) {
  const auto whitened = [&](size_t k, Eigen::Vector3d* e) {
    *e = errors[k].cwiseQuotient(noise_sigma);
    return e->cwiseAbs().maxCoeff() <= 3.0;
  };
  Eigen::Matrix3d lag0 = Eigen::Matrix3d::Zero(), lag1 = Eigen::Matrix3d::Zero();
  int count = 0;
  NeighbourCorrelation out;
  Eigen::Vector3d a, b;
  for (size_t k = 0; k < errors.size() && k < interval_start.size(); ++k) {
    if (!whitened(k, &a)) continue;
    lag0 += a * a.transpose();
    ++count;
    if (k + 1 < errors.size() && k + 1 < interval_start.size() &&
        interval_start[k + 1] == interval_start[k] + 1 && whitened(k + 1, &b)) {
      lag1 += a * b.transpose();
      ++out.pairs;
    }
  }
  if (count == 0 || out.pairs == 0 || !(lag0.diagonal().minCoeff() > 0.0)) return out;
  const Eigen::Vector3d scale = (lag0.diagonal() / count).cwiseSqrt().cwiseInverse();
  out.correlation = scale.asDiagonal() * (lag1 / out.pairs) * scale.asDiagonal();
  return out;
}

StatusOr<Eigen::MatrixXd> LatentNeighbourCovariance(const LatentLinearization& lin,
                                                    const LatentCovariance& covariance,
                                                    const Eigen::Matrix3d& correlation) {
  const Eigen::Index g = covariance.globals.rows();
  CALIB_RETURN_IF_ERROR(NeedScores(lin, lin.row_globals[0]));
  const size_t rows = lin.interval_sample.size();
  const auto profile = [&](size_t i) {  // J̃_i, 3 × g.
    Eigen::MatrixXd j(3, g);
    for (int c = 0; c < 3; ++c) {
      const auto row = [c](const LatentLinearization::LatentScore& l) { return l.row[c]; };
      j.row(c) = ProfileRow(lin.row_globals[c], i, lin, covariance.latent_gain, row).transpose();
    }
    return j;
  };
  Eigen::MatrixXd cross = Eigen::MatrixXd::Zero(g, g);
  Eigen::MatrixXd previous;
  for (size_t i = 0; i < rows; ++i) {
    Eigen::MatrixXd current = profile(i);
    if (i > 0 && lin.interval_sample[i] == lin.interval_sample[i - 1] + 1) {
      cross += previous.transpose() * correlation * current;
    }
    previous = std::move(current);
  }
  const Eigen::MatrixXd& c = covariance.globals;
  return Eigen::MatrixXd(c * (cross + cross.transpose()) * c);
}

}  // namespace calib
