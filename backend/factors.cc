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

RelativePose2Cost::RelativePose2Cost(const Pose2& measurement, const Eigen::Matrix3d& sqrt_information)
    : measurement_(measurement),
      cos_z_(std::cos(measurement.theta())),
      sin_z_(std::sin(measurement.theta())),
      sqrt_information_(sqrt_information) {
  set_num_residuals(3);
  mutable_parameter_block_sizes()->assign({3, 3});
}

RelativePose2Cost::RelativePose2Cost(const Pose2& measurement, const Eigen::Matrix3d& sqrt_information,
                                     SwitchFunction function)
    : RelativePose2Cost(measurement, sqrt_information) {
  switch_function_ = function;
  mutable_parameter_block_sizes()->push_back(1);
}

bool RelativePose2Cost::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const double* pose_i = parameters[0];
  const double* pose_j = parameters[1];
  // The error as RelativePose2Error forms it, operation for operation.
  const double c = std::cos(pose_i[2]), s = std::sin(pose_i[2]);
  const double dx = pose_j[0] - pose_i[0], dy = pose_j[1] - pose_i[1];
  const double lx0 = c * dx + s * dy, ly0 = -s * dx + c * dy;
  const double lx = lx0 - measurement_.x(), ly = ly0 - measurement_.y();
  const Eigen::Vector3d e(cos_z_ * lx + sin_z_ * ly, -sin_z_ * lx + cos_z_ * ly,
                          WrapAngleAutoDiff(pose_j[2] - pose_i[2] - measurement_.theta()));
  double psi = 1.0, dpsi = 0.0;
  if (switch_function_) {
    const double sw = parameters[2][0];
    psi = Psi(sw, *switch_function_);
    dpsi = *switch_function_ == SwitchFunction::kLinear ? 1.0 : psi * (1.0 - psi);
  }
  // U e summed as Eigen sums the automatic differentiation's product, so
  // that both give the same residual to the last bit.
  const Eigen::Matrix3d& u = sqrt_information_;
  Eigen::Vector3d r;
  for (int k = 0; k < 3; ++k) r(k) = u(k, 0) * e(0) + (u(k, 1) * e(1) + u(k, 2) * e(2));
  Eigen::Map<Eigen::Vector3d> residual(residuals);
  residual = psi * r;
  if (jacobians == nullptr) return true;
  using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
  if (jacobians[0] != nullptr || jacobians[1] != nullptr) {
    // de/dt_j: R_z^T R_i^T; its negative and de/dtheta_i for pose i.
    Eigen::Matrix2d rzt_rit;
    rzt_rit << cos_z_ * c - sin_z_ * s, cos_z_ * s + sin_z_ * c,  //
        -sin_z_ * c - cos_z_ * s, -sin_z_ * s + cos_z_ * c;
    Eigen::Matrix3d de_dj = Eigen::Matrix3d::Zero();
    de_dj.topLeftCorner<2, 2>() = rzt_rit;
    de_dj(2, 2) = 1.0;
    if (jacobians[0] != nullptr) {
      Eigen::Matrix3d de_di = -de_dj;
      de_di(0, 2) = cos_z_ * ly0 - sin_z_ * lx0;
      de_di(1, 2) = -sin_z_ * ly0 - cos_z_ * lx0;
      Eigen::Map<RowMajor3> jacobian(jacobians[0]);
      jacobian = psi * (sqrt_information_ * de_di);
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<RowMajor3> jacobian(jacobians[1]);
      jacobian = psi * (sqrt_information_ * de_dj);
    }
  }
  if (switch_function_ && jacobians[2] != nullptr) {
    Eigen::Map<Eigen::Vector3d> jacobian(jacobians[2]);
    jacobian = dpsi * r;
  }
  return true;
}

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
  if constexpr (std::is_same_v<PoseT, Pose2>) {
    if (cost_ == RelativePoseCostType::kG2o) return std::make_unique<RelativePose2Cost>(mean_, sqrt_information_);
  }
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
  if constexpr (std::is_same_v<PoseT, Pose2>) {
    if (cost_ == RelativePoseCostType::kG2o && num_switches == 1) {
      return std::make_unique<RelativePose2Cost>(mean_, sqrt_information_, function_);
    }
  }
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
