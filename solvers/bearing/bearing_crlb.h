#ifndef CALIB_SOLVERS_BEARING_BEARING_CRLB_H_
#define CALIB_SOLVERS_BEARING_BEARING_CRLB_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>

// Cramér–Rao bound of the bearing-only calibration for a simulated log.
namespace calib {

struct BearingBound {
  BearingParamMatrix covariance = BearingParamMatrix::Zero();  // φ, ψ, η, δ, ξ.
  BearingParamVector stddev = BearingParamVector::Zero();
  bool has_metric = false;  // meta.json gives an initial distance.
  BearingMetricMatrix metric_covariance = BearingMetricMatrix::Zero();  // φ, ψ, ρ, δR, δL, δB.
  BearingMetricVector metric_stddev = BearingMetricVector::Zero();
};

// The inverse Fisher information of the model the bundle adjustment fits (BearingProblem: bearing
// noise N(0, σβ²) and the encoder noise K²/r·|Δα| per increment, propagated to the relative pose
// between consecutive bearing times), evaluated at the truth — the true calibration and the true
// poses at the bearing times — with the true noise levels; the poses are nuisance parameters.
// The encoder covariances use the log's increments (first order; the noise is far below the
// increments). With an initial distance in meta.json the bound of the metric set follows from
// that of (φ, ψ, η, δ, ξ, D0'), D0 being known exactly.
StatusOr<BearingBound> BearingCramerRaoBound(const BearingLog& log, const BearingSimTruth& truth,
                                             const BearingNoise& noise);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_CRLB_H_
