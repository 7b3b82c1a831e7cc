#include <calib/core/timing/banded_ldlt.h>

#include <algorithm>
#include <cmath>

namespace calib {

bool BandedLdlt::Compute(Eigen::MatrixXd band) {
  const Eigen::Index w = band.rows() - 1;
  const Eigen::Index n = band.cols();
  // Right-looking: column j's multipliers update the trailing band.
  for (Eigen::Index j = 0; j < n; ++j) {
    const double d = band(0, j);
    if (!(d > 0.0) || !std::isfinite(d)) return false;
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) {
      const double l = band(a, j) / d;
      for (Eigen::Index b = a; b <= w && j + b < n; ++b) band(b - a, j + a) -= l * band(b, j);
    }
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) band(a, j) /= d;
  }
  factor_ = std::move(band);
  return true;
}

Eigen::MatrixXd BandedLdlt::Solve(const Eigen::MatrixXd& b) const {
  RowMajorMatrix x = b;
  SolveInPlace(&x);
  return x;
}

void BandedLdlt::SolveInPlace(RowMajorMatrix* x) const {
  const Eigen::Index w = bandwidth();
  const Eigen::Index n = size();
  const Eigen::Index m = x->cols();
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* l = &factor_(0, j);
    const double* from = x->row(j).data();
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) {
      double* to = x->row(j + a).data();
      for (Eigen::Index c = 0; c < m; ++c) to[c] -= l[a] * from[c];
    }
  }
  for (Eigen::Index j = 0; j < n; ++j) x->row(j) /= factor_(0, j);
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const double* l = &factor_(0, j);
    double* to = x->row(j).data();
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) {
      const double* from = x->row(j + a).data();
      for (Eigen::Index c = 0; c < m; ++c) to[c] -= l[a] * from[c];
    }
  }
}

void BandedLdlt::SolveInPlace(Eigen::VectorXd* x) const {
  const Eigen::Index w = bandwidth();
  const Eigen::Index n = size();
  double* v = x->data();
  for (Eigen::Index j = 0; j < n; ++j) {
    const double* l = &factor_(0, j);
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) v[j + a] -= l[a] * v[j];
  }
  for (Eigen::Index j = 0; j < n; ++j) v[j] /= factor_(0, j);
  for (Eigen::Index j = n - 1; j >= 0; --j) {
    const double* l = &factor_(0, j);
    for (Eigen::Index a = 1; a <= w && j + a < n; ++a) v[j] -= l[a] * v[j + a];
  }
}

double BandedLdlt::LogDeterminant() const { return factor_.row(0).array().log().sum(); }

Eigen::VectorXd BandedLdlt::InverseDiagonal() const { return InverseBand().row(0).transpose(); }

Eigen::MatrixXd BandedLdlt::InverseBand() const {
  // Z = A⁻¹ inside the band: Z(j, i) = −Σ_a L(i + a, i)·Z(i + a, j) for j in (i, i + w], and
  // Z(i, i) = 1/D_i − Σ_a L(i + a, i)·Z(i + a, i); every Z(i + a, j) lies in the band already.
  // For j = i + d the sum runs over Z(i + a, i + d) = z(d − a, i + a) for a < d and z(a − d, i + d)
  // for a ≥ d, in two loops (no branch per term; the same order of the terms).
  const Eigen::Index w = bandwidth();
  const Eigen::Index n = size();
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(w + 1, n);  // z(d, i) = Z(i + d, i).
  const Eigen::Index rows = w + 1;
  double* zp = z.data();
  for (Eigen::Index i = n - 1; i >= 0; --i) {
    const Eigen::Index reach = std::min(w, n - 1 - i);
    const double* l = &factor_(0, i);
    for (Eigen::Index d = reach; d >= 1; --d) {
      double sum = 0.0;
      for (Eigen::Index a = 1; a < d; ++a) sum += l[a] * zp[(i + a) * rows + (d - a)];
      const double* column = zp + (i + d) * rows;
      for (Eigen::Index a = d; a <= reach; ++a) sum += l[a] * column[a - d];
      zp[i * rows + d] = -sum;
    }
    double sum = 0.0;
    for (Eigen::Index a = 1; a <= reach; ++a) sum += l[a] * zp[i * rows + a];
    zp[i * rows] = 1.0 / l[0] - sum;
  }
  return z;
}

}  // namespace calib
