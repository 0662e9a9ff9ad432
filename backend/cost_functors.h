// Ceres cost functors of the pose graph. Templates live here, and only here
// (style guide): every other back-end file is compiled once.
//
// Parameter blocks: a 2D pose is [x, y, theta]; a 3D pose is
// [tx, ty, tz, qx, qy, qz, qw] on ProductManifold<EuclideanManifold<3>,
// EigenQuaternionManifold>; a switch is [s] bounded to [0, 1].
//
// The error of a relative-pose measurement Z_ij of poses X_i, X_j is g2o's, so
// that 0.5 * sum of squared residuals is half of g2o's chi2:
//   2D:  e = [ R(theta_z)^T (R(theta_i)^T (t_j - t_i) - t_z) ;
//              wrap(theta_j - theta_i - theta_z) ]
//   3D:  D = Z^-1 * X_i^-1 * X_j,  e = [ t_D ; vec(q_D) with w(q_D) >= 0 ]
// and the residual is r = U e with U the upper Cholesky factor of the
// information, Omega = U^T U (not L^T: style guide, ceres-solver #449, #1135).
#ifndef CATGRAPH_BACKEND_COST_FUNCTORS_H_
#define CATGRAPH_BACKEND_COST_FUNCTORS_H_

#include <array>
#include <cmath>
#include <optional>
#include <type_traits>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ceres/ceres.h>

#include "backend/factors.h"
#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"

namespace catgraph {

// theta wrapped to [-pi, pi) in a form automatic differentiation can follow.
template <typename T>
T WrapAngleAutoDiff(const T& angle_rad) {
  const T two_pi(2.0 * M_PI);
  return angle_rad - two_pi * ceres::floor((angle_rad + T(M_PI)) / two_pi);
}

// The unscaled g2o error e of a 2D relative pose (see the file comment).
template <typename T>
Eigen::Matrix<T, 3, 1> RelativePose2Error(const T* pose_i, const T* pose_j, const Pose2& z) {
  const T c = ceres::cos(pose_i[2]), s = ceres::sin(pose_i[2]);
  const T dx = pose_j[0] - pose_i[0], dy = pose_j[1] - pose_i[1];
  // Delta t in frame i, then minus t_z, rotated into the measurement's frame.
  const T lx = c * dx + s * dy - T(z.x());
  const T ly = -s * dx + c * dy - T(z.y());
  const double cz = std::cos(z.theta()), sz = std::sin(z.theta());
  Eigen::Matrix<T, 3, 1> e;
  e << T(cz) * lx + T(sz) * ly, T(-sz) * lx + T(cz) * ly,
      WrapAngleAutoDiff(pose_j[2] - pose_i[2] - T(z.theta()));
  return e;
}

// The unscaled g2o error e of a 3D relative pose.
template <typename T>
Eigen::Matrix<T, 6, 1> RelativePose3Error(const T* pose_i, const T* pose_j, const Pose3& z) {
  const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_i(pose_i), t_j(pose_j);
  const Eigen::Map<const Eigen::Quaternion<T>> q_i(pose_i + 3), q_j(pose_j + 3);
  const Eigen::Quaternion<T> q_z_inv = z.rotation().conjugate().template cast<T>();
  const Eigen::Matrix<T, 3, 1> t_z = z.translation().template cast<T>();
  const Eigen::Quaternion<T> q_i_inv = q_i.conjugate();
  // X_i^-1 X_j, then Z^-1 times it.
  const Eigen::Matrix<T, 3, 1> t_ij = q_i_inv * (t_j - t_i);
  const Eigen::Quaternion<T> q_ij = q_i_inv * q_j;
  Eigen::Quaternion<T> q_d = q_z_inv * q_ij;
  const Eigen::Matrix<T, 3, 1> t_d = q_z_inv * (t_ij - t_z);
  if (q_d.w() < T(0.0)) q_d.coeffs() = -q_d.coeffs();
  Eigen::Matrix<T, 6, 1> e;
  e << t_d, q_d.vec();
  return e;
}

template <typename PoseT>
struct RelativePoseTraits;
template <>
struct RelativePoseTraits<Pose2> {
  static constexpr int kResiduals = 3, kParameters = 3;
  template <typename T>
  static Eigen::Matrix<T, 3, 1> Error(const T* i, const T* j, const Pose2& z) {
    return RelativePose2Error(i, j, z);
  }
};
template <>
struct RelativePoseTraits<Pose3> {
  static constexpr int kResiduals = 6, kParameters = 7;
  template <typename T>
  static Eigen::Matrix<T, 6, 1> Error(const T* i, const T* j, const Pose3& z) {
    return RelativePose3Error(i, j, z);
  }
};

// The residual of a relative-pose measurement, as a policy of the cost
// functors below: `kResiduals` values from the two poses' parameter blocks.
//
// g2o's: r = U e.
template <typename PoseT>
class G2oResidual {
 public:
  static constexpr int kResiduals = RelativePoseTraits<PoseT>::kResiduals;
  static constexpr int kParameters = RelativePoseTraits<PoseT>::kParameters;
  using SqrtInformation = Eigen::Matrix<double, kResiduals, kResiduals>;

  G2oResidual(const PoseT& measurement, const SqrtInformation& sqrt_information)
      : measurement_(measurement), sqrt_information_(sqrt_information) {}

  template <typename T>
  void operator()(const T* pose_i, const T* pose_j, T* residuals) const {
    Eigen::Map<Eigen::Matrix<T, kResiduals, 1>> r(residuals);
    r = sqrt_information_.template cast<T>() *
        RelativePoseTraits<PoseT>::Error(pose_i, pose_j, measurement_);
  }

 private:
  PoseT measurement_;
  SqrtInformation sqrt_information_;
};

// SE-Sync's chordal cost (Rosen et al., IJRR 2019):
//   r = [ sqrt(kappa) vec(R_j - R_i R_z) ; sqrt(tau) (t_j - t_i - R_i t_z) ]
// so that sum |r|^2 is SE-Sync's objective F.
template <typename T>
Eigen::Matrix<T, 2, 2> RotationOfParameters2(const T* pose) {
  const T c = ceres::cos(pose[2]), s = ceres::sin(pose[2]);
  Eigen::Matrix<T, 2, 2> r;
  r << c, -s, s, c;
  return r;
}

template <typename PoseT>
class ChordalResidual {
 public:
  static constexpr int kD = std::is_same_v<PoseT, Pose2> ? 2 : 3;
  static constexpr int kResiduals = kD * kD + kD;
  static constexpr int kParameters = RelativePoseTraits<PoseT>::kParameters;

  ChordalResidual(const PoseT& measurement, const ChordalWeights& weights)
      : measurement_(measurement), weights_(weights) {}

  template <typename T>
  void operator()(const T* pose_i, const T* pose_j, T* residuals) const {
    Eigen::Matrix<T, kD, kD> r_i, r_j;
    Eigen::Matrix<T, kD, 1> t_i, t_j;
    Eigen::Matrix<double, kD, kD> r_z;
    Eigen::Matrix<double, kD, 1> t_z;
    if constexpr (kD == 2) {
      r_i = RotationOfParameters2(pose_i);
      r_j = RotationOfParameters2(pose_j);
      t_i << pose_i[0], pose_i[1];
      t_j << pose_j[0], pose_j[1];
      r_z = measurement_.rotation();
      t_z = measurement_.translation();
    } else {
      r_i = Eigen::Map<const Eigen::Quaternion<T>>(pose_i + 3).toRotationMatrix();
      r_j = Eigen::Map<const Eigen::Quaternion<T>>(pose_j + 3).toRotationMatrix();
      t_i = Eigen::Map<const Eigen::Matrix<T, 3, 1>>(pose_i);
      t_j = Eigen::Map<const Eigen::Matrix<T, 3, 1>>(pose_j);
      r_z = measurement_.rotation().toRotationMatrix();
      t_z = measurement_.translation();
    }
    const Eigen::Matrix<T, kD, kD> dr = r_j - r_i * r_z.template cast<T>();
    const Eigen::Matrix<T, kD, 1> dt = t_j - t_i - r_i * t_z.template cast<T>();
    const T sqrt_kappa(std::sqrt(weights_.kappa)), sqrt_tau(std::sqrt(weights_.tau));
    for (int c = 0; c < kD; ++c) {
      for (int r = 0; r < kD; ++r) residuals[c * kD + r] = sqrt_kappa * dr(r, c);
    }
    for (int k = 0; k < kD; ++k) residuals[kD * kD + k] = sqrt_tau * dt(k);
  }

 private:
  PoseT measurement_;
  ChordalWeights weights_;
};

// A relative-pose constraint: r = the residual (G2oResidual or ChordalResidual).
template <typename Residual>
class RelativePoseCost {
 public:
  static constexpr int kN = Residual::kResiduals;
  static constexpr int kP = Residual::kParameters;

  explicit RelativePoseCost(const Residual& residual) : residual_(residual) {}

  template <typename T>
  bool operator()(const T* pose_i, const T* pose_j, T* residuals) const {
    residual_(pose_i, pose_j, residuals);
    return true;
  }

  static ceres::CostFunction* Create(const Residual& residual) {
    return new ceres::AutoDiffCostFunction<RelativePoseCost, kN, kP, kP>(new RelativePoseCost(residual));
  }

 private:
  Residual residual_;
};

// Switchable constraint (Suenderhauf & Protzel 2012): r = Psi(s) r_0, with
// r_0 the residual, Psi(s) = s (s bounded to [0, 1] by the problem) or the
// sigmoid Psi(s) = 1 / (1 + exp(-s)) (s unbounded). dr/ds = Psi'(s) r_0.
template <typename Residual>
class SwitchableRelativePoseCost {
 public:
  static constexpr int kN = Residual::kResiduals;
  static constexpr int kP = Residual::kParameters;

  SwitchableRelativePoseCost(const Residual& residual, SwitchFunction function)
      : residual_(residual), function_(function) {}

  template <typename T>
  bool operator()(const T* pose_i, const T* pose_j, const T* s, T* residuals) const {
    residual_(pose_i, pose_j, residuals);
    const T scale = Psi(s[0], function_);
    for (int k = 0; k < kN; ++k) residuals[k] *= scale;
    return true;
  }

  static ceres::CostFunction* Create(const Residual& residual, SwitchFunction function) {
    return new ceres::AutoDiffCostFunction<SwitchableRelativePoseCost, kN, kP, kP, 1>(
        new SwitchableRelativePoseCost(residual, function));
  }

 private:
  Residual residual_;
  SwitchFunction function_;
};

// A switchable constraint whose residual is also scaled by other switches
// (the coupled closure hierarchy: a child closure by its parents'):
// r = Psi(s_0) Psi(s_1) ... Psi(s_k) r_0. Parameter blocks: pose i, pose j,
// then the k + 1 switches, own first. The number of switches is known only at
// run time, hence the dynamic cost function.
template <typename Residual>
class CoupledSwitchableRelativePoseCost {
 public:
  static constexpr int kN = Residual::kResiduals;
  static constexpr int kP = Residual::kParameters;

  CoupledSwitchableRelativePoseCost(const Residual& residual, SwitchFunction function, int num_switches)
      : residual_(residual), function_(function), num_switches_(num_switches) {}

  template <typename T>
  bool operator()(T const* const* parameters, T* residuals) const {
    T scale(1.0);
    for (int k = 0; k < num_switches_; ++k) {
      scale *= Psi(parameters[2 + k][0], function_);
    }
    residual_(parameters[0], parameters[1], residuals);
    for (int k = 0; k < kN; ++k) residuals[k] *= scale;
    return true;
  }

  static ceres::CostFunction* Create(const Residual& residual, SwitchFunction function, int num_switches) {
    // Stride 4: a 3D pose block (7) takes two passes, a switch one.
    auto* cost = new ceres::DynamicAutoDiffCostFunction<CoupledSwitchableRelativePoseCost, 4>(
        new CoupledSwitchableRelativePoseCost(residual, function, num_switches));
    cost->AddParameterBlock(kP);
    cost->AddParameterBlock(kP);
    for (int k = 0; k < num_switches; ++k) cost->AddParameterBlock(1);
    cost->SetNumResiduals(kN);
    return cost;
  }

 private:
  Residual residual_;
  SwitchFunction function_;
  int num_switches_;
};

// g2o's 2D residual r = U e with its Jacobians in closed form: what
// RelativePoseCost<G2oResidual<Pose2>> computes by automatic
// differentiation, the same residual to the last bit; Ceres' Jacobian
// evaluation takes half the time with it (BENCHMARKS.md). With l =
// R(theta_i)^T (t_j - t_i), e = [R(theta_z)^T (l - t_z); wrap(theta_j -
// theta_i - theta_z)]:
//   de/dt_i = -de/dt_j = [-R(theta_z)^T R(theta_i)^T; 0],
//   de/dtheta_i = [R(theta_z)^T (l_y, -l_x); -1],  de/dtheta_j = [0; 0; 1].
// With a switch, r = Psi(s) U e, dr/dX = Psi(s) U de/dX, dr/ds = Psi'(s) U e.
class RelativePose2Cost final : public ceres::CostFunction {
 public:
  // No switch: parameter blocks pose i, pose j.
  RelativePose2Cost(const Pose2& measurement, const Eigen::Matrix3d& sqrt_information);
  // Switchable: pose i, pose j, the switch.
  RelativePose2Cost(const Pose2& measurement, const Eigen::Matrix3d& sqrt_information, SwitchFunction function);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  Pose2 measurement_;
  double cos_z_, sin_z_;
  Eigen::Matrix3d sqrt_information_;
  std::optional<SwitchFunction> switch_function_;
};

// Switch prior: r = sqrt(information) (gamma - s).
class SwitchPriorCost {
 public:
  SwitchPriorCost(double mean, double information)
      : mean_(mean), sqrt_information_(std::sqrt(information)) {}

  template <typename T>
  bool operator()(const T* s, T* residual) const {
    residual[0] = T(sqrt_information_) * (T(mean_) - s[0]);
    return true;
  }

  static ceres::CostFunction* Create(double mean, double information) {
    return new ceres::AutoDiffCostFunction<SwitchPriorCost, 1, 1>(
        new SwitchPriorCost(mean, information));
  }

 private:
  double mean_;
  double sqrt_information_;
};

// Pose prior: r = U e(X_prior, X), the relative-pose error with the prior as
// the "from" pose and the identity as measurement.
template <typename PoseT>
class PosePriorCost {
 public:
  static constexpr int kN = RelativePoseTraits<PoseT>::kResiduals;
  static constexpr int kP = RelativePoseTraits<PoseT>::kParameters;
  using SqrtInformation = Eigen::Matrix<double, kN, kN>;

  PosePriorCost(const PoseT& prior, const SqrtInformation& sqrt_information)
      : prior_(prior), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* pose, T* residuals) const {
    T prior[kP];
    const auto values = ToParameters(prior_);
    for (int k = 0; k < kP; ++k) prior[k] = T(values[k]);
    Eigen::Map<Eigen::Matrix<T, kN, 1>> r(residuals);
    r = sqrt_information_.template cast<T>() *
        RelativePoseTraits<PoseT>::Error(prior, pose, PoseT::Identity());
    return true;
  }

  static ceres::CostFunction* Create(const PoseT& prior, const SqrtInformation& sqrt_info) {
    return new ceres::AutoDiffCostFunction<PosePriorCost, kN, kP>(
        new PosePriorCost(prior, sqrt_info));
  }

 private:
  static std::array<double, kP> ToParameters(const Pose2& p) { return {p.x(), p.y(), p.theta()}; }
  static std::array<double, kP> ToParameters(const Pose3& p) {
    const auto& t = p.translation();
    const auto& q = p.rotation();
    return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
  }

  PoseT prior_;
  SqrtInformation sqrt_information_;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_COST_FUNCTORS_H_
