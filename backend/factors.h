// The standard factors of the pose graph. Each documents its error; residuals
// are scaled by the upper Cholesky factor U of the information (U^T U = Omega).
#ifndef CATGRAPH_BACKEND_FACTORS_H_
#define CATGRAPH_BACKEND_FACTORS_H_

#include <cmath>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "backend/factor_graph.h"
#include "backend/graph/pose_graph.h"

namespace catgraph {

// How a switch scales its constraint: Psi(s) = s with s in [0, 1]
// (Vertigo's default), or the sigmoid 1 / (1 + e^-s) with s unbounded.
enum class SwitchFunction { kLinear, kSigmoid };

// Psi(s), for T = double and for Ceres' Jets (their exp is found by ADL).
template <typename T>
T Psi(const T& s, SwitchFunction function) {
  using std::exp;
  return function == SwitchFunction::kLinear ? s : T(1.0) / (T(1.0) + exp(-s));
}

// A robust loss applied to a factor's squared residual norm.
struct RobustLoss {
  enum class Type { kNone, kHuber, kCauchy, kDcs, kScaled };
  Type type = Type::kNone;
  // Huber / Cauchy: the residual norm (in sigmas) where the loss bends.
  // DCS: Phi, the chi2 beyond which the edge is down-weighted.
  // Scaled: the weight w of rho(chi2) = w chi2 (GNC's weighted least squares).
  double scale = 1.0;
};

// The upper Cholesky factor U of `information`. When the whole matrix is
// indefinite but its translation and rotation blocks are positive definite
// (se-sync/cubicle.g2o), the coupling is dropped, as SE-Sync does; otherwise
// throws std::invalid_argument.
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& information);

// SE-Sync's isotropic weights of a measurement (robust-backend-notes.md §3):
// tau = d / trace(Sigma_t); kappa = I_theta_theta (2D) or
// 3 / (2 trace(Sigma_R)) (3D), Sigma the inverses of the information blocks.
struct ChordalWeights {
  double kappa = 1.0;
  double tau = 1.0;
};
template <int N>
ChordalWeights ChordalWeightsOf(const Eigen::Matrix<double, N, N>& information);

// Which error a relative-pose factor minimises.
enum class RelativePoseCostType {
  kG2o,      // g2o's error, weighted by the full information (the default)
  kChordal,  // SE-Sync's chordal cost: kappa |R_j - R_i R_ij|_F^2 + tau |t_j - t_i - R_i t_ij|^2
};

// e = g2o's error of Z^-1 * X_from^-1 * X_to (cost_functors.h), or the
// chordal residual when `cost` says so.
template <typename PoseT>
class BetweenFactor : public Factor {
 public:
  BetweenFactor(PoseId from, PoseId to, const RelativePoseMeasurement<PoseT>& measurement,
                RobustLoss loss = {}, RelativePoseCostType cost = RelativePoseCostType::kG2o);
  std::vector<Key> keys() const override { return {PoseKey(from_), PoseKey(to_)}; }
  std::unique_ptr<ceres::CostFunction> NewCostFunction() const override;
  std::unique_ptr<ceres::LossFunction> NewLossFunction() const override;

 private:
  PoseId from_, to_;
  PoseT mean_;
  Eigen::Matrix<double, PoseT::kTangentDim, PoseT::kTangentDim> sqrt_information_;
  ChordalWeights chordal_weights_;
  RobustLoss loss_;
  RelativePoseCostType cost_;
};

// r = Psi(s) U e (Suenderhauf & Protzel 2012). With coupled switches s_k
// (the switches of the closures this one depends on: its parents in the
// closure hierarchy), r = Psi(s) prod_k Psi(s_k) U e, so that switching a
// parent off switches the child off in the same solve. With the chordal
// cost, the chordal residual takes U e's place.
template <typename PoseT>
class SwitchableBetweenFactor : public Factor {
 public:
  SwitchableBetweenFactor(PoseId from, PoseId to, SwitchId switch_id,
                          const RelativePoseMeasurement<PoseT>& measurement,
                          SwitchFunction function = SwitchFunction::kLinear,
                          std::vector<SwitchId> coupled = {},
                          RelativePoseCostType cost = RelativePoseCostType::kG2o);
  std::vector<Key> keys() const override;
  std::unique_ptr<ceres::CostFunction> NewCostFunction() const override;
  std::vector<ParameterBound> bounds() const override;

 private:
  PoseId from_, to_;
  SwitchId switch_;
  std::vector<SwitchId> coupled_;
  PoseT mean_;
  Eigen::Matrix<double, PoseT::kTangentDim, PoseT::kTangentDim> sqrt_information_;
  ChordalWeights chordal_weights_;
  SwitchFunction function_;
  RelativePoseCostType cost_;
};

// r = sqrt(information) (gamma - s).
class SwitchPriorFactor : public Factor {
 public:
  SwitchPriorFactor(SwitchId id, const SwitchPrior& prior);
  std::vector<Key> keys() const override { return {SwitchKey(id_)}; }
  std::unique_ptr<ceres::CostFunction> NewCostFunction() const override;

 private:
  SwitchId id_;
  SwitchPrior prior_;
};

// r = U e(prior, X): the pose's deviation from `prior`, in the prior's frame.
template <typename PoseT>
class PriorFactor : public Factor {
 public:
  PriorFactor(PoseId id, const PoseT& prior,
              const InformationMatrix<PoseT>& information);
  std::vector<Key> keys() const override { return {PoseKey(id_)}; }
  std::unique_ptr<ceres::CostFunction> NewCostFunction() const override;

 private:
  PoseId id_;
  PoseT prior_;
  Eigen::Matrix<double, PoseT::kTangentDim, PoseT::kTangentDim> sqrt_information_;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_FACTORS_H_
