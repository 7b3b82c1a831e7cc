#include <calib/core/order_statistic.h>
#include <calib/solvers/stats/change_point.h>
#include <calib/solvers/stats/score_test.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

namespace calib {
namespace {

struct Split {
  size_t index = 0;
  double statistic = 0.0;
  double p_value = 1.0;
};

// The CUSUM scan of rows [begin, end).
Split BestSplit(const Eigen::MatrixXd& series, size_t begin, size_t end, double trim,
                size_t min_length) {
  Split best;
  const size_t n = end - begin;
  const Eigen::Index d = series.cols();
  if (n < 2 * std::max<size_t>(min_length, 2)) return best;
  const Eigen::MatrixXd block = series.middleRows(begin, n);
  const Eigen::RowVectorXd mean = block.colwise().mean();
  const Eigen::RowVectorXd variance =
      (block.rowwise() - mean).colwise().squaredNorm() / static_cast<double>(n - 1);
  if (!(variance.array() > 0.0).all()) return best;
  const size_t lo = std::max(min_length, static_cast<size_t>(std::ceil(trim * n)));
  const size_t hi = std::min(n - min_length, static_cast<size_t>(std::floor((1.0 - trim) * n)));
  Eigen::RowVectorXd partial = Eigen::RowVectorXd::Zero(d);
  for (size_t j = 1; j < n; ++j) {
    partial += block.row(j - 1) - mean;  // Σ of the first j centred rows.
    if (j < lo || j > hi) continue;
    const double pi = static_cast<double>(j) / n;
    const double q = (partial.array().square() / variance.array()).sum() / (n * pi * (1.0 - pi));
    if (q > best.statistic) {
      best.statistic = q;
      best.index = begin + j;
    }
  }
  if (best.index > 0) {
    best.p_value = SupChiSquareSurvival(best.statistic, static_cast<int>(d), trim);
  }
  return best;
}

}  // namespace

std::vector<SeriesSegment> SegmentMeans(const Eigen::MatrixXd& series, double alpha,
                                        int max_segments, double trim, size_t min_length) {
  const size_t n = static_cast<size_t>(series.rows());
  std::vector<std::pair<size_t, size_t>> done;
  std::vector<std::pair<size_t, size_t>> open = {{0, n}};
  // Splits the segment with the strongest significant change first.
  while (!open.empty() && static_cast<int>(done.size() + open.size()) < max_segments) {
    double best_p = 1.0;
    size_t best_open = open.size();
    Split best_split;
    for (size_t i = 0; i < open.size(); ++i) {
      const Split split = BestSplit(series, open[i].first, open[i].second, trim, min_length);
      if (split.index > 0 && split.p_value < best_p) {
        best_p = split.p_value;
        best_open = i;
        best_split = split;
      }
    }
    if (best_open == open.size() || best_p >= alpha) break;
    const auto segment = open[best_open];
    open.erase(open.begin() + best_open);
    open.push_back({segment.first, best_split.index});
    open.push_back({best_split.index, segment.second});
  }
  done.insert(done.end(), open.begin(), open.end());
  std::sort(done.begin(), done.end());
  const double total = series.rows() > 0 ? series.col(0).sum() : 0.0;
  std::vector<SeriesSegment> segments;
  for (const auto& [begin, end] : done) {
    if (end <= begin) continue;
    SeriesSegment segment;
    segment.begin = begin;
    segment.end = end;
    segment.mean = series.middleRows(begin, end - begin).colwise().mean().transpose();
    segment.share = total != 0.0 ? series.col(0).segment(begin, end - begin).sum() / total : 0.0;
    segments.push_back(segment);
  }
  return segments;
}

double ConstantMeanPValue(const Eigen::MatrixXd& series, double trim, size_t* split) {
  const Split best = BestSplit(series, 0, static_cast<size_t>(series.rows()), trim, 2);
  if (split != nullptr) *split = best.index;
  return best.p_value;
}

std::vector<size_t> CovariateOrder(const std::vector<double>& covariate) {
  return StableOrder(covariate);
}

BinnedMeans BinByCovariate(const std::vector<double>& covariate, const Eigen::MatrixXd& values,
                           const Eigen::VectorXd& weights, int bins) {
  return BinByCovariate(covariate, CovariateOrder(covariate), values, weights, bins);
}

BinnedMeans BinByCovariate(const std::vector<double>& covariate, const std::vector<size_t>& order,
                           const Eigen::MatrixXd& values, const Eigen::VectorXd& weights,
                           int bins) {
  BinnedMeans result;
  const size_t n = covariate.size();
  const Eigen::Index d = values.cols();
  bins = std::max(1, std::min<int>(bins, static_cast<int>(n / 4)));
  if (n == 0) return result;
  double total = 0.0, explained = 0.0;
  for (size_t k = 0; k < n; ++k) total += weights(k) * values.row(k).squaredNorm();
  for (int b = 0; b < bins; ++b) {
    const size_t begin = n * b / bins, end = n * (b + 1) / bins;
    double sum_w = 0.0, sum_w2 = 0.0, center = 0.0;
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(d);
    for (size_t i = begin; i < end; ++i) {
      const size_t k = order[i];
      sum_w += weights(k);
      sum_w2 += weights(k) * weights(k);
      sum += weights(k) * values.row(k).transpose();
      center += covariate[k];
    }
    if (!(sum_w > 0.0)) continue;
    const Eigen::VectorXd mean = sum / sum_w;
    Eigen::VectorXd scatter = Eigen::VectorXd::Zero(d);
    for (size_t i = begin; i < end; ++i) {
      const size_t k = order[i];
      scatter += (weights(k) * (values.row(k).transpose() - mean)).cwiseAbs2();
    }
    const Eigen::VectorXd standard_error = scatter.cwiseSqrt() / sum_w;
    result.center.push_back(center / (end - begin));
    result.mean.push_back(mean);
    result.standard_error.push_back(standard_error);
    result.count.push_back(end - begin);
    for (Eigen::Index c = 0; c < d; ++c) {
      if (standard_error(c) > 0.0) {
        result.statistic += std::pow(mean(c) / standard_error(c), 2);
        ++result.dof;
      }
    }
    explained += sum_w * mean.squaredNorm();
  }
  result.p_value = ChiSquareSurvival(result.statistic, result.dof);
  result.explained = total > 0.0 ? std::min(1.0, explained / total) : 0.0;
  return result;
}

std::string PValueText(double p) {
  char text[64];
  if (p < 1e-9) return "p < 1e-9";
  std::snprintf(text, sizeof(text), p < 1e-3 ? "p = %.1e" : "p = %.3f", p);
  return text;
}

std::string WindowWords(const MismatchLocation& location) {
  if (location.windows.size() <= 1) return ", throughout the log";
  const auto strongest =
      std::max_element(location.windows.begin(), location.windows.end(),
                       [](const auto& a, const auto& b) { return a.rate < b.rate; });
  char text[96];
  std::snprintf(text, sizeof(text), ", concentrated in t = %.0f–%.0f s", strongest->start_s,
                strongest->end_s);
  return text;
}

}  // namespace calib
