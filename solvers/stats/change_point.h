#ifndef CALIB_SOLVERS_STATS_CHANGE_POINT_H_
#define CALIB_SOLVERS_STATS_CHANGE_POINT_H_

#include <Eigen/Core>
#include <cstddef>
#include <string>
#include <vector>

// Where a mismatch lives: change points of a series over time (CUSUM) and the dependence of
// residuals on a covariate (binned means).
namespace calib {

struct SeriesSegment {
  size_t begin = 0;      // First index.
  size_t end = 0;        // One past the last index.
  Eigen::VectorXd mean;  // Per column.
  double share = 0.0;    // Of the series' total (first column), Σ_segment / Σ_all.
};

// Splits the rows of `series` (N × d) into segments of different means by binary segmentation:
// a segment [a, b) splits at the j maximizing the CUSUM statistic
//   Q(j) = Σ_c (S_c(j) − π·S_c(b))² / (σ_c²·n·π(1 − π)),  π = (j − a)/n, n = b − a,
// when P(sup Q > observed) < alpha (SupChiSquareSurvival with d degrees of freedom and the
// trim), at most max_segments segments, none shorter than min_length.
std::vector<SeriesSegment> SegmentMeans(const Eigen::MatrixXd& series, double alpha,
                                        int max_segments, double trim, size_t min_length);

// The p-value of the first split of SegmentMeans (1 when it does not split): is the mean
// constant over time?
double ConstantMeanPValue(const Eigen::MatrixXd& series, double trim, size_t* split = nullptr);

// Rows of `values` (N × d) grouped into `bins` bins of (nearly) equal count by the covariate.
struct BinnedMeans {
  std::vector<double> center;                   // Mean covariate per bin.
  std::vector<Eigen::VectorXd> mean;            // Weighted mean per bin.
  std::vector<Eigen::VectorXd> standard_error;  // Of the mean.
  std::vector<size_t> count;
  // Σ_bins Σ_c z²: the bin means as z-scores, χ² with bins·d degrees of freedom when the values
  // have mean zero and do not depend on the covariate.
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
  // Share of Σ_k w_k‖v_k‖² that the bin means explain.
  double explained = 0.0;
};
BinnedMeans BinByCovariate(const std::vector<double>& covariate, const Eigen::MatrixXd& values,
                           const Eigen::VectorXd& weights, int bins);
// The rows in the covariate's ascending order (ties in row order): the sort BinByCovariate does,
// computed once where one covariate bins several series.
std::vector<size_t> CovariateOrder(const std::vector<double>& covariate);
// BinByCovariate with `order` = CovariateOrder(covariate).
BinnedMeans BinByCovariate(const std::vector<double>& covariate, const std::vector<size_t>& order,
                           const Eigen::MatrixXd& values, const Eigen::VectorXd& weights, int bins);

// Where a finding's mismatch lives.
struct MismatchLocation {
  // The covariate its signal follows best (LaserCovariateNames, BearingCovariateNames).
  std::string covariate;
  double explained = 0.0;  // Share of the signal the covariate's binned means explain.
  struct Window {
    double start_s = 0.0;  // From the log start.
    double end_s = 0.0;
    double share = 0.0;  // Of the score.
    double rate = 0.0;   // Mean score contribution per sample.
  };
  std::vector<Window> windows;  // Time windows of different score rates (one: throughout).
};

// Binned residuals against one covariate, before (baseline) and after (final fit). Channels:
// the unwhitened error components (laser: x, y (m), θ (rad); bearing: β (rad)) and, in a
// finding's profile, one more: the whitened residual along the finding's signal (its score
// density, σ units).
struct CovariateProfile {
  std::string name;
  std::string unit;
  // Per channel: axis label and display scale (empty: the laser's x, y, θ and signal).
  std::vector<std::string> channel_labels;
  std::vector<double> channel_scales;
  std::vector<double> center;
  std::vector<Eigen::VectorXd> before_mean, before_stderr;
  std::vector<Eigen::VectorXd> after_mean, after_stderr;
  double before_statistic = 0.0, after_statistic = 0.0;  // χ² of the bin means (error channels).
  double before_p_value = 1.0, after_p_value = 1.0;
  int dof = 0;
};

// Structure left in the residuals of a fit, whether or not a candidate explains it.
struct ResidualStructure {
  bool found = false;           // Some covariate or the time change point is significant (Holm).
  std::string covariate;        // The most significant covariate ("" when none).
  double p_value = 1.0;         // Its p-value.
  double change_time_s = -1.0;  // A change of the mean residual over time (< 0: none).
  double change_p_value = 1.0;
  std::string statement;
};

// "p < 1e-9", "p = 3.2e-05", "p = 0.214": a p-value for a sentence.
std::string PValueText(double p);

// Where a finding's score concentrates, for its sentence: ", concentrated in t = a–b s" (the
// window of the highest rate) or ", throughout the log".
std::string WindowWords(const MismatchLocation& location);

}  // namespace calib

#endif  // CALIB_SOLVERS_STATS_CHANGE_POINT_H_
