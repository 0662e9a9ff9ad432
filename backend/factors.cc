#include "backend/factors.h"

#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>

#include <Eigen/Cholesky>
#include <ceres/ceres.h>

#include "backend/cost_functors.h"
#include "backend/robust_losses.h"

namespace catgraph {

template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& information) {
  Eigen::LLT<Eigen::Matrix<double, N, N>> llt(information);
  if (llt.info() == Eigen::Success) return llt.matrixU();
  constexpr int kTranslation = N == 3 ? 2 : 3;
  Eigen::Matrix<double, N, N> blocks = Eigen::Matrix<double, N, N>::Zero();
  blocks.template topLeftCorner<kTranslation, kTranslation>() =
      information.template topLeftCorner<kTranslation, kTranslation>();
  blocks.template bottomRightCorner<N - kTranslation, N - kTranslation>() =
      information.template bottomRightCorner<N - kTranslation, N - kTranslation>();
  Eigen::LLT<Eigen::Matrix<double, N, N>> block_llt(blocks);
  if (block_llt.info() != Eigen::Success) {
    throw std::invalid_argument("information matrix is not positive definite");
  }
  return block_llt.matrixU();
}
template Eigen::Matrix<double, 3, 3> SqrtInformation<3>(const Eigen::Matrix<double, 3, 3>&);
template Eigen::Matrix<double, 6, 6> SqrtInformation<6>(const Eigen::Matrix<double, 6, 6>&);

template <int N>
ChordalWeights ChordalWeightsOf(const Eigen::Matrix<double, N, N>& information) {
  constexpr int kD = N == 3 ? 2 : 3;
  const Eigen::Matrix<double, kD, kD> sigma_t =
      information.template topLeftCorner<kD, kD>().inverse();
  const double tau = kD / sigma_t.trace();
  if constexpr (N == 3) {
    return {information(2, 2), tau};
  } else {
    const Eigen::Matrix3d sigma_r = information.template bottomRightCorner<3, 3>().inverse();
    return {3.0 / (2.0 * sigma_r.trace()), tau};
  }
}
template ChordalWeights ChordalWeightsOf<3>(const Eigen::Matrix<double, 3, 3>&);
template ChordalWeights ChordalWeightsOf<6>(const Eigen::Matrix<double, 6, 6>&);

namespace {

// make(residual) with the residual of `cost`: g2o's error scaled by U, or the
// chordal residual.
template <typename PoseT, typename Make>
std::unique_ptr<ceres::CostFunction> NewRelativePoseCost(
    RelativePoseCostType cost, const PoseT& mean,
    const Eigen::Matrix<double, PoseT::kTangentDim, PoseT::kTangentDim>& sqrt_information,
    const ChordalWeights& chordal_weights, const Make& make) {
  if (cost == RelativePoseCostType::kChordal) {
    return std::unique_ptr<ceres::CostFunction>(make(ChordalResidual<PoseT>(mean, chordal_weights)));
  }
  return std::unique_ptr<ceres::CostFunction>(make(G2oResidual<PoseT>(mean, sqrt_information)));
}

}  // namespace

template <typename PoseT>
BetweenFactor<PoseT>::BetweenFactor(PoseId from, PoseId to,
                                    const RelativePoseMeasurement<PoseT>& measurement,
                                    RobustLoss loss, RelativePoseCostType cost)
    : from_(from),
      to_(to),
      mean_(measurement.mean),
      sqrt_information_(SqrtInformation<PoseT::kTangentDim>(measurement.information)),
      chordal_weights_(ChordalWeightsOf<PoseT::kTangentDim>(measurement.information)),
      loss_(loss),
      cost_(cost) {
  if (loss.type != RobustLoss::Type::kNone && !(loss.scale > 0.0)) {
    throw std::invalid_argument("BetweenFactor: robust loss scale must be > 0, got " +
                                std::to_string(loss.scale));
  }
}

template <typename PoseT>
std::unique_ptr<ceres::CostFunction> BetweenFactor<PoseT>::NewCostFunction() const {
  return NewRelativePoseCost(cost_, mean_, sqrt_information_, chordal_weights_, [](const auto& residual) {
    return RelativePoseCost<std::decay_t<decltype(residual)>>::Create(residual);
  });
}

std::unique_ptr<ceres::LossFunction> NewLoss(const RobustLoss& loss) {
  switch (loss.type) {
    case RobustLoss::Type::kNone: return nullptr;
    case RobustLoss::Type::kHuber: return std::make_unique<ceres::HuberLoss>(loss.scale);
    case RobustLoss::Type::kCauchy: return std::make_unique<ceres::CauchyLoss>(loss.scale);
    case RobustLoss::Type::kDcs: return std::make_unique<DcsLoss>(loss.scale);
    case RobustLoss::Type::kScaled:
      return std::make_unique<ceres::ScaledLoss>(nullptr, loss.scale, ceres::TAKE_OWNERSHIP);
  }
  return nullptr;
}

template <typename PoseT>
std::unique_ptr<ceres::LossFunction> BetweenFactor<PoseT>::NewLossFunction() const {
  return NewLoss(loss_);
}

template <typename PoseT>
SwitchableBetweenFactor<PoseT>::SwitchableBetweenFactor(
    PoseId from, PoseId to, SwitchId switch_id, const RelativePoseMeasurement<PoseT>& measurement,
    SwitchFunction function, std::vector<SwitchId> coupled, RelativePoseCostType cost)
    : from_(from),
      to_(to),
      switch_(switch_id),
      coupled_(std::move(coupled)),
      mean_(measurement.mean),
      sqrt_information_(SqrtInformation<PoseT::kTangentDim>(measurement.information)),
      chordal_weights_(ChordalWeightsOf<PoseT::kTangentDim>(measurement.information)),
      function_(function),
      cost_(cost) {
  std::set<SwitchId> seen = {switch_};
  for (const SwitchId s : coupled_) {
    if (!seen.insert(s).second) {
      throw std::invalid_argument("SwitchableBetweenFactor: switch " + std::to_string(s.value()) +
                                  " appears twice among the constraint's switches");
    }
  }
}

template <typename PoseT>
std::vector<Key> SwitchableBetweenFactor<PoseT>::keys() const {
  std::vector<Key> keys = {PoseKey(from_), PoseKey(to_), SwitchKey(switch_)};
  for (const SwitchId s : coupled_) keys.push_back(SwitchKey(s));
  return keys;
}

template <typename PoseT>
std::unique_ptr<ceres::CostFunction> SwitchableBetweenFactor<PoseT>::NewCostFunction() const {
  const int num_switches = static_cast<int>(coupled_.size()) + 1;
  return NewRelativePoseCost(cost_, mean_, sqrt_information_, chordal_weights_, [&](const auto& residual) {
    using Residual = std::decay_t<decltype(residual)>;
    if (num_switches > 1) {
      return CoupledSwitchableRelativePoseCost<Residual>::Create(residual, function_, num_switches);
    }
    return SwitchableRelativePoseCost<Residual>::Create(residual, function_);
  });
}

template <typename PoseT>
std::vector<ParameterBound> SwitchableBetweenFactor<PoseT>::bounds() const {
  if (function_ == SwitchFunction::kSigmoid) return {};
  std::vector<ParameterBound> bounds;
  for (const Key key : keys()) {
    if (key.type == KeyType::kSwitch) bounds.push_back(ParameterBound{key, 0, 0.0, 1.0});
  }
  return bounds;
}

SwitchPriorFactor::SwitchPriorFactor(SwitchId id, const SwitchPrior& prior)
    : id_(id), prior_(prior) {
  if (!(prior.information > 0.0)) {
    throw std::invalid_argument("SwitchPriorFactor: information must be > 0, got " +
                                std::to_string(prior.information));
  }
}

std::unique_ptr<ceres::CostFunction> SwitchPriorFactor::NewCostFunction() const {
  return std::unique_ptr<ceres::CostFunction>(
      SwitchPriorCost::Create(prior_.mean, prior_.information));
}

template <typename PoseT>
PriorFactor<PoseT>::PriorFactor(PoseId id, const PoseT& prior,
                                const InformationMatrix<PoseT>& information)
    : id_(id), prior_(prior), sqrt_information_(SqrtInformation<PoseT::kTangentDim>(information)) {}

template <typename PoseT>
std::unique_ptr<ceres::CostFunction> PriorFactor<PoseT>::NewCostFunction() const {
  return std::unique_ptr<ceres::CostFunction>(
      PosePriorCost<PoseT>::Create(prior_, sqrt_information_));
}

template class BetweenFactor<Pose2>;
template class BetweenFactor<Pose3>;
template class SwitchableBetweenFactor<Pose2>;
template class SwitchableBetweenFactor<Pose3>;
template class PriorFactor<Pose2>;
template class PriorFactor<Pose3>;

}  // namespace catgraph
