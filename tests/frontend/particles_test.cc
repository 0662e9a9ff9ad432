// The particle utilities both filters share (frontend/particles.h) and
// CAT-Graph+'s odometric filter on its own (frontend/odometric_inference.h),
// on straight lines whose answers are known.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "tests/catch.h"

#include "frontend/odometric_inference.h"
#include "frontend/particles.h"
#include "frontend/trajectory_graph.h"

namespace catgraph {
namespace {

// A straight line of `nodes` nodes `spacing` m apart along x, one per
// second.
TrajectoryGraph SpacedLine(int nodes, double spacing) {
  TrajectoryGraph g;
  for (int i = 0; i < nodes; ++i) g.AddNode(i, i, spacing * i, Pose2(spacing * i, 0.0, 0.0), {});
  for (int i = 1; i < nodes; ++i) g.AddEdge(i - 1, i, Pose2(spacing, 0.0, 0.0), EdgeType::kOdometry);
  return g;
}

std::vector<Particle> Weighted(const std::vector<double>& weights) {
  std::vector<Particle> particles;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    particles.push_back({static_cast<int>(i), 0.5, 1, std::log(weights[i])});
  }
  return particles;
}

TEST_CASE("LogSumExp, the total weight and Eq 5's effective sample size", "[frontend][particles]") {
  CHECK(LogSumExp(std::log(2.0), std::log(3.0)) == Approx(std::log(5.0)));
  CHECK(LogSumExp(kNegInf, -700.0) == -700.0);
  CHECK(LogSumExp(-1000.0, -1000.0) == Approx(-1000.0 + std::log(2.0)));  // no underflow
  CHECK(LogTotalWeight({}) == kNegInf);
  CHECK(LogTotalWeight(Weighted({0.1, 0.2, 0.3})) == Approx(std::log(0.6)));

  CHECK(EffectiveSampleSize({}) == 0.0);
  CHECK(EffectiveSampleSize(Weighted({0.25, 0.25, 0.25, 0.25})) == Approx(4.0));
  CHECK(EffectiveSampleSize(Weighted({1.0, 1e-300})) == Approx(1.0));
  // (sum w)² / sum w², whatever the weights sum to.
  CHECK(EffectiveSampleSize(Weighted({0.1, 0.3})) == Approx(0.16 / 0.1));
}

TEST_CASE("Systematic resampling draws each particle n w times, to within one, and counts the rest beyond",
          "[frontend][particles]") {
  const std::vector<double> weights = {0.05, 0.4, 0.0, 0.15, 0.1};  // sum 0.7
  const std::vector<Particle> particles = Weighted(weights);
  constexpr int kDraws = 1000;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::size_t beyond = 0;
    const std::vector<Particle> drawn = SystematicResample(particles, kDraws, rng, &beyond);
    std::vector<int> count(weights.size(), 0);
    for (const Particle& p : drawn) ++count[static_cast<std::size_t>(p.edge)];
    for (std::size_t i = 0; i < weights.size(); ++i) {
      CAPTURE(seed, i);
      CHECK(std::abs(count[i] - kDraws * weights[i]) <= 1.0);
    }
    CHECK(std::abs(static_cast<double>(beyond) - 0.3 * kDraws) <= 1.0);
    CHECK(drawn.size() + beyond == static_cast<std::size_t>(kDraws));
    // Drawn in the particles' order, with their weights.
    for (std::size_t k = 1; k < drawn.size(); ++k) CHECK(drawn[k - 1].edge <= drawn[k].edge);
    CHECK(drawn.front().log_weight == particles.front().log_weight);
  }
  std::mt19937_64 a(7), b(7);
  std::size_t beyond_a = 0, beyond_b = 0;
  const auto first = SystematicResample(particles, 100, a, &beyond_a);
  const auto second = SystematicResample(particles, 100, b, &beyond_b);
  REQUIRE(first.size() == second.size());
  for (std::size_t k = 0; k < first.size(); ++k) CHECK(first[k].edge == second[k].edge);

  std::mt19937_64 rng(1);
  std::size_t beyond = 0;
  CHECK(SystematicResample({}, 10, rng, &beyond).empty());
  CHECK(beyond == 10);
}

TEST_CASE("The kernel moves particles along the line by the odometry and finds Eq 4's heaviest disc",
          "[frontend][particles]") {
  const TrajectoryGraph line = SpacedLine(21, 0.5);  // 0 ... 10 m
  ParticleKernel kernel(line, {}, {});

  // Almost no noise: a particle at 2.25 m moved 0.3 m ahead lands at 2.55 m
  // (edge 5 at 0.1), facing along the line, weighed by Eq 1 for the noise
  // projected away.
  std::vector<Particle> moved = {{4, 0.5, 1, 0.0}, {4, 0.5, -1, 0.0}};
  std::mt19937_64 rng(1);
  kernel.Move(moved, Pose2(0.3, 0.0, 0.0), Eigen::Vector3d::Constant(1e-9), rng);
  CHECK(moved[0].edge == 5);
  CHECK(moved[0].alpha == Approx(0.1).margin(1e-6));
  CHECK(moved[0].direction == 1);
  CHECK(moved[0].log_weight <= 0.0);
  CHECK(moved[0].log_weight > -20.0);
  // Facing against the line, it goes back to 1.95 m.
  CHECK(moved[1].edge == 3);
  CHECK(moved[1].alpha == Approx(0.9).margin(1e-6));
  CHECK(moved[1].direction == -1);

  // 0.6 of the weight around 2.5 m, 0.4 around 7 m: Eq 4 picks the first,
  // with the weight within d_h = 1 m, at the weighted mean of its particles.
  auto at_x = [](double x, int direction) {
    const int edge = static_cast<int>(x / 0.5);
    return Particle{edge, (x - 0.5 * edge) / 0.5, direction, std::log(0.2)};
  };
  const std::vector<Particle> particles = {at_x(2.3, 1), at_x(2.5, 1), at_x(2.7, 1), at_x(6.9, -1), at_x(7.1, -1)};
  const LocationHypothesis best = kernel.BestHypothesis(particles);
  CHECK(best.value == Approx(0.6));
  CHECK(best.direction == 1);
  const std::optional<Pose2> at = HypothesisPose(kernel.Local(0, 20.0), best);
  REQUIRE(at);
  CHECK(at->x() == Approx(2.5).margin(1e-9));
  CHECK(at->theta() == Approx(0.0).margin(1e-12));
  // The loop edge to the nearer end of the edge: node 5 at 2.5 m.
  const auto [matched, T] = kernel.LoopTo(best);
  CHECK(matched == 5);
  CHECK(T.translation().norm() == Approx(0.0).margin(1e-9));

  // Facing against the line, a hypothesis' pose is turned by π.
  const std::optional<Pose2> back = HypothesisPose(kernel.Local(0, 20.0), {14, 0.0, -1, 0.4});
  REQUIRE(back);
  CHECK(back->x() == Approx(7.0));
  CHECK(std::abs(back->theta()) == Approx(std::numbers::pi));
  CHECK(kernel.BestHypothesis({}).edge == -1);
}

TEST_CASE("CAT-Graph+ on its own: O follows the odometry from a visual closure and the next one validates it",
          "[frontend][particles][catgraph-plus]") {
  // An old trajectory 0 ... 20 m, then a second pass from 2 m on: the new
  // nodes are 40 ... (a restart between the passes is the caller's).
  TrajectoryGraph graph = SpacedLine(41, 0.5);
  CatGraphOptions options;
  options.motion_sigma = Eigen::Vector3d(0.01, 0.01, 0.005);
  ParticleKernel kernel(graph, {}, [](int n) { return n <= 40; });
  OdometricInference inference(graph, kernel, options);
  const Pose2 u(0.25, 0.0, 0.0);
  // V: a tight cloud at the start of edge `edge`.
  auto cloud_at = [](int edge) {
    std::vector<Particle> v;
    for (int k = 0; k < 200; ++k) v.push_back({edge, 0.01 * (k % 3), 1, std::log(1.0 / 200)});
    return v;
  };
  // The visual match at 2 m (edge 4 from node 4).
  const std::vector<Particle> visual = cloud_at(4);
  int node = graph.AddNode(100, 100.0, 20.5, Pose2(), {});
  InferenceStep first;
  inference.Step(node, Pose2(), /*closure=*/true, {4, 0.0, 1, 1.0}, visual, 41, first);
  CHECK(first.inferred.empty());
  CHECK_FALSE(inference.particles().empty());
  // Eight frames of 0.25 m without a visual closure: each waits.
  int pending = 0;
  for (int k = 1; k <= 8; ++k) {
    const int next = graph.AddNode(100 + k, 100.0 + k, 20.5 + 0.25 * k, Pose2(), {});
    graph.AddEdge(node, next, u, EdgeType::kOdometry);
    node = next;
    InferenceStep step;
    inference.Step(node, u, false, {}, visual, 41, step);
    CAPTURE(k);
    REQUIRE(step.odometric_best.edge >= 0);
    const std::optional<Pose2> at = HypothesisPose(kernel.Local(0, 30.0), step.odometric_best);
    REQUIRE(at);
    CHECK(at->x() == Approx(2.0 + 0.25 * k).margin(0.1));
    pending += step.pending;
  }
  CHECK(pending == 8);
  // The next visual closure at 4.25 m agrees: all eight are validated,
  // each matched to the old node at its place.
  const int next = graph.AddNode(109, 109.0, 22.75, Pose2(), {});
  graph.AddEdge(node, next, u, EdgeType::kOdometry);
  InferenceStep end;
  inference.Step(next, u, true, {8, 0.5, 1, 1.0}, visual, 41, end);
  CHECK(end.reference_node == 41);
  CHECK(end.discarded.empty());
  REQUIRE(end.inferred.size() == 8);
  for (std::size_t i = 0; i < end.inferred.size(); ++i) {
    const double x = 2.0 + 0.25 * static_cast<double>(i + 1);
    CHECK(std::abs(0.5 * end.inferred[i].matched_node - x) <= 0.25 + 1e-9);
  }

  // A closure that disagrees (at 12 m instead of ~4.5 m) discards what waits
  // (no retries); a restart drops it as lost.
  options.inference.total_path_retries = 0;
  OdometricInference strict(graph, kernel, options);
  InferenceStep start, wait, wrong, dropped;
  const std::vector<Particle> at_4 = cloud_at(8);  // 4 m
  strict.Step(next, Pose2(), true, {8, 0.0, 1, 1.0}, at_4, 41, start);
  const int last = graph.AddNode(110, 110.0, 23.0, Pose2(), {});
  graph.AddEdge(next, last, u, EdgeType::kOdometry);
  strict.Step(last, u, false, {}, at_4, 41, wait);
  REQUIRE(wait.pending);
  strict.Restart(dropped);
  CHECK(dropped.reference_node == next);
  CHECK(dropped.lost.size() == 1);
  CHECK(dropped.lost_reason == DiscardReason::kSequenceBreak);
  CHECK(strict.particles().empty());
  strict.Step(last, Pose2(), true, {8, 0.0, 1, 1.0}, at_4, 41, start);
  strict.Step(last, u, false, {}, at_4, 41, wait);
  REQUIRE(wait.pending);
  strict.Step(last, u, true, {24, 0.0, 1, 1.0}, at_4, 41, wrong);
  CHECK(wrong.inferred.empty());
  CHECK(wrong.discarded.size() == 1);
}

}  // namespace
}  // namespace catgraph
