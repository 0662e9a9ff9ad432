#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "tests/catch.h"

#include "backend/chi_square.h"
#include "backend/factor_graph.h"
#include "backend/factors.h"
#include "backend/initialization.h"
#include "backend/io/graph_io.h"
#include "backend/optimizer.h"
#include "backend/pose_graph_optimizer.h"
#include "backend/robust_losses.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// A simulated Manhattan world with `count` false closures injected by
// `policy`; the ids of the injected ones.
struct SpoiledWorld {
  SimulatedPoseGraph2 sim;
  std::set<ClosureId> injected;
};
SpoiledWorld SpoiledManhattanWorld(int poses, std::uint64_t world_seed, int count,
                                   std::uint64_t outlier_seed, OutlierPolicy policy = OutlierPolicy::kRandom) {
  ManhattanWorldOptions world;
  world.num_poses = poses;
  world.seed = world_seed;
  SpoiledWorld out{SimulateManhattanWorld(world), {}};
  OutlierOptions outliers;
  outliers.count = count;
  outliers.seed = outlier_seed;
  outliers.policy = policy;
  for (const InjectedClosure& c : InjectOutliers(out.sim.graph, outliers)) out.injected.insert(c.id);
  return out;
}

// The largest distance between a pose's positions in two solutions.
double LargestPositionDifference(const AnyPoseGraph& a, const AnyPoseGraph& b) {
  const auto& got = std::get<PoseGraph2>(a).vertices;
  double largest_m = 0.0;
  for (const auto& [id, v] : std::get<PoseGraph2>(b).vertices) {
    largest_m = std::max(largest_m, (Eigen::Vector2d(v.pose->x(), v.pose->y()) -
                                     Eigen::Vector2d(got.at(id).pose->x(), got.at(id).pose->y()))
                                        .norm());
  }
  return largest_m;
}

TEST_CASE("chi-square quantiles match the tables", "[backend][chi2]") {
  CHECK(ChiSquareQuantile(3, 0.99) == Approx(11.3449).epsilon(1e-5));
  CHECK(ChiSquareQuantile(3, 0.999) == Approx(16.2662).epsilon(1e-5));
  CHECK(ChiSquareQuantile(6, 0.99) == Approx(16.8119).epsilon(1e-5));
  CHECK(ChiSquareQuantile(6, 0.999) == Approx(22.4577).epsilon(1e-5));
  CHECK(ChiSquareQuantile(2, 0.5) == Approx(2.0 * std::log(2.0)).epsilon(1e-9));
  CHECK_THROWS_AS(ChiSquareQuantile(3, 1.0), std::invalid_argument);
}

TEST_CASE("the cdf of A + c B, A and B chi-square, is analytic where it can be",
          "[backend][chi2][chordal]") {
  for (const double x : {0.3, 2.0, 7.5, 20.0, 60.0}) {
    INFO("x " << x);
    // c = 1: chi2(a + b).
    CHECK(ChiSquareSumCdf(2, 1, 1.0, x) == Approx(ChiSquareCdf(3, x)).margin(1e-10));
    CHECK(ChiSquareSumCdf(3, 3, 1.0, x) == Approx(ChiSquareCdf(6, x)).margin(1e-10));
    // Two exponentials of rates 1/2 and 1/(2c) (chi2(2) and c chi2(2)): the
    // hypoexponential 1 - (l2 e^(-l1 x) - l1 e^(-l2 x)) / (l2 - l1).
    const double l1 = 0.5, l2 = 1.0 / 8.0;  // c = 4
    const double expected = 1.0 - (l2 * std::exp(-l1 * x) - l1 * std::exp(-l2 * x)) / (l2 - l1);
    CHECK(ChiSquareSumCdf(2, 2, 4.0, x) == Approx(expected).margin(1e-10));
  }
  CHECK(ChiSquareSumCdf(2, 1, 2.0, 0.0) == 0.0);
  // The chordal gates: past the chi2 gate of the same dimension, and
  // ChordalCostCdf inverts them.
  for (const int dimension : {2, 3}) {
    const double gate = ChordalCostQuantile(dimension, 0.999);
    CHECK(ChordalCostCdf(dimension, gate) == Approx(0.999).margin(1e-9));
    CHECK(gate > ChiSquareQuantile(dimension == 2 ? 3 : 6, 0.999));
  }
  CHECK_THROWS_AS(ChordalCostQuantile(4, 0.5), std::invalid_argument);
  CHECK_THROWS_AS(ChiSquareSumCdf(2, 1, 0.0, 1.0), std::invalid_argument);
}

TEST_CASE("the DCS loss is continuous, its derivative is DCS's squared weight", "[backend][dcs]") {
  const double phi = 2.5;
  DcsLoss loss(phi);
  for (double x : {0.1, 1.0, 2.4, 2.5, 2.6, 10.0, 100.0, 1e4}) {
    double rho[3], lo[3], hi[3];
    const double h = 1e-6 * std::max(1.0, x);
    loss.Evaluate(x, rho);
    loss.Evaluate(x - h, lo);
    loss.Evaluate(x + h, hi);
    CHECK(rho[1] == Approx((hi[0] - lo[0]) / (2.0 * h)).epsilon(1e-5));
    CHECK(rho[1] == Approx(DcsLoss::SquaredWeight(phi, x)));
    CHECK(rho[1] > 0.0);
    CHECK(rho[0] <= 3.0 * phi + 1e-12);
    if (x != phi) CHECK(rho[2] == Approx((hi[1] - lo[1]) / (2.0 * h)).epsilon(1e-4).margin(1e-12));
  }
}

// Four poses around a 2 m square, exact measurements with `information`,
// pose k started at truth[k] * Pose2(k * step), pose 0 held constant.
struct SquareLoop {
  std::vector<Pose2> truth = {{0, 0, 0}, {2, 0, M_PI / 2}, {2, 2, M_PI}, {0, 2, -M_PI / 2}};
  Values initial;
  FactorGraph graph;
  RelativePoseMeasurement<Pose2> z;
};
SquareLoop MakeSquareLoop(const Eigen::Vector3d& step, const Eigen::Matrix3d& information) {
  SquareLoop loop;
  loop.z.information = information;
  for (int k = 0; k < 4; ++k) {
    loop.initial.Insert(PoseId(k), loop.truth[k] * Pose2(k * step.x(), k * step.y(), k * step.z()));
    loop.z.mean = loop.truth[k].Between(loop.truth[(k + 1) % 4]);
    loop.graph.Emplace<BetweenFactor<Pose2>>(PoseId(k), PoseId((k + 1) % 4), loop.z);
  }
  loop.graph.SetConstant(PoseKey(PoseId(0)));
  return loop;
}

TEST_CASE("a factor graph built in code solves a square loop exactly", "[backend][api]") {
  Eigen::Matrix3d information;
  information << 10, 2, 0, 2, 10, 1, 0, 1, 50;
  const auto [truth, initial, graph, z] = MakeSquareLoop({0.2, -0.1, 0.1}, information);
  const OptimizationResult result = Optimize(graph, initial);
  REQUIRE(result.summary.IsUsable());
  CHECK(result.summary.final_cost < 1e-12);
  for (int k = 0; k < 4; ++k) {
    CHECK(testing::ApproxEqual(result.values.AtPose2(PoseId(k)), truth[k], 1e-6));
  }
  CHECK_THROWS_AS(initial.AtPose3(PoseId(0)), std::invalid_argument);
  CHECK_THROWS_AS(initial.AtSwitch(SwitchId(0)), std::out_of_range);
  FactorGraph dangling;
  dangling.Emplace<BetweenFactor<Pose2>>(PoseId(0), PoseId(9), z);
  CHECK_THROWS_AS(Optimize(dangling, initial), std::invalid_argument);
}

// OptimizerOptions::stop_test: called after each iteration that lowered the
// cost, on the current values; returning true ends the solve as converged.
TEST_CASE("a caller's stop test ends the solve where it says, with the values it saw",
          "[backend][api]") {
  const SquareLoop loop = MakeSquareLoop({0.3, -0.2, 0.2}, Eigen::Matrix3d::Identity());
  const Values& initial = loop.initial;
  const FactorGraph& graph = loop.graph;
  const OptimizationResult full = Optimize(graph, initial);
  REQUIRE(full.summary.iterations >= 3);
  OptimizerOptions options;
  int calls = 0;
  Pose2 seen;
  std::vector<double> decreases;
  options.stop_test = [&](const Values& values, double relative_decrease) {
    seen = values.AtPose2(PoseId(2));
    decreases.push_back(relative_decrease);
    return ++calls == 2;
  };
  const OptimizationResult stopped = Optimize(graph, initial, options);
  CHECK(calls == 2);
  CHECK(stopped.summary.stopped_by_test);
  CHECK(stopped.summary.termination == Termination::kConverged);
  CHECK(stopped.summary.iterations == 2);
  CHECK(stopped.summary.final_cost > full.summary.final_cost);
  // The test saw the iterate the solve returned, not the initial values.
  CHECK(testing::ApproxEqual(stopped.values.AtPose2(PoseId(2)), seen, 1e-12));
  CHECK_FALSE(testing::ApproxEqual(initial.AtPose2(PoseId(2)), seen, 1e-3));
  for (const double d : decreases) CHECK((d > 0.0 && std::isfinite(d)));
  CHECK_FALSE(full.summary.stopped_by_test);
}

TEST_CASE("an incremental optimizer grows a graph and solves it as Optimize solves the whole", "[backend][api]") {
  Eigen::Matrix3d information;
  information << 10, 2, 0, 2, 10, 1, 0, 1, 50;
  const SquareLoop loop = MakeSquareLoop({0.2, -0.1, 0.1}, information);
  auto odometry = [&](int k) {
    return RelativePoseMeasurement<Pose2>{loop.truth[k - 1].Between(loop.truth[k]), information};
  };
  IncrementalOptimizer optimizer;
  // The square's poses and odometry one by one, each solve from where the
  // last one ended.
  optimizer.Insert(PoseId(0), loop.initial.AtPose2(PoseId(0)));
  optimizer.SetConstant(PoseKey(PoseId(0)));
  for (int k = 1; k < 4; ++k) {
    optimizer.Insert(PoseId(k), loop.initial.AtPose2(PoseId(k)));
    optimizer.Add(std::make_unique<BetweenFactor<Pose2>>(PoseId(k - 1), PoseId(k), odometry(k)));
    REQUIRE(optimizer.Solve().IsUsable());
  }
  // Odometry alone: the poses follow it exactly from the held pose.
  for (int k = 1; k < 4; ++k) CHECK(testing::ApproxEqual(optimizer.values().AtPose2(PoseId(k)), loop.truth[k], 1e-6));
  // A closing edge that disagrees: the whole loop's least squares, as
  // Optimize finds it from scratch.
  const RelativePoseMeasurement<Pose2> closing{Pose2(0.3, 0.1, 0.05) * loop.truth[3].Between(loop.truth[0]),
                                               information};
  const auto closure = optimizer.Add(std::make_unique<BetweenFactor<Pose2>>(PoseId(3), PoseId(0), closing));
  CHECK(optimizer.num_factors() == 4);
  REQUIRE(optimizer.Solve().IsUsable());
  FactorGraph whole;
  for (int k = 1; k < 4; ++k) whole.Emplace<BetweenFactor<Pose2>>(PoseId(k - 1), PoseId(k), odometry(k));
  whole.Emplace<BetweenFactor<Pose2>>(PoseId(3), PoseId(0), closing);
  whole.SetConstant(PoseKey(PoseId(0)));
  const OptimizationResult reference = Optimize(whole, loop.initial);
  for (int k = 0; k < 4; ++k) {
    CHECK(testing::ApproxEqual(optimizer.values().AtPose2(PoseId(k)), reference.values.AtPose2(PoseId(k)), 1e-6));
  }
  CHECK_FALSE(testing::ApproxEqual(optimizer.values().AtPose2(PoseId(3)), loop.truth[3], 1e-3));
  // The closure removed and pose 2 held: pose 2 stays, pose 3 follows its
  // odometry from it.
  optimizer.Remove(closure);
  optimizer.SetConstant(PoseKey(PoseId(2)));
  const Pose2 held = optimizer.values().AtPose2(PoseId(2));
  REQUIRE(optimizer.Solve().IsUsable());
  CHECK(testing::ApproxEqual(optimizer.values().AtPose2(PoseId(2)), held, 1e-12));
  CHECK(testing::ApproxEqual(optimizer.values().AtPose2(PoseId(3)), held * odometry(3).mean, 1e-6));
  // A switch set between solves; mistakes refused.
  optimizer.Insert(SwitchId(7), 1.0);
  optimizer.Set(SwitchId(7), 0.25);
  CHECK(optimizer.values().AtSwitch(SwitchId(7)) == 0.25);
  CHECK_THROWS_AS(optimizer.Insert(PoseId(1), Pose2()), std::invalid_argument);
  CHECK_THROWS_AS(optimizer.Set(SwitchId(8), 1.0), std::out_of_range);
  CHECK_THROWS_AS(optimizer.Remove(closure), std::invalid_argument);
  CHECK_THROWS_AS(optimizer.Add(std::make_unique<BetweenFactor<Pose2>>(PoseId(3), PoseId(9), closing)),
                  std::invalid_argument);
  CHECK(optimizer.num_factors() == 3);
}

TEST_CASE("an incremental optimizer solves 3D poses on their manifold", "[backend][api]") {
  // Exact relative measurements of a 7-pose 3D loop with chords, each pose
  // started a little off: every solve as the graph grows reaches the truth.
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.05);
  constexpr int kPoses = 7;
  std::vector<Pose3> truth;
  for (int k = 0; k < kPoses; ++k) {
    truth.emplace_back(Eigen::Vector3d(3.0 * std::cos(k), 3.0 * std::sin(k), 0.2 * k),
                       Eigen::Quaterniond(Eigen::AngleAxisd(0.9 * k, Eigen::Vector3d(0.1, 0.2, 1.0).normalized())));
  }
  auto perturbed = [&](const Pose3& p) {
    return Pose3(p.translation() + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)),
                 p.rotation() * Eigen::Quaterniond(Eigen::AngleAxisd(noise(rng), Eigen::Vector3d::UnitX())));
  };
  auto between = [&](int a, int b) {
    RelativePoseMeasurement<Pose3> z;
    z.mean = truth[a].Between(truth[b]);
    return std::make_unique<BetweenFactor<Pose3>>(PoseId(a), PoseId(b), z);
  };
  IncrementalOptimizer optimizer;
  optimizer.Insert(PoseId(0), truth[0]);
  optimizer.SetConstant(PoseKey(PoseId(0)));
  for (int k = 1; k < kPoses; ++k) {
    optimizer.Insert(PoseId(k), perturbed(truth[k]));
    optimizer.Add(between(k - 1, k));
    if (k >= 3) optimizer.Add(between(k - 3, k));
    const Summary summary = optimizer.Solve();
    REQUIRE(summary.IsUsable());
    CHECK(summary.final_cost < 1e-16);
  }
  for (int k = 0; k < kPoses; ++k) {
    const Pose3 solved = optimizer.values().AtPose3(PoseId(k));
    CHECK((solved.translation() - truth[k].translation()).norm() < 1e-8);
    CHECK(solved.rotation().angularDistance(truth[k].rotation()) < 1e-8);
  }
}

// Two steps from a pose held constant, both measuring no motion, linearised
// at the identity where every Jacobian is +-I: the second pose's covariance
// is the sum of the steps' covariances, the first's is the first step's, and
// so is their cross-covariance. 2D and 3D (in the Pose3 tangent space:
// translation, then rotation).
template <typename PoseT, int kDim>
void CheckChainMarginals() {
  using Matrix = Eigen::Matrix<double, kDim, kDim>;
  Matrix a = Matrix::Random(), b = Matrix::Random();
  const Matrix omega1 = a * a.transpose() + Matrix::Identity(), omega2 = b * b.transpose() + Matrix::Identity();
  Values values;
  FactorGraph graph;
  for (int k = 0; k < 3; ++k) values.Insert(PoseId(k), PoseT());
  RelativePoseMeasurement<PoseT> z;
  z.information = omega1;
  graph.Emplace<BetweenFactor<PoseT>>(PoseId(0), PoseId(1), z);
  z.information = omega2;
  graph.Emplace<BetweenFactor<PoseT>>(PoseId(1), PoseId(2), z);
  // Without a gauge the information is singular.
  CHECK_THROWS_AS(JointMarginalCovariances(graph, values, {{PoseKey(PoseId(1)), PoseKey(PoseId(2))}}),
                  std::runtime_error);
  graph.SetConstant(PoseKey(PoseId(0)));
  const std::vector<Eigen::MatrixXd> joint = JointMarginalCovariances(
      graph, values, {{PoseKey(PoseId(1)), PoseKey(PoseId(2))}, {PoseKey(PoseId(0)), PoseKey(PoseId(2))}});
  REQUIRE(joint.size() == 2);
  REQUIRE(joint[0].rows() == 2 * kDim);
  const Matrix s1 = omega1.inverse(), s2 = omega2.inverse();
  CHECK((joint[0].topLeftCorner<kDim, kDim>() - s1).norm() < 1e-9);
  CHECK((joint[0].topRightCorner<kDim, kDim>() - s1).norm() < 1e-9);
  CHECK((joint[0].bottomLeftCorner<kDim, kDim>() - s1).norm() < 1e-9);
  CHECK((joint[0].bottomRightCorner<kDim, kDim>() - (s1 + s2)).norm() < 1e-9);
  CHECK(joint[1].topLeftCorner<kDim, kDim>().norm() == 0.0);  // held constant
  CHECK((joint[1].bottomRightCorner<kDim, kDim>() - (s1 + s2)).norm() < 1e-9);
  CHECK_THROWS_AS(JointMarginalCovariances(graph, values, {{PoseKey(PoseId(1)), PoseKey(PoseId(7))}}),
                  std::invalid_argument);
  // The factor's linearisation there: residual 0, Jacobians -L and L for
  // the square-root information L (L^T L = Omega).
  const LinearizedFactor linear = Linearize(*graph.factors()[1], values);
  CHECK(linear.residual.norm() == 0.0);
  REQUIRE(linear.jacobians.size() == 2);
  CHECK((linear.jacobians[1].transpose() * linear.jacobians[1] - omega2).norm() < 1e-9);
  CHECK((linear.jacobians[0] + linear.jacobians[1]).norm() < 1e-12);
}

TEST_CASE("joint marginal covariances of a chain sum its steps' covariances, 2D and 3D", "[backend][api][marginals]") {
  std::srand(7);
  CheckChainMarginals<Pose2, 3>();
  CheckChainMarginals<Pose3, 6>();
}

// Checks JointMarginalCovariances on `pairs` against the blocks of the dense
// inverse of the information sum J^T J assembled from each factor's
// linearisation (Linearize, itself checked against the chain above), for a
// graph of poses 0..num_poses-1 with one of them, `constant`, held constant.
template <int kDim>
void CheckMarginalsAgainstDenseInverse(const FactorGraph& graph, const Values& values, int num_poses,
                                       int constant, const std::vector<std::pair<int, int>>& pairs) {
  auto column = [&](int k) { return kDim * (k < constant ? k : k - 1); };
  Eigen::MatrixXd information = Eigen::MatrixXd::Zero(kDim * (num_poses - 1), kDim * (num_poses - 1));
  for (const auto& factor : graph.factors()) {
    const LinearizedFactor linear = Linearize(*factor, values);
    const std::vector<Key> keys = factor->keys();
    for (int i = 0; i < 2; ++i) {
      for (int j = 0; j < 2; ++j) {
        const int ki = static_cast<int>(keys[i].id), kj = static_cast<int>(keys[j].id);
        if (ki == constant || kj == constant) continue;
        information.block<kDim, kDim>(column(ki), column(kj)) +=
            linear.jacobians[i].transpose() * linear.jacobians[j];
      }
    }
  }
  const Eigen::MatrixXd covariance = information.inverse();
  std::vector<std::pair<Key, Key>> keys;
  for (const auto& [a, b] : pairs) keys.emplace_back(PoseKey(PoseId(a)), PoseKey(PoseId(b)));
  const std::vector<Eigen::MatrixXd> joint = JointMarginalCovariances(graph, values, keys);
  REQUIRE(joint.size() == pairs.size());
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const auto [a, b] = pairs[p];
    CAPTURE(a, b);
    REQUIRE(joint[p].rows() == 2 * kDim);
    for (const auto& [x, row] : {std::pair{a, 0}, std::pair{b, kDim}}) {
      for (const auto& [y, col] : {std::pair{a, 0}, std::pair{b, kDim}}) {
        const Eigen::MatrixXd got = joint[p].block<kDim, kDim>(row, col);
        if (x == constant || y == constant) {
          CHECK(got.norm() == 0.0);  // held constant
          continue;
        }
        const Eigen::MatrixXd want = covariance.block<kDim, kDim>(column(x), column(y));
        CHECK((got - want).norm() < 1e-9 * want.norm());
      }
    }
  }
}

// A loop of 3D poses away from their optimum (so no Jacobian is +-I), with
// non-diagonal information, one pose held constant.
TEST_CASE("joint marginal covariances equal the dense inverse of the information on a loop",
          "[backend][api][marginals]") {
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.3);
  constexpr int kPoses = 7;
  Values values;
  FactorGraph graph;
  for (int k = 0; k < kPoses; ++k) {
    const Eigen::Vector3d axis = Eigen::Vector3d(noise(rng), noise(rng), 1.0).normalized();
    values.Insert(PoseId(k), Pose3(Eigen::Vector3d(3.0 * std::cos(k), 3.0 * std::sin(k), noise(rng)),
                                   Eigen::Quaterniond(Eigen::AngleAxisd(0.9 * k + noise(rng), axis))));
  }
  RelativePoseMeasurement<Pose3> z;
  for (int k = 0; k < kPoses; ++k) {
    const Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Random();
    z.information = a * a.transpose() + Eigen::Matrix<double, 6, 6>::Identity();
    z.mean = Pose3(Eigen::Vector3d(noise(rng), 1.0, noise(rng)),
                   Eigen::Quaterniond(Eigen::AngleAxisd(0.9, Eigen::Vector3d::UnitZ())));
    graph.Emplace<BetweenFactor<Pose3>>(PoseId(k), PoseId((k + 1) % kPoses), z);
    if (k % 3 == 0) graph.Emplace<BetweenFactor<Pose3>>(PoseId(k), PoseId((k + 3) % kPoses), z);
  }
  graph.SetConstant(PoseKey(PoseId(2)));
  CheckMarginalsAgainstDenseInverse<6>(graph, values, kPoses, 2, {{0, 4}, {5, 1}, {3, 3}, {2, 6}});
}

// A generated world's closures fill the factor in a deep elimination tree
// whose paths share most of their rows: each pair is solved on the union of
// its poses' paths alone, so pairs far apart in the tree, in one branch,
// sharing a pose, or with the constant pose all check that union.
TEST_CASE("joint marginal covariances equal the dense inverse on a generated world",
          "[backend][api][marginals]") {
  ManhattanWorldOptions options;
  options.num_poses = 300;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(options);
  Values values;  // chained odometry: away from the optimum
  FactorGraph graph;
  for (const auto& [id, vertex] : sim.graph.vertices) values.Insert(id, *vertex.pose);
  for (const auto& c : sim.graph.constraints) graph.Emplace<BetweenFactor<Pose2>>(c.from, c.to, c.measurement);
  REQUIRE(sim.graph.constraints.size() > sim.graph.vertices.size() + 100);  // closures, not just a chain
  constexpr int kConstant = 150;
  graph.SetConstant(PoseKey(PoseId(kConstant)));
  std::vector<std::pair<int, int>> pairs = {{0, 299}, {1, 2}, {7, 7}, {150, 3}, {298, 150}, {40, 260}};
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> pose(0, options.num_poses - 1);
  for (int k = 0; k < 30; ++k) pairs.emplace_back(pose(rng), pose(rng));
  CheckMarginalsAgainstDenseInverse<3>(graph, values, options.num_poses, kConstant, pairs);
}

TEST_CASE("spanning-tree initialisation chains odometry exactly", "[backend][init]") {
  ManhattanWorldOptions options;
  options.num_poses = 200;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(options);
  PoseGraph2 stripped = sim.graph;
  for (auto& [id, v] : stripped.vertices) v.pose.reset();
  InitializeBySpanningTree(stripped);
  for (const auto& [id, v] : sim.graph.vertices) {
    // The simulator's initial guess is the chained noisy odometry.
    REQUIRE(testing::ApproxEqual(*stripped.vertices.at(id).pose, *v.pose, 1e-9));
  }
}

TEST_CASE("switchable constraints with the default gate reject injected closures and keep "
          "true ones on a graph with correct information",
          "[backend][switchable][slow]") {
  const auto [sim, injected] = SpoiledManhattanWorld(1000, 9, 50, 3);
  std::size_t true_closures = 0;
  // The gate is chi2's quantile for g2o's cost, the chordal cost's own
  // (ChordalCostQuantile) for SE-Sync's.
  for (const RelativePoseCostType cost : {RelativePoseCostType::kG2o, RelativePoseCostType::kChordal}) {
    INFO("chordal cost: " << (cost == RelativePoseCostType::kChordal));
    PoseGraphOptimizerOptions options;
    options.cost = cost;
    const PoseGraphOptimization result = OptimizePoseGraph(sim.graph, options);
    REQUIRE(result.summary.IsUsable());
    const testing::InjectedDecisions counts = testing::CountInjected(result, injected);
    CHECK(counts.false_accepted == 0);
    // The 0.999 gate rejects 1 in 1000 true closures at the true poses by
    // construction; at the solution, on five clean 2000-pose worlds, 65 of
    // 46344 for either cost (0.14 %). 0.4 % is that plus three binomial
    // sigmas for this graph's 2244 true closures.
    true_closures = counts.true_closures;
    CHECK(counts.true_rejected <= true_closures / 250);
  }
  // Vertigo's xi = 1 rejects most true closures of such a graph.
  PoseGraphOptimizerOptions vertigo;
  vertigo.switch_prior_information = 1.0;
  const PoseGraphOptimization fixed = OptimizePoseGraph(sim.graph, vertigo);
  CHECK(fixed.rejected > true_closures / 2);
}

TEST_CASE("refinement gives the plain optimum of the graph without the rejected closures",
          "[backend][refine]") {
  const SimulatedPoseGraph2 sim = SpoiledManhattanWorld(400, 12, 60, 5).sim;
  for (RobustMethod method : {RobustMethod::kSwitchable, RobustMethod::kDcs}) {
    PoseGraphOptimizerOptions options;
    options.method = method;
    options.readmission.enabled = false;  // the robust solve's decisions, refined
    const PoseGraphOptimization refined = OptimizePoseGraph(sim.graph, options);
    REQUIRE(refined.refinement);
    REQUIRE(refined.refinement->IsUsable());
    options.refinement.enabled = false;
    const PoseGraphOptimization raw = OptimizePoseGraph(sim.graph, options);
    CHECK(!raw.refinement);
    // The same decisions ...
    REQUIRE(raw.closures.size() == refined.closures.size());
    for (std::size_t k = 0; k < raw.closures.size(); ++k) {
      CHECK(raw.closures[k].accepted == refined.closures[k].accepted);
    }
    // ... and the poses of a plain solve without the rejected closures.
    PoseGraphOptimizerOptions plain;
    plain.method = RobustMethod::kNone;
    const PoseGraphOptimization reference =
        OptimizePoseGraph(DropRejected(raw.graph, raw.closures), plain);
    CAPTURE(ToString(method));
    CHECK(LargestPositionDifference(refined.graph, reference.graph) < 1e-5);
    CHECK(Chi2(reference.graph) < Chi2(raw.graph));
  }
}

// PoseGraphOptimizerOptions::stop_when_settled: the robust solve ends once
// its decisions settle; the refinement then gives the map the full solve
// gives, with the same decisions. Long false closures (random policy) make
// the full solve's late iterations the costly ones.
TEST_CASE("the robust solve stops when its decisions settle, with the full solve's decisions and map",
          "[backend][refine][slow]") {
  const SimulatedPoseGraph2 sim = SpoiledManhattanWorld(1000, 21, 200, 8).sim;
  for (RobustMethod method : {RobustMethod::kSwitchable, RobustMethod::kDcs}) {
    CAPTURE(ToString(method));
    PoseGraphOptimizerOptions options;
    options.method = method;
    const PoseGraphOptimization settled = OptimizePoseGraph(sim.graph, options);
    options.refinement.stop_when_settled = false;
    const PoseGraphOptimization full = OptimizePoseGraph(sim.graph, options);
    REQUIRE(settled.refinement);
    REQUIRE(full.refinement);
    CHECK(settled.summary.stopped_by_test);
    CHECK_FALSE(full.summary.stopped_by_test);
    CAPTURE(settled.summary.iterations, full.summary.iterations);
    CHECK(settled.summary.iterations < full.summary.iterations);
    REQUIRE(settled.closures.size() == full.closures.size());
    for (std::size_t k = 0; k < full.closures.size(); ++k) {
      CHECK(settled.closures[k].accepted == full.closures[k].accepted);
    }
    CHECK(LargestPositionDifference(settled.graph, full.graph) < 1e-5);
  }
  PoseGraphOptimizerOptions bad;
  bad.refinement.settled_iterations = 0;
  CHECK_THROWS_AS(Validate(bad), std::invalid_argument);
  bad = {};
  bad.refinement.settled_decrease = 0.0;
  CHECK_THROWS_AS(Validate(bad), std::invalid_argument);
}

// Readmission (PoseGraphOptimizerOptions::readmit) on a world with the
// right information: the true closures the gate rejected come back, the
// injected ones stay out, for every method deciding at the gate.
TEST_CASE("readmission brings back the true closures the gate rejected and no false one",
          "[backend][readmit][slow]") {
  const auto [sim, injected] = SpoiledManhattanWorld(800, 4, 50, 6, OutlierPolicy::kLocal);
  for (RobustMethod method : {RobustMethod::kSwitchable, RobustMethod::kDcs, RobustMethod::kGnc}) {
    CAPTURE(ToString(method));
    PoseGraphOptimizerOptions options;
    options.method = method;
    options.readmission.enabled = false;
    const PoseGraphOptimization gated = OptimizePoseGraph(sim.graph, options);
    options.readmission.enabled = true;
    const PoseGraphOptimization r = OptimizePoseGraph(sim.graph, options);
    const testing::InjectedDecisions before = testing::CountInjected(gated, injected);
    const testing::InjectedDecisions after = testing::CountInjected(r, injected);
    CAPTURE(before.true_rejected, before.false_accepted, after.true_rejected, after.false_accepted);
    CHECK(before.true_rejected > 0);
    CHECK(after.true_rejected == 0);  // measured 5, 6 and 2 before
    CHECK(after.false_accepted == before.false_accepted);
    CHECK(r.readmitted == before.true_rejected - after.true_rejected);
    std::size_t flagged = 0;
    for (std::size_t k = 0; k < r.closures.size(); ++k) {
      const ClosureDecision &d = r.closures[k], &g = gated.closures[k];
      flagged += d.readmitted;
      if (d.readmitted) {
        CHECK_FALSE(g.accepted);
        CHECK(d.accepted);
        CHECK(d.weight == 1.0);
      } else {
        CHECK(d.accepted == g.accepted);
      }
    }
    CHECK(flagged == r.readmitted);
  }
}

TEST_CASE("the solve reports the stages it ran, in order, with their iterations and times",
          "[backend][stages]") {
  const auto [sim, injected] = SpoiledManhattanWorld(300, 5, 20, 2, OutlierPolicy::kLocal);
  auto names = [](const PoseGraphOptimization& r) {
    std::vector<std::string> out;
    for (const StageTime& s : r.stages) out.push_back(s.stage);
    return out;
  };
  // The named stage; iterations -1 when it did not run.
  auto stage_of = [](const PoseGraphOptimization& r, const std::string& stage) {
    for (const StageTime& s : r.stages) {
      if (s.stage == stage) return s;
    }
    return StageTime{stage, 0.0, -1};
  };
  auto iterations_of = [&stage_of](const PoseGraphOptimization& r, const std::string& stage) {
    return stage_of(r, stage).iterations;
  };
  auto check_times = [&stage_of](const PoseGraphOptimization& r) {
    double sum = 0.0;
    for (const StageTime& s : r.stages) {
      CHECK(s.time_s >= 0.0);
      sum += s.time_s;
    }
    CHECK(r.WallTimeS() == Approx(sum));
    // The stages' wall clock holds every solve Ceres timed.
    CHECK(r.WallTimeS() >= r.TotalTimeS());
    CHECK(r.initial_guess_time_s == stage_of(r, "initial_guess").time_s);
  };

  PoseGraphOptimizerOptions options;
  options.gate.narrow = false;
  const PoseGraphOptimization r = OptimizePoseGraph(sim.graph, options);
  REQUIRE(r.refinement);
  CHECK(names(r) == std::vector<std::string>{"noise_scale", "initial_guess", "robust_solve", "refine",
                                              "readmit", "costs"});
  CHECK(iterations_of(r, "robust_solve") == r.summary.iterations);
  CHECK(iterations_of(r, "refine") == r.refinement->iterations);
  CHECK(iterations_of(r, "initial_guess") == 0);
  if (r.readmission) CHECK(iterations_of(r, "readmit") >= r.readmission->iterations);
  check_times(r);

  // Plain least squares: no noise scale, no refinement, no readmission.
  options.method = RobustMethod::kNone;
  const PoseGraphOptimization plain = OptimizePoseGraph(sim.graph, options);
  CHECK(names(plain) == std::vector<std::string>{"initial_guess", "robust_solve", "costs"});
  CHECK(iterations_of(plain, "robust_solve") == plain.summary.iterations);
  check_times(plain);
}

TEST_CASE("chordal initialisation recovers exact poses from exact measurements",
          "[backend][init]") {
  ManhattanWorldOptions options;
  options.num_poses = 300;
  options.seed = 4;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(options);
  PoseGraph2 g = sim.truth;
  for (auto& [id, v] : g.vertices) {
    if (id.value() > 0) v.pose = Pose2(5.0, -3.0, 2.0);  // a useless guess
  }
  InitializeChordal(g);
  for (const auto& [id, v] : sim.truth.vertices) {
    REQUIRE(testing::ApproxEqual(*g.vertices.at(id).pose, *v.pose, 1e-6));
  }
  // 3D: lift the planar truth and rotate it out of the plane.
  PoseGraph3 g3;
  const Pose3 tilt(Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(0.9, 0.3, -0.2, 0.1));
  auto lift = [&](const Pose2& p) {
    return tilt * Pose3(Eigen::Vector3d(p.x(), p.y(), 0.0),
                        Eigen::Quaterniond(Eigen::AngleAxisd(p.theta(), Eigen::Vector3d::UnitZ())));
  };
  for (const auto& [id, v] : sim.truth.vertices) {
    g3.vertices.emplace(id, Vertex<Pose3>{id, id.value() == 0 ? lift(*v.pose) : Pose3(), false});
  }
  for (const auto& c : sim.truth.constraints) {
    Constraint<Pose3> c3;
    c3.id = c.id;
    c3.from = c.from;
    c3.to = c.to;
    c3.kind = c.kind;
    c3.measurement.mean = lift(*sim.truth.vertices.at(c.from).pose)
                              .Between(lift(*sim.truth.vertices.at(c.to).pose));
    g3.constraints.push_back(c3);
  }
  InitializeChordal(g3);
  for (const auto& [id, v] : sim.truth.vertices) {
    REQUIRE(testing::ApproxEqual(*g3.vertices.at(id).pose, lift(*v.pose), 1e-6));
  }
}

TEST_CASE("chordal initialisation escapes the local minima of MIT and M3500b",
          "[backend][init][shared][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  PoseGraphOptimizerOptions options;
  options.method = RobustMethod::kNone;
  options.initial_guess = InitialGuess::kChordal;
  // robust-backend-notes.md §3: 41.16 and 2054.7 (the latter not certified).
  const auto mit = OptimizePoseGraph(ReadGraphFile(root / "se-sync/MIT.g2o").graph, options);
  CHECK(mit.chi2 == Approx(41.16).epsilon(1e-3));
  const auto m3500b =
      OptimizePoseGraph(ReadGraphFile(root / "carlone/input_M3500b_g2o.g2o").graph, options);
  CHECK(m3500b.chi2 == Approx(2054.7).epsilon(1e-4));
  // From chained odometry, plain LM stays far from it on MIT.
  options.initial_guess = InitialGuess::kFile;
  CHECK(OptimizePoseGraph(ReadGraphFile(root / "se-sync/MIT.g2o").graph, options).chi2 > 1000.0);
}

TEST_CASE("the auto initial guess takes chordal on a clean graph and the file's poses among "
          "false closures",
          "[backend][init]") {
  ManhattanWorldOptions world;
  world.num_poses = 500;
  world.seed = 9;
  SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  PoseGraphOptimizerOptions options;  // kAuto by default
  REQUIRE(options.initial_guess == InitialGuess::kAuto);
  // Clean: the chordal guess explains the closures better than chained odometry.
  CHECK(OptimizePoseGraph(sim.graph, options).initial_guess == InitialGuess::kChordal);
  // 50 false closures bend the chordal guess (it is a least-squares fit to
  // every edge); the truncated cost prefers the file's poses, and the result
  // is the file's.
  OutlierOptions outliers;
  outliers.count = 50;
  outliers.seed = 3;
  std::set<ClosureId> injected;
  for (const InjectedClosure& c : InjectOutliers(sim.graph, outliers)) injected.insert(c.id);
  const PoseGraphOptimization automatic = OptimizePoseGraph(sim.graph, options);
  CHECK(automatic.initial_guess == InitialGuess::kFile);
  options.initial_guess = InitialGuess::kFile;
  const PoseGraphOptimization file = OptimizePoseGraph(sim.graph, options);
  CHECK(file.initial_guess == InitialGuess::kFile);
  CHECK(automatic.chi2 == file.chi2);
  for (const auto& d : automatic.closures) {
    if (injected.contains(d.id)) CHECK(!d.accepted);
  }
}

TEST_CASE("with the default initial guess, switchable constraints keep every closure of MIT",
          "[backend][init][shared][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const AnyPoseGraph mit = ReadGraphFile(root / "se-sync/MIT.g2o").graph;
  const PoseGraphOptimization r = OptimizePoseGraph(mit);
  CHECK(r.initial_guess == InitialGuess::kChordal);
  CHECK(r.rejected == 0);
  CHECK(r.accepted == 20);
  // From the file's poses the switches settle in a local minimum, the
  // reason kAuto is the default ...
  PoseGraphOptimizerOptions file;
  file.initial_guess = InitialGuess::kFile;
  file.readmission.enabled = false;
  const PoseGraphOptimization trapped = OptimizePoseGraph(mit, file);
  CHECK(trapped.rejected > 0);
  // ... from which readmission brings every closure back.
  file.readmission.enabled = true;
  const PoseGraphOptimization readmitted = OptimizePoseGraph(mit, file);
  CHECK(readmitted.rejected == 0);
  CHECK(readmitted.readmitted == trapped.rejected);
  // Its map: the plain least-squares optimum, as from the chordal start
  // (the chi2 without the switches).
  PoseGraphOptimizerOptions plain;
  plain.method = RobustMethod::kNone;
  CHECK(Chi2(DropRejected(readmitted.graph, readmitted.closures)) ==
        Approx(OptimizePoseGraph(mit, plain).chi2).epsilon(1e-6));
}

// Plain least squares on SE-Sync's cost from the chordal initial guess.
PoseGraphOptimizerOptions ChordalCostOptions() {
  PoseGraphOptimizerOptions options;
  options.method = RobustMethod::kNone;
  options.initial_guess = InitialGuess::kChordal;
  options.cost = RelativePoseCostType::kChordal;
  return options;
}

TEST_CASE("the chordal cost reaches SE-Sync's certified optima", "[backend][shared][chordal]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  // robust-backend-notes.md §3; the references carry four significant
  // digits, which bounds the tolerance (half a unit of the last digit).
  const std::vector<std::pair<const char*, double>> optima = {
      {"se-sync/manhattan.g2o", 6.432e3}, {"se-sync/intel.g2o", 5.235e1}, {"se-sync/CSAIL.g2o", 3.170e1}};
  PoseGraphOptimizerOptions options = ChordalCostOptions();
  for (const auto& [path, optimum] : optima) {
    SECTION(path) {
      const auto result = OptimizePoseGraph(ReadGraphFile(root / path).graph, options);
      REQUIRE(result.summary.IsUsable());
      CHECK(result.chordal_cost == Approx(optimum).epsilon(5e-4));
      CHECK(result.chordal_cost == Approx(2.0 * result.summary.final_cost).epsilon(1e-9));
    }
  }
}

TEST_CASE("switchable constraints with the chordal cost keep every closure of intel and CSAIL at "
          "SE-Sync's optimum",
          "[backend][shared][chordal][switchable]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  PoseGraphOptimizerOptions options = ChordalCostOptions();
  options.method = RobustMethod::kSwitchable;
  const std::vector<std::pair<const char*, double>> optima = {{"se-sync/intel.g2o", 5.235e1},
                                                              {"se-sync/CSAIL.g2o", 3.170e1}};
  for (const auto& [path, optimum] : optima) {
    SECTION(path) {
      const auto result = OptimizePoseGraph(ReadGraphFile(root / path).graph, options);
      REQUIRE(result.summary.IsUsable());
      CHECK(result.rejected == 0);
      CHECK(result.chordal_cost == Approx(optimum).epsilon(5e-4));
    }
  }
}

TEST_CASE("the chordal cost reaches SE-Sync's certified optima in 3D", "[backend][shared][chordal][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  PoseGraphOptimizerOptions options = ChordalCostOptions();
  const auto garage = OptimizePoseGraph(ReadGraphFile(root / "se-sync/parking-garage.g2o").graph, options);
  CHECK(garage.chordal_cost == Approx(1.263).epsilon(5e-4));
  const auto cubicle = OptimizePoseGraph(ReadGraphFile(root / "se-sync/cubicle.g2o").graph, options);
  CHECK(cubicle.chordal_cost == Approx(7.171e2).epsilon(5e-4));
}

// The most informative edge of `graph` between poses `from` and `to` (either
// direction in the file), as the pose of `to` in the frame of `from`.
std::optional<Pose3> MeasuredBetween(const PoseGraph3& graph, std::int64_t from, std::int64_t to) {
  const Constraint<Pose3>* best = nullptr;
  for (const auto& c : graph.constraints) {
    const bool joins =
        (c.from.value() == from && c.to.value() == to) || (c.from.value() == to && c.to.value() == from);
    if (joins && (!best || c.measurement.information.trace() > best->measurement.information.trace())) {
      best = &c;
    }
  }
  if (!best) return std::nullopt;
  return best->from.value() == from ? best->measurement.mean : best->measurement.mean.Inverse();
}

// The file's odometry from pose `from` to pose `to`: at each step the edge to
// the farthest of the next three poses that has one.
std::optional<Pose3> OdometryBetween(const PoseGraph3& graph, std::int64_t from, std::int64_t to) {
  Pose3 pose;
  const std::int64_t direction = to > from ? 1 : -1;
  for (std::int64_t k = from; k != to;) {
    std::int64_t step = std::min<std::int64_t>(3, (to - k) * direction);
    std::optional<Pose3> edge;
    while (step >= 1 && !(edge = MeasuredBetween(graph, k, k + step * direction))) --step;
    if (!edge) return std::nullopt;
    pose = pose * *edge;
    k += step * direction;
  }
  return pose;
}

// Where closure (a, b) puts pose b seen from a, against where closure (c, d)
// puts it, carried there by the odometry a..c and d..b: the distance between
// the two positions (m) and the angle between the two orientations (rad).
std::pair<double, double> Disagreement(const PoseGraph3& graph, std::int64_t a, std::int64_t b, std::int64_t c,
                                       std::int64_t d) {
  const Pose3 direct = MeasuredBetween(graph, a, b).value();
  const Pose3 via = OdometryBetween(graph, a, c).value() * MeasuredBetween(graph, c, d).value() *
                    OdometryBetween(graph, d, b).value();
  return {(direct.translation() - via.translation()).norm(),
          RotationAngle(direct.rotation().conjugate() * via.rotation())};
}

TEST_CASE("SE-Sync's cubicle contradicts itself at the four closures the defaults reject",
          "[backend][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  // `catgraph optimize se-sync/cubicle.g2o` rejects 4298-5703, 4298-5704,
  // 4301-5699 and 4316-5667 (docs/backend.md, measured: the full solve takes
  // a minute). Each disagrees by decimetres to metres and tens of degrees
  // with closures from the same or a neighbouring pose to poses centimetres
  // away, which agree with each other: they are failed registrations, not
  // noise. The file alone shows it; no solve is needed.
  const auto cubicle = std::get<PoseGraph3>(ReadGraphFile(root / "se-sync/cubicle.g2o").graph);
  constexpr double kDegree = std::numbers::pi / 180.0;
  struct Pair {
    std::int64_t a, b, c, d;
    bool agree;
  };
  const std::vector<Pair> pairs = {
      // One revisit, two registrations of the same frames that cannot both hold.
      {4298, 5703, 4298, 5701, false},
      {4298, 5704, 4298, 5701, false},
      {4301, 5699, 4300, 5693, false},
      {4301, 5699, 4300, 5691, false},
      {4298, 5701, 4297, 5700, true},
      {4300, 5693, 4300, 5691, true},
      {4298, 5703, 4298, 5704, true},
      {4301, 5699, 4298, 5703, true},
      // 4316-5667 against every neighbour, which agree with each other.
      {4316, 5667, 4316, 5664, false},
      {4316, 5667, 4316, 5668, false},
      {4316, 5667, 4314, 5666, false},
      {4316, 5667, 4312, 5665, false},
      {4316, 5664, 4316, 5668, true},
      {4316, 5668, 4314, 5666, true},
      {4314, 5666, 4312, 5665, true},
  };
  for (const Pair& p : pairs) {
    const auto [distance, angle] = Disagreement(cubicle, p.a, p.b, p.c, p.d);
    CAPTURE(p.a, p.b, p.c, p.d, distance, angle / kDegree);
    if (p.agree) {
      CHECK(distance < 0.1);
      CHECK(angle < 5.0 * kDegree);
    } else {
      CHECK(distance > 0.4);
      CHECK(angle > 10.0 * kDegree);
    }
  }
}

struct ReferenceChi2 {
  const char* path;
  double chi2;
};

TEST_CASE("plain least squares reaches the reference chi2 of the shared graphs",
          "[backend][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  // ../shared/docs/robust-backend-notes.md, section 3.
  const std::vector<ReferenceChi2> references = {
      {"vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o", 146.08},
      {"vertigo/manhattan/originalDataset/Olson/manhattanOlson3500.g2o", 146.08},
      {"vertigo/intel/originalDataset/intel.g2o", 546.46},
      {"vertigo/ring/originalDataset/ring.g2o", 11.16},
      {"carlone/input_M3500_g2o.g2o", 137.91},
  };
  PoseGraphOptimizerOptions options;
  options.method = RobustMethod::kNone;
  for (const auto& ref : references) {
    SECTION(ref.path) {
      const auto result = OptimizePoseGraph(ReadGraphFile(root / ref.path).graph, options);
      REQUIRE(result.summary.IsUsable());
      CHECK(result.chi2 == Approx(ref.chi2).epsilon(1e-4).margin(0.005));
      CHECK(Chi2(result.graph) == Approx(result.chi2));
      CHECK(result.chi2 == Approx(4.0 * result.summary.final_cost / 2.0).epsilon(1e-9));
    }
  }
}

// The inlier cost of a robust solve: the chi2 of its solution over the
// original edges only, the `injected` false closures and every switch left
// out.
template <typename PoseT>
double InlierChi2(const PoseGraphOptimization& r, const std::set<ClosureId>& injected) {
  PoseGraph<PoseT> inliers = std::get<PoseGraph<PoseT>>(r.graph);
  std::erase_if(inliers.constraints, [&](const auto& c) { return injected.contains(c.id); });
  for (auto& c : inliers.constraints) c.switch_id.reset();
  inliers.switches.clear();
  return Chi2(inliers);
}

// A long real trajectory (SE-Sync's KITTI 05: 2761 poses, 66 closures) with
// 100 random false closures: the gate rejects the true closures too, whose
// residuals are heavier than their information states, and readmission,
// on marginals along the trajectory's long elimination-tree paths, brings
// every one of them back and no false one; the map is the clean optimum.
TEST_CASE("KITTI 05 with 100 random outliers: readmission brings back every true closure and no false one",
          "[backend][shared][outliers][readmit]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const AnyPoseGraph clean = ReadGraphFile(root / "se-sync/kitti_05.g2o").graph;
  PoseGraphOptimizerOptions plain;
  plain.method = RobustMethod::kNone;
  const double optimum = OptimizePoseGraph(clean, plain).chi2;
  AnyPoseGraph spoiled = clean;
  OutlierOptions outliers;
  outliers.count = 100;
  std::set<ClosureId> injected;
  for (const InjectedClosure& c : InjectOutliers(spoiled, outliers)) injected.insert(c.id);
  const PoseGraphOptimization r = OptimizePoseGraph(spoiled, PoseGraphOptimizerOptions{});
  REQUIRE(r.summary.IsUsable());
  std::size_t true_closures = 0, true_rejected = 0, outliers_accepted = 0;
  for (const ClosureDecision& d : r.closures) {
    if (injected.contains(d.id)) {
      outliers_accepted += d.accepted;
    } else {
      ++true_closures;
      true_rejected += !d.accepted;
    }
  }
  CHECK(true_closures == 66);
  CHECK(true_rejected == 0);
  CHECK(outliers_accepted == 0);
  CHECK(r.readmitted == 66);
  CHECK(InlierChi2<Pose2>(r, injected) == Approx(optimum).epsilon(1e-4));
}

TEST_CASE("3D: smallGrid3D with 100 random outliers keeps the outlier-free inlier cost",
          "[backend][shared][outliers]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const AnyPoseGraph clean = ReadGraphFile(root / "se-sync/smallGrid3D.g2o").graph;
  PoseGraphOptimizerOptions plain;
  plain.method = RobustMethod::kNone;
  const double optimum = OptimizePoseGraph(clean, plain).chi2;
  for (std::uint64_t seed : {1, 2, 3}) {
    AnyPoseGraph spoiled = clean;
    OutlierOptions outliers;
    outliers.count = 100;
    outliers.seed = seed;
    std::set<ClosureId> injected;
    for (const InjectedClosure& c : InjectOutliers(spoiled, outliers)) injected.insert(c.id);
    // The default method (DCS drops one true closure on seed 3 and misses by
    // 16%; see the issue note).
    for (RobustMethod method : {RobustMethod::kSwitchable}) {
      PoseGraphOptimizerOptions options;
      options.method = method;
      const PoseGraphOptimization r = OptimizePoseGraph(spoiled, options);
      REQUIRE(r.summary.IsUsable());
      std::size_t outliers_accepted = 0;
      for (const ClosureDecision& d : r.closures) {
        outliers_accepted += injected.contains(d.id) && d.accepted;
      }
      CAPTURE(seed, ToString(method), optimum);
      CHECK(outliers_accepted == 0);
      CHECK(InlierChi2<Pose3>(r, injected) == Approx(optimum).epsilon(1e-3));
    }
  }
}

}  // namespace
}  // namespace catgraph
