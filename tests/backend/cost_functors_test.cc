// Every cost functor's Jacobian agrees with finite differences
// (ceres::GradientChecker), and the residuals are scaled by the upper
// Cholesky factor: |r|^2 = e^T Omega e also for non-diagonal information.
// The chordal residual's |r|^2 is SE-Sync's cost, distributed at the truth as
// ChordalCostCdf says.
#include <algorithm>
#include <memory>
#include <type_traits>
#include <random>
#include <vector>

#include "tests/catch.h"
#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>

#include <Eigen/Cholesky>

#include "backend/chi_square.h"
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
  if (checker.Probe(parameters.data(), 1e-7, &results)) return;
  // The checker's test is relative only, and fails entries that are zero
  // analytically and 1e-13 numerically (the chordal residual's rotation
  // blocks); allow an absolute error far below any entry that matters.
  INFO(results.error_log);
  for (std::size_t block = 0; block < results.local_jacobians.size(); ++block) {
    const Eigen::MatrixXd& user = results.local_jacobians[block];
    const Eigen::MatrixXd& finite = results.local_numeric_jacobians[block];
    const double scale = 1.0 + std::max(user.cwiseAbs().maxCoeff(), finite.cwiseAbs().maxCoeff());
    for (Eigen::Index i = 0; i < user.size(); ++i) {
      const double a = user.data()[i], b = finite.data()[i];
      REQUIRE(std::abs(a - b) <= 1e-7 * std::max(std::abs(a), std::abs(b)) + 1e-10 * scale);
    }
  }
}

TEST_CASE("2D relative-pose functor: Jacobians match finite differences", "[backend][functor]") {
  std::mt19937_64 rng(21);
  for (int trial = 0; trial < 20; ++trial) {
    const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
    const Pose2 xj = xi * z * Pose2(0.3, -0.2, 0.4);  // heading error far from the +-pi cut
    const Eigen::Matrix3d u = SqrtInformation<3>(RandomInformation<3>(rng));
    std::unique_ptr<ceres::CostFunction> cost(RelativePoseCost<G2oResidual<Pose2>>::Create({z, u}));
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
    std::unique_ptr<ceres::CostFunction> cost(RelativePoseCost<G2oResidual<Pose3>>::Create({z, u}));
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
        std::unique_ptr<ceres::CostFunction> cost(SwitchableRelativePoseCost<G2oResidual<Pose2>>::Create(
            {z, SqrtInformation<3>(RandomInformation<3>(rng))}, f));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*cost, {nullptr, nullptr, nullptr}, {bi.data(), bj.data(), &s});
      }
      {
        const Pose3 xi = RandomPose3(rng), z = RandomPose3(rng);
        const Pose3 xj = xi * z * Pose3(Eigen::Vector3d(0.3, 0.1, 0.0),
                                        Eigen::Quaterniond(1.0, 0.1, 0.0, -0.1));
        std::unique_ptr<ceres::CostFunction> cost(SwitchableRelativePoseCost<G2oResidual<Pose3>>::Create(
            {z, SqrtInformation<6>(RandomInformation<6>(rng))}, f));
        auto bi = Block(xi), bj = Block(xj);
        CheckGradients(*cost, {&manifold, &manifold, nullptr}, {bi.data(), bj.data(), &s});
      }
    }
  }
}

// The closed-form 2D cost against the automatic differentiation it replaces:
// the same residuals bit for bit (the same operations), Jacobians to
// rounding; any poses (the heading error across the +-pi cut included),
// without a switch and with each switch function, the switch at its bounds.
TEST_CASE("closed-form 2D cost: residuals and Jacobians equal the autodiff functors'", "[backend][functor]") {
  std::mt19937_64 rng(24);
  const auto same = [](const ceres::CostFunction& closed, const ceres::CostFunction& autodiff,
                       std::vector<double*> parameters) {
    const std::size_t blocks = parameters.size();
    REQUIRE(closed.parameter_block_sizes() == autodiff.parameter_block_sizes());
    REQUIRE(closed.num_residuals() == 3);
    double r_closed[3], r_autodiff[3], r_only[3];
    std::vector<std::vector<double>> j_closed(blocks), j_autodiff(blocks);
    std::vector<double*> jc, ja;
    for (std::size_t b = 0; b < blocks; ++b) {
      j_closed[b].assign(3 * closed.parameter_block_sizes()[b], 0.0);
      j_autodiff[b].assign(3 * closed.parameter_block_sizes()[b], 0.0);
      jc.push_back(j_closed[b].data());
      ja.push_back(j_autodiff[b].data());
    }
    REQUIRE(closed.Evaluate(parameters.data(), r_closed, jc.data()));
    REQUIRE(autodiff.Evaluate(parameters.data(), r_autodiff, ja.data()));
    REQUIRE(closed.Evaluate(parameters.data(), r_only, nullptr));
    for (int k = 0; k < 3; ++k) {
      CHECK(r_closed[k] == r_autodiff[k]);
      CHECK(r_only[k] == r_closed[k]);
    }
    for (std::size_t b = 0; b < blocks; ++b) {
      for (std::size_t k = 0; k < j_closed[b].size(); ++k) {
        CAPTURE(b, k);
        CHECK(std::abs(j_closed[b][k] - j_autodiff[b][k]) <= 1e-12 * (1.0 + std::abs(j_autodiff[b][k])));
      }
    }
    // A block Ceres holds constant gets no Jacobian.
    jc[0] = nullptr;
    REQUIRE(closed.Evaluate(parameters.data(), r_closed, jc.data()));
  };
  for (int trial = 0; trial < 50; ++trial) {
    CAPTURE(trial);
    const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
    const Pose2 xj = trial % 2 == 0 ? RandomPose2(rng) : xi * z * Pose2(0.3, -0.2, 0.4);
    const Eigen::Matrix3d u = SqrtInformation<3>(RandomInformation<3>(rng));
    auto bi = Block(xi), bj = Block(xj);
    {
      const RelativePose2Cost closed(z, u);
      std::unique_ptr<ceres::CostFunction> autodiff(RelativePoseCost<G2oResidual<Pose2>>::Create({z, u}));
      same(closed, *autodiff, {bi.data(), bj.data()});
    }
    for (SwitchFunction f : {SwitchFunction::kLinear, SwitchFunction::kSigmoid}) {
      const double from_range = std::uniform_real_distribution<double>(-3.0, 3.0)(rng);
      for (double s : {0.0, 1.0, f == SwitchFunction::kLinear ? std::abs(from_range) / 3.0 : from_range}) {
        CAPTURE(static_cast<int>(f), s);
        const RelativePose2Cost closed(z, u, f);
        std::unique_ptr<ceres::CostFunction> autodiff(
            SwitchableRelativePoseCost<G2oResidual<Pose2>>::Create({z, u}, f));
        same(closed, *autodiff, {bi.data(), bj.data(), &s});
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
        std::unique_ptr<ceres::CostFunction> coupled(
            CoupledSwitchableRelativePoseCost<G2oResidual<Pose2>>::Create({z, u}, f, 3));
        std::unique_ptr<ceres::CostFunction> plain(RelativePoseCost<G2oResidual<Pose2>>::Create({z, u}));
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
        std::unique_ptr<ceres::CostFunction> coupled(
            CoupledSwitchableRelativePoseCost<G2oResidual<Pose3>>::Create(
                {z, SqrtInformation<6>(RandomInformation<6>(rng))}, f, 2));
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
        RelativePoseCost<G2oResidual<Pose2>>::Create({z, SqrtInformation<3>(omega)}));
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

// SE-Sync's chordal cost of one measurement, written out.
template <typename PoseT>
double ChordalCostOf(const PoseT& xi, const PoseT& xj, const PoseT& z, const ChordalWeights& w) {
  auto rotation = [](const PoseT& p) {
    if constexpr (std::is_same_v<PoseT, Pose2>) {
      return Eigen::Matrix2d(p.rotation());
    } else {
      return Eigen::Matrix3d(p.rotation().toRotationMatrix());
    }
  };
  return w.kappa * (rotation(xj) - rotation(xi) * rotation(z)).squaredNorm() +
         w.tau * (xj.translation() - xi.translation() - rotation(xi) * z.translation()).squaredNorm();
}

TEST_CASE("chordal functors: Jacobians match, |r|^2 is SE-Sync's cost, times the switches' product",
          "[backend][functor][chordal]") {
  std::mt19937_64 rng(27);
  ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold> manifold;
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  for (int trial = 0; trial < 10; ++trial) {
    std::array<double, 2> s = {unit(rng), unit(rng)};
    {
      const Pose2 xi = RandomPose2(rng), z = RandomPose2(rng);
      const Pose2 xj = xi * z * Pose2(-0.2, 0.5, -0.3);
      const ChordalWeights w = ChordalWeightsOf<3>(RandomInformation<3>(rng));
      const ChordalResidual<Pose2> residual(z, w);
      std::unique_ptr<ceres::CostFunction> plain(RelativePoseCost<ChordalResidual<Pose2>>::Create(residual));
      std::unique_ptr<ceres::CostFunction> switched(
          SwitchableRelativePoseCost<ChordalResidual<Pose2>>::Create(residual, SwitchFunction::kLinear));
      std::unique_ptr<ceres::CostFunction> coupled(
          CoupledSwitchableRelativePoseCost<ChordalResidual<Pose2>>::Create(residual, SwitchFunction::kLinear,
                                                                            2));
      auto bi = Block(xi), bj = Block(xj);
      CheckGradients(*plain, {nullptr, nullptr}, {bi.data(), bj.data()});
      CheckGradients(*switched, {nullptr, nullptr, nullptr}, {bi.data(), bj.data(), &s[0]});
      CheckGradients(*coupled, {nullptr, nullptr, nullptr, nullptr}, {bi.data(), bj.data(), &s[0], &s[1]});
      Eigen::Matrix<double, 6, 1> r_plain, r_switched, r_coupled;
      const double* plain_params[] = {bi.data(), bj.data()};
      const double* switched_params[] = {bi.data(), bj.data(), &s[0]};
      const double* coupled_params[] = {bi.data(), bj.data(), &s[0], &s[1]};
      REQUIRE(plain->Evaluate(plain_params, r_plain.data(), nullptr));
      REQUIRE(switched->Evaluate(switched_params, r_switched.data(), nullptr));
      REQUIRE(coupled->Evaluate(coupled_params, r_coupled.data(), nullptr));
      const double f = ChordalCostOf(xi, xj, z, w);
      CHECK(r_plain.squaredNorm() == Approx(f).epsilon(1e-12));
      CHECK(r_switched.squaredNorm() == Approx(s[0] * s[0] * f).epsilon(1e-12));
      CHECK(r_coupled.squaredNorm() == Approx(s[0] * s[0] * s[1] * s[1] * f).epsilon(1e-12));
    }
    {
      const Pose3 xi = RandomPose3(rng), z = RandomPose3(rng);
      const Pose3 xj =
          xi * z * Pose3(Eigen::Vector3d(0.3, 0.1, 0.0), Eigen::Quaterniond(1.0, 0.1, 0.0, -0.1));
      const ChordalWeights w = ChordalWeightsOf<6>(RandomInformation<6>(rng));
      const ChordalResidual<Pose3> residual(z, w);
      std::unique_ptr<ceres::CostFunction> plain(RelativePoseCost<ChordalResidual<Pose3>>::Create(residual));
      std::unique_ptr<ceres::CostFunction> switched(
          SwitchableRelativePoseCost<ChordalResidual<Pose3>>::Create(residual, SwitchFunction::kSigmoid));
      auto bi = Block(xi), bj = Block(xj);
      CheckGradients(*plain, {&manifold, &manifold}, {bi.data(), bj.data()});
      CheckGradients(*switched, {&manifold, &manifold, nullptr}, {bi.data(), bj.data(), &s[0]});
      Eigen::Matrix<double, 12, 1> r;
      const double* params[] = {bi.data(), bj.data()};
      REQUIRE(plain->Evaluate(params, r.data(), nullptr));
      CHECK(r.squaredNorm() == Approx(ChordalCostOf(xi, xj, z, w)).epsilon(1e-12));
    }
  }
}

// The fraction of `costs` at most ChordalCostQuantile(dimension, p) is p
// within 4 binomial sigmas; the chi2(dof) quantile the gate used to be is
// not (it falls short by far more).
void CheckChordalCostQuantiles(std::vector<double> costs, int dimension, int dof) {
  std::sort(costs.begin(), costs.end());
  const double n = static_cast<double>(costs.size());
  auto fraction_below = [&](double x) {
    return static_cast<double>(std::upper_bound(costs.begin(), costs.end(), x) - costs.begin()) / n;
  };
  for (const double p : {0.5, 0.9, 0.99, 0.999}) {
    INFO("dimension " << dimension << ", p " << p);
    const double tolerance = 4.0 * std::sqrt(p * (1.0 - p) / n);
    CHECK(std::abs(fraction_below(ChordalCostQuantile(dimension, p)) - p) < tolerance);
  }
  CHECK(fraction_below(ChiSquareQuantile(dof, 0.99)) < 0.99 - 0.01);
}

TEST_CASE("at the truth, the chordal cost under g2o's Gaussian noise follows ChordalCostCdf",
          "[backend][functor][chordal]") {
  std::mt19937_64 rng(28);
  std::normal_distribution<double> normal(0.0, 1.0);
  constexpr int kSamples = 40000;
  {
    const double sigma_t = 0.1, sigma_theta = 0.02;
    Eigen::Matrix3d information = Eigen::Vector3d(1.0 / (sigma_t * sigma_t), 1.0 / (sigma_t * sigma_t),
                                                  1.0 / (sigma_theta * sigma_theta)).asDiagonal();
    const ChordalWeights w = ChordalWeightsOf<3>(information);
    std::vector<double> costs;
    for (int k = 0; k < kSamples; ++k) {
      const Pose2 xi = RandomPose2(rng), xj = RandomPose2(rng);
      // g2o's error of z at the truth, Z^-1 X_i^-1 X_j, is the noise n.
      const Pose2 n(sigma_t * normal(rng), sigma_t * normal(rng), sigma_theta * normal(rng));
      const Pose2 z = xi.Between(xj) * n.Inverse();
      REQUIRE((RelativePoseError(xi, xj, z) - n.ToVector()).norm() < 1e-9);
      costs.push_back(ChordalCostOf(xi, xj, z, w));
    }
    CheckChordalCostQuantiles(costs, 2, 3);
  }
  {
    const double sigma_t = 0.1, sigma_q = 0.01;  // sigma_q: of the quaternion's vector part
    Eigen::Matrix<double, 6, 1> diagonal;
    diagonal << Eigen::Vector3d::Constant(1.0 / (sigma_t * sigma_t)),
        Eigen::Vector3d::Constant(1.0 / (sigma_q * sigma_q));
    const ChordalWeights w = ChordalWeightsOf<6>(Eigen::Matrix<double, 6, 6>(diagonal.asDiagonal()));
    std::vector<double> costs;
    for (int k = 0; k < kSamples; ++k) {
      const Pose3 xi = RandomPose3(rng), xj = RandomPose3(rng);
      const Eigen::Vector3d t(sigma_t * normal(rng), sigma_t * normal(rng), sigma_t * normal(rng));
      const Eigen::Vector3d v(sigma_q * normal(rng), sigma_q * normal(rng), sigma_q * normal(rng));
      const Pose3 n(t, Eigen::Quaterniond(std::sqrt(1.0 - v.squaredNorm()), v.x(), v.y(), v.z()));
      const Pose3 z = xi.Between(xj) * n.Inverse();
      Eigen::Matrix<double, 6, 1> e;
      e << t, v;
      REQUIRE((RelativePoseError(xi, xj, z) - e).norm() < 1e-9);
      costs.push_back(ChordalCostOf(xi, xj, z, w));
    }
    CheckChordalCostQuantiles(costs, 3, 6);
  }
}

}  // namespace
}  // namespace catgraph
