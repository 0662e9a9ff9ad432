// Every cost functor's Jacobian agrees with finite differences
// (ceres::GradientChecker), and the residuals are scaled by the upper
// Cholesky factor: |r|^2 = e^T Omega e also for non-diagonal information.
#include <memory>
#include <random>
#include <vector>

#include "tests/catch.h"
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>

#include <Eigen/Cholesky>

#include "backend/cost_functors.h"
#include "backend/factors.h"
#include "backend/graph/relative_pose_error.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

using testing::RandomPose2;
using testing::RandomPose3;

// A random symmetric positive-definite matrix with strong off-diagonal terms.
template <int N>
Eigen::Matrix<double, N, N> RandomInformation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix<double, N, N> a;
  for (int r = 0; r < N; ++r) {
    for (int c = 0; c < N; ++c) a(r, c) = n(rng);
  }
  return a.transpose() * a + 0.5 * Eigen::Matrix<double, N, N>::Identity();
}

std::array<double, 3> Block(const Pose2& p) { return {p.x(), p.y(), p.theta()}; }
std::array<double, 7> Block(const Pose3& p) {
  const auto& t = p.translation();
  const auto& q = p.rotation();
  return {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
}

void CheckGradients(const ceres::CostFunction& cost, const std::vector<const ceres::Manifold*>& manifolds,
                    const std::vector<double*>& parameters) {
  ceres::NumericDiffOptions numeric;
  // The checker differentiates by Ridders' method, whose default first step
  // (1% of the value) is far from the local regime of a pose graph.
  numeric.ridders_relative_initial_step_size = 1e-4;
  ceres::GradientChecker checker(&cost, &manifolds, numeric);
  ceres::GradientChecker::ProbeResults results;
  const bool ok = checker.Probe(parameters.data(), 1e-7, &results);
  INFO(results.error_log);
  REQUIRE(ok);
}

TEST_CASE("2D relative-pose functor: Jacobians match finite differences", "[backend][functor]") {
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
    const Pose2 xj = xi * z * Pose2(0.3, -0.2, 0.4);  // heading error far from the +-pi cut
    const Eigen::Matrix3d u = SqrtInformation<3>(RandomInformation<3>(rng));
    std::unique_ptr<ceres::CostFunction> cost(RelativePoseCost<Pose2>::Create(z, u));
    auto bi = Block(xi), bj = Block(xj);
    CheckGradients(*cost, {nullptr, nullptr}, {bi.data(), bj.data()});
  }
}

TEST_CASE("3D relative-pose functor: Jacobians on the quaternion manifold match",
          "[backend][functor]") {
  std::mt19937_64 rng(22);
  ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold> manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 xi = RandomPose3(rng), z = RandomPose3(rng);
    // Near the measurement, where the solver works (|rotation error| < pi).
    const Pose3 xj = xi * z * Pose3(Eigen::Vector3d(0.1, -0.2, 0.05),
                                    Eigen::Quaterniond(1.0, 0.05, -0.1, 0.08));
    const Eigen::Matrix<double, 6, 6> u = SqrtInformation<6>(RandomInformation<6>(rng));
    std::unique_ptr<ceres::CostFunction> cost(RelativePoseCost<Pose3>::Create(z, u));
    auto bi = Block(xi), bj = Block(xj);
    CheckGradients(*cost, {&manifold, &manifold}, {bi.data(), bj.data()});
  }
}

TEST_CASE("the functors' error is the graph layer's RelativePoseError, 2D and 3D",
          "[backend][functor]") {
  std::mt19937_64 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    CAPTURE(trial);
    // Any poses, the heading error across the +-pi cut included.
    const Pose2 xi = RandomPose2(rng), xj = RandomPose2(rng), z = RandomPose2(rng);
    const auto bi = Block(xi), bj = Block(xj);
    const Eigen::Vector3d e2 = RelativePose2Error(bi.data(), bj.data(), z);
    CHECK((e2 - RelativePoseError(xi, xj, z)).norm() < 1e-12);
    const Pose3 pi = RandomPose3(rng), pj = RandomPose3(rng), w = RandomPose3(rng);
    const auto ci = Block(pi), cj = Block(pj);
    const Eigen::Matrix<double, 6, 1> e3 = RelativePose3Error(ci.data(), cj.data(), w);
    CHECK((e3 - RelativePoseError(pi, pj, w)).norm() < 1e-12);
  }
}

TEST_CASE("switchable functors: Jacobians including d/ds match, linear and sigmoid",
          "[backend][functor]") {
  std::mt19937_64 rng(23);
  ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold> manifold;
  for (SwitchFunction f : {SwitchFunction::kLinear, SwitchFunction::kSigmoid}) {
    for (int trial = 0; trial < 10; ++trial) {
      double s = std::uniform_real_distribution<double>(0.1, 0.9)(rng);
      {
        const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
        const Pose2 xj = xi * z * Pose2(-0.2, 0.5, -0.3);
        std::unique_ptr<ceres::CostFunction> cost(SwitchableRelativePoseCost<Pose2>::Create(
            z, SqrtInformation<3>(RandomInformation<3>(rng)), f));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*cost, {nullptr, nullptr, nullptr}, {bi.data(), bj.data(), &s});
      }
      {
        const Pose3 xi = RandomPose3(rng), z = RandomPose3(rng);
        const Pose3 xj = xi * z * Pose3(Eigen::Vector3d(0.3, 0.1, 0.0),
                                        Eigen::Quaterniond(1.0, 0.1, 0.0, -0.1));
        std::unique_ptr<ceres::CostFunction> cost(SwitchableRelativePoseCost<Pose3>::Create(
            z, SqrtInformation<6>(RandomInformation<6>(rng)), f));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*cost, {&manifold, &manifold, nullptr}, {bi.data(), bj.data(), &s});
      }
    }
  }
}

TEST_CASE("coupled switchable functor: Jacobians match, residual is the product of the switches times the plain one",
          "[backend][functor]") {
  std::mt19937_64 rng(26);
  ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold> manifold;
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  for (SwitchFunction f : {SwitchFunction::kLinear, SwitchFunction::kSigmoid}) {
    for (int trial = 0; trial < 5; ++trial) {
      std::array<double, 3> s = {unit(rng), unit(rng), unit(rng)};  // own, two parents
      const double product = Psi(s[0], f) *
                             Psi(s[1], f) *
                             Psi(s[2], f);
      {
        const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
        const Pose2 xj = xi * z * Pose2(-0.2, 0.5, -0.3);
        const Eigen::Matrix3d u = SqrtInformation<3>(RandomInformation<3>(rng));
        std::unique_ptr<ceres::CostFunction> coupled(CoupledSwitchableRelativePoseCost<Pose2>::Create(z, u, f, 3));
        std::unique_ptr<ceres::CostFunction> plain(RelativePoseCost<Pose2>::Create(z, u));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*coupled, {nullptr, nullptr, nullptr, nullptr, nullptr},
                       {bi.data(), bj.data(), &s[0], &s[1], &s[2]});
        Eigen::Vector3d r_coupled, r_plain;
        const double* coupled_params[] = {bi.data(), bj.data(), &s[0], &s[1], &s[2]};
        const double* plain_params[] = {bi.data(), bj.data()};
        REQUIRE(coupled->Evaluate(coupled_params, r_coupled.data(), nullptr));
        REQUIRE(plain->Evaluate(plain_params, r_plain.data(), nullptr));
        CHECK((r_coupled - product * r_plain).norm() < 1e-12 * (1.0 + r_plain.norm()));
      }
      {
        const Pose3 xi = RandomPose3(rng), z = RandomPose3(rng);
        const Pose3 xj = xi * z * Pose3(Eigen::Vector3d(0.3, 0.1, 0.0), Eigen::Quaterniond(1.0, 0.1, 0.0, -0.1));
        std::unique_ptr<ceres::CostFunction> coupled(CoupledSwitchableRelativePoseCost<Pose3>::Create(
            z, SqrtInformation<6>(RandomInformation<6>(rng)), f, 2));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*coupled, {&manifold, &manifold, nullptr, nullptr}, {bi.data(), bj.data(), &s[0], &s[1]});
      }
    }
  }
}

TEST_CASE("switch prior and pose prior functors: Jacobians match", "[backend][functor]") {
  std::mt19937_64 rng(24);
  std::unique_ptr<ceres::CostFunction> prior(SwitchPriorCost::Create(1.0, 4.0));
  double s = 0.3;
  CheckGradients(*prior, {nullptr}, {&s});
  double r = 0.0;
  const double* params[] = {&s};
  prior->Evaluate(params, &r, nullptr);
  CHECK(r == Approx(2.0 * 0.7));  // sqrt(4) (1 - 0.3)

  const Pose2 p2 = RandomPose2(rng), x2 = RandomPose2(rng);
  std::unique_ptr<ceres::CostFunction> c2(
      PosePriorCost<Pose2>::Create(p2, SqrtInformation<3>(RandomInformation<3>(rng))));
  auto b2 = Block(x2);
  CheckGradients(*c2, {nullptr}, {b2.data()});
}

TEST_CASE("residuals are scaled by the upper Cholesky factor of a non-diagonal information",
          "[backend][functor]") {
  std::mt19937_64 rng(25);
  for (int trial = 0; trial < 50; ++trial) {
    const Pose2 xi = RandomPose2(rng), xj = RandomPose2(rng), z = RandomPose2(rng);
    const Eigen::Matrix3d omega = RandomInformation<3>(rng);
    std::unique_ptr<ceres::CostFunction> cost(
        RelativePoseCost<Pose2>::Create(z, SqrtInformation<3>(omega)));
    auto bi = Block(xi), bj = Block(xj);
    const double* params[] = {bi.data(), bj.data()};
    Eigen::Vector3d r;
    cost->Evaluate(params, r.data(), nullptr);
    // g2o's error: Z^-1 X_i^-1 X_j as (x, y, theta).
    const Eigen::Vector3d e = z.Between(xi.Between(xj)).ToVector();
    REQUIRE(r.squaredNorm() == Approx(e.dot(omega * e)).epsilon(1e-9));
    // The lower factor would give a different value for this matrix.
    const Eigen::Vector3d wrong = Eigen::Matrix3d(omega.llt().matrixL()) * e;
    if (std::abs(omega(0, 1)) > 0.1) REQUIRE(wrong.squaredNorm() != Approx(e.dot(omega * e)));
  }
}

}  // namespace
}  // namespace catgraph
