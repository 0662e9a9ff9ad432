#include <set>
#include <stdexcept>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "tests/catch.h"

#include "backend/chi_square.h"
#include "backend/evaluation.h"
#include "backend/graph/trajectory.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"
#include "backend/noise_scale.h"
#include "backend/pose_graph_optimizer.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

// Every edge's information times `factor`: the file then claims
// 1 / factor of the variance its measurements carry.
PoseGraph2 InformationTimes(PoseGraph2 graph, double factor) {
  for (auto& c : graph.constraints) c.measurement.information *= factor;
  return graph;
}

// A simulated world whose information states 100 times the noise's variance
// (Vertigo's Manhattan: about 45 times), spoiled by `count` false closures
// in local groups of 10. The false closures copy that information, so the
// gate in it lets in those whose pairs lie within about 2.8 m.
struct OverstatedWorld {
  PoseGraph2 right;  // the world with its information right, no false closures
  PoseGraph2 graph;
  std::vector<InjectedClosure> injected;
};

OverstatedWorld SimulateOverstatedWorld(int num_poses, std::uint64_t world_seed, int count,
                                        std::uint64_t outlier_seed) {
  ManhattanWorldOptions world;
  world.num_poses = num_poses;
  world.seed = world_seed;
  OverstatedWorld out;
  out.right = SimulateManhattanWorld(world).graph;
  out.graph = InformationTimes(out.right, 0.01);
  OutlierOptions outliers;
  outliers.count = count;
  outliers.policy = OutlierPolicy::kLocalGrouped;
  outliers.group_size = 10;
  outliers.seed = outlier_seed;
  out.injected = InjectOutliers(out.graph, outliers);
  return out;
}

TEST_CASE("short cycles measure how far the information understates the noise",
          "[backend][noise-scale]") {
  ManhattanWorldOptions world;
  world.num_poses = 2000;
  world.seed = 3;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  // The simulator's information is its noise's: about 1, and 400 cycles
  // put Q(0.25)'s sampling error near 7 %.
  const NoiseScaleEstimate right = EstimateNoiseScale(sim.graph);
  CHECK(right.cycles == 400);
  CHECK(right.scale == Approx(1.0).epsilon(0.25));
  CHECK(EstimateNoiseScale(InformationTimes(sim.graph, 10.0)).scale == Approx(10.0).epsilon(0.25));
  // Conservative information (a tenth of the information) reads below 1.
  CHECK(EstimateNoiseScale(InformationTimes(sim.graph, 0.1)).scale == Approx(0.1).epsilon(0.25));
  // Deterministic.
  CHECK(EstimateNoiseScale(sim.graph).scale == right.scale);
  // Gaussian noise of one variance: the upper quantile reads the same scale.
  CHECK(right.upper_scale == Approx(right.scale).epsilon(0.25));

  // False closures, one for every six true ones, move the low quantile
  // little.
  PoseGraph2 spoiled = sim.graph;
  OutlierOptions outliers;
  outliers.count = 1500;
  outliers.policy = OutlierPolicy::kLocal;
  std::set<ClosureId> injected;
  for (const InjectedClosure& c : InjectOutliers(spoiled, outliers)) injected.insert(c.id);
  const NoiseScaleEstimate with_false = EstimateNoiseScale(spoiled);
  CHECK(with_false.scale < 1.5);
  // Their cycles fill the upper quantile; left out of every cycle, they
  // leave the true closures' estimate.
  CHECK(with_false.upper_scale > 5.0);
  const NoiseScaleEstimate without = EstimateNoiseScale(spoiled, {}, injected);
  CHECK(without.upper_scale == Approx(right.upper_scale).epsilon(0.25));
  CHECK(without.scale == Approx(right.scale).epsilon(0.25));

  // Without closures there are no cycles and no estimate.
  PoseGraph2 chain = sim.graph;
  std::erase_if(chain.constraints, [](const auto& c) { return c.kind != ClosureKind::kOdometry; });
  const NoiseScaleEstimate none = EstimateNoiseScale(chain);
  CHECK(none.cycles == 0);
  CHECK(none.scale == 1.0);

  NoiseScaleOptions bad;
  bad.quantile = 1.0;
  CHECK_THROWS_AS(EstimateNoiseScale(sim.graph, bad), std::invalid_argument);
  bad.quantile = 0.5;
  bad.upper_quantile = 0.4;  // below the lower one
  CHECK_THROWS_AS(EstimateNoiseScale(sim.graph, bad), std::invalid_argument);
}

TEST_CASE("the gate widens by the measured noise scale on overconfident information, and only there",
          "[backend][noise-scale][switchable][slow]") {
  ManhattanWorldOptions world;
  world.num_poses = 1000;
  world.seed = 9;
  SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  OutlierOptions outliers;
  outliers.count = 50;
  outliers.seed = 3;
  // The false closures get the closures' stated information, so they stay
  // as far beyond the widened gate as beyond the right one.
  PoseGraph2 graph = InformationTimes(sim.graph, 10.0);
  std::set<ClosureId> injected;
  for (const InjectedClosure& c : InjectOutliers(graph, outliers)) injected.insert(c.id);

  const PoseGraphOptimization widened = OptimizePoseGraph(graph);
  REQUIRE(widened.summary.IsUsable());
  CHECK(widened.gate_factor == widened.noise_scale.scale);
  CHECK(widened.gate_factor == Approx(10.0).epsilon(0.25));
  const testing::InjectedDecisions counts = testing::CountInjected(widened, injected);
  CHECK(counts.false_accepted == 0);
  // As on the right information (the switchable gate test): at most 0.4 %.
  CHECK(counts.true_rejected <= counts.true_closures / 250);

  // The gate where the information puts it rejects a large share of them.
  PoseGraphOptimizerOptions fixed;
  fixed.gate.estimate_noise_scale = false;
  const PoseGraphOptimization kept = OptimizePoseGraph(graph, fixed);
  CHECK(kept.gate_factor == 1.0);
  CHECK(testing::CountInjected(kept, injected).true_rejected > counts.true_closures / 10);

  // Right information: measured about 1, below the threshold; the gate stays.
  const PoseGraphOptimization right = OptimizePoseGraph(sim.graph);
  CHECK(right.noise_scale.scale < 1.5);
  CHECK(right.gate_factor == 1.0);
}

TEST_CASE("information that overstates Gaussian noise: the accepted closures' cycles narrow the "
          "gate, and false closures near the truth are rejected with every true one kept",
          "[backend][noise-scale][switchable][slow]") {
  const OverstatedWorld world = SimulateOverstatedWorld(1500, 3, 500, 3);
  const PoseGraph2& graph = world.graph;
  std::set<ClosureId> injected;
  for (const InjectedClosure& c : world.injected) injected.insert(c.id);

  PoseGraphOptimizerOptions first_only;
  first_only.gate.narrow = false;
  first_only.readmission.enabled = false;  // the first solve's decisions alone
  const PoseGraphOptimization first = OptimizePoseGraph(graph, first_only);
  REQUIRE(first.summary.IsUsable());
  CHECK_FALSE(first.narrowed);
  CHECK(first.narrow_factor == 1.0);
  const testing::InjectedDecisions before = testing::CountInjected(first, injected);

  const PoseGraphOptimization r = OptimizePoseGraph(graph);
  REQUIRE(r.narrowed);
  REQUIRE(r.narrowed->IsUsable());
  CHECK(r.inlier_noise_scale.cycles == 400);
  CHECK(r.inlier_noise_scale.upper_scale == Approx(0.01).epsilon(0.25));
  // The calibrated gate: upper scale x the chi2(3) quantile at
  // 1 - 0.001 / n, n the closures the first solve accepted.
  const double tested = static_cast<double>(first.accepted);
  CHECK(r.narrow_factor * ChiSquareQuantile(3, 0.999) ==
        Approx(r.inlier_noise_scale.upper_scale * ChiSquareQuantile(3, 1.0 - 0.001 / tested)));
  const testing::InjectedDecisions after = testing::CountInjected(r, injected);
  CAPTURE(before.false_accepted, before.true_rejected, after.false_accepted, after.true_rejected);
  CHECK(before.false_accepted >= 10);  // 17 measured
  CHECK(after.false_accepted == 0);
  CHECK(after.true_rejected == 0);
  // What the first solve rejected stays rejected; the second rejected the
  // false closures the first let in, and nothing else.
  CHECK(r.rejected >= first.rejected);
  CHECK(r.narrow_newly_rejected == before.false_accepted - after.false_accepted +
                                       after.true_rejected - before.true_rejected);

  // A narrowed solve that rejects more than narrow_max_rejected_share of
  // what the first accepted is not kept (a first solve bent by many false
  // closures: docs/backend.md); here any share is too much.
  PoseGraphOptimizerOptions strict;
  strict.gate.narrow_max_rejected_share = 1e-9;
  const PoseGraphOptimization guarded = OptimizePoseGraph(graph, strict);
  REQUIRE(guarded.narrowed);
  CHECK(guarded.narrow_newly_rejected == r.narrow_newly_rejected);
  CHECK(guarded.narrow_factor == 1.0);
  CHECK(guarded.readmitted == 0);  // not after a narrowed solve, kept or not
  CHECK(guarded.accepted == first.accepted);
  CHECK(guarded.chi2 == Approx(first.chi2).epsilon(1e-9));

  // Right information: the calibrated gate is not a third of the first's.
  const PoseGraphOptimization right = OptimizePoseGraph(world.right);
  CHECK_FALSE(right.narrowed);
  CHECK(right.inlier_noise_scale.cycles == 400);
}

TEST_CASE("the narrowed solve keeps the hierarchy's policies: disabled closures stay off, coupled "
          "children follow their parents",
          "[backend][noise-scale][switchable]") {
  const OverstatedWorld world = SimulateOverstatedWorld(1500, 4, 300, 7);
  const PoseGraph2& graph = world.graph;
  PoseGraphOptimizerOptions options;
  std::set<ClosureId> injected;
  std::map<int, ClosureId> first_of_group;
  for (const InjectedClosure& c : world.injected) {
    injected.insert(c.id);
    // As the hierarchy couples an inferred closure to its visual parent.
    const auto [first, is_first] = first_of_group.emplace(c.group, c.id);
    if (!is_first) options.coupled_closures[c.id] = {first->second};
  }
  std::vector<ClosureId> true_closures;
  for (const auto& c : graph.constraints) {
    if (c.kind != ClosureKind::kOdometry && !injected.contains(c.id)) true_closures.push_back(c.id);
  }
  REQUIRE(true_closures.size() > 100);
  for (std::size_t k = 0; k < 5; ++k) options.disabled_closures.insert(true_closures[k * 20]);
  // A true closure coupled to another true one stays on with it.
  options.coupled_closures[true_closures[1]] = {true_closures[2]};

  const PoseGraphOptimization r = OptimizePoseGraph(graph, options);
  REQUIRE(r.summary.IsUsable());
  REQUIRE(r.narrowed);
  REQUIRE(r.narrowed->IsUsable());
  CHECK(r.narrow_factor < 1.0 / 3.0);
  std::map<ClosureId, bool> accepted;
  for (const ClosureDecision& d : r.closures) accepted[d.id] = d.accepted;
  for (const ClosureDecision& d : r.closures) {
    CAPTURE(d.id.value());
    if (options.disabled_closures.contains(d.id)) {
      CHECK_FALSE(d.accepted);
      CHECK(d.weight == 0.0);
    }
    if (const auto coupled = options.coupled_closures.find(d.id); coupled != options.coupled_closures.end()) {
      for (const ClosureId parent : coupled->second) {
        if (!accepted.at(parent)) CHECK_FALSE(d.accepted);
      }
    }
  }
  const testing::InjectedDecisions counts = testing::CountInjected(r, injected);
  CHECK(counts.false_accepted == 0);
  CHECK(counts.true_rejected == options.disabled_closures.size());
  CHECK(accepted.at(true_closures[1]));
}

TEST_CASE("true closures with heavier tails than one Gaussian keep the first gate",
          "[backend][noise-scale][switchable][slow]") {
  ManhattanWorldOptions world;
  world.num_poses = 2000;
  world.seed = 3;
  SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  // One closure in five carries noise 4 times the rest's (sigma), as a real
  // front end's matches do now and then; the information is conservative
  // for all of them.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> metres(0.0, 4.0 * world.closure_sigma_m);
  std::normal_distribution<double> radians(0.0, 4.0 * world.closure_sigma_rad);
  int k = 0;
  for (auto& c : sim.graph.constraints) {
    if (c.kind == ClosureKind::kOdometry || ++k % 5 != 0) continue;
    c.measurement.mean = c.measurement.mean * Pose2(metres(rng), metres(rng), radians(rng));
  }
  const PoseGraphOptimization r = OptimizePoseGraph(InformationTimes(sim.graph, 0.01));
  REQUIRE(r.summary.IsUsable());
  CAPTURE(r.inlier_noise_scale.scale, r.inlier_noise_scale.upper_scale);
  CHECK(r.inlier_noise_scale.upper_scale > 1.25 * r.inlier_noise_scale.scale);
  CHECK_FALSE(r.narrowed);
  CHECK(r.rejected == 0);
}

TEST_CASE("switchable constraints keep sphere_bignoise's closures: its information states a "
          "15th of its noise",
          "[backend][noise-scale][shared][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const AnyPoseGraph sphere = ReadGraphFile(root / "se-sync/sphere_bignoise_vertex3.g2o").graph;
  const PoseGraphOptimization r = OptimizePoseGraph(sphere);
  REQUIRE(r.summary.IsUsable());
  CHECK(r.noise_scale.cycles == 400);
  CHECK(r.gate_factor == Approx(14.64).epsilon(0.01));
  // The robust solve rejects 288 of 6448 (4.5 %); with the gate where the
  // information puts it, 6384. The noise is heavier-tailed than chi2(6)
  // scaled. Readmission, at the widened family-wise gate, brings back all
  // but 6 (measured).
  CHECK(r.readmitted > 250);
  CHECK(r.rejected <= 10);
}

TEST_CASE("Vertigo's Manhattan + 1000 outliers: the narrowed gate rejects the local ones the first "
          "gate let in, and the map is the outlier-free one",
          "[backend][noise-scale][shared][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const auto manhattan = root / "vertigo/manhattan";
  const auto clean =
      std::get<PoseGraph2>(ReadGraphFile(manhattan / "originalDataset/g2o/manhattanOlson3500.g2o").graph);
  const AnyTrajectory truth =
      ReadTrajectoryFile(manhattan / "groundTruth/manhattanOlson3500_nodes_groundTruth.dat");
  // Its information states about 45 times the noise, which is Gaussian.
  const PoseGraphOptimization plain = OptimizePoseGraph(clean);
  REQUIRE(plain.narrow_factor < 1.0 / 3.0);
  CHECK(plain.rejected == 0);
  CHECK(plain.inlier_noise_scale.upper_scale == Approx(0.022).epsilon(0.1));
  const double clean_ate = EvaluateTrajectory(TrajectoryOf(plain.graph), truth).ate_m.rmse;
  CHECK(clean_ate == Approx(0.794).margin(0.002));

  struct Case {
    OutlierPolicy policy;
    int group_size;
    std::uint64_t seed;
  };
  // The seeds that missed before the narrowing (docs/backend.md): ATE
  // 1.082 m, 98.19 % and 98.6 % of the outliers rejected.
  for (const Case& k : {Case{OutlierPolicy::kLocalGrouped, 10, 3}, Case{OutlierPolicy::kLocalGrouped, 10, 2},
                        Case{OutlierPolicy::kLocal, 1, 5}}) {
    PoseGraph2 graph = clean;
    OutlierOptions outliers;
    outliers.count = 1000;
    outliers.policy = k.policy;
    outliers.group_size = k.group_size;
    outliers.seed = k.seed;
    std::set<ClosureId> injected;
    for (const InjectedClosure& c : InjectOutliers(graph, outliers)) injected.insert(c.id);
    const PoseGraphOptimization r = OptimizePoseGraph(graph);
    REQUIRE(r.summary.IsUsable());
    const testing::InjectedDecisions counts = testing::CountInjected(r, injected);
    const double ate = EvaluateTrajectory(TrajectoryOf(r.graph), truth).ate_m.rmse;
    CAPTURE(static_cast<int>(k.policy), k.seed, counts.false_accepted, counts.true_rejected, ate);
    CHECK(r.narrow_factor < 1.0 / 3.0);
    CHECK(counts.false_accepted <= 10);  // >= 99 % rejected; measured 0, 0, 2
    CHECK(counts.true_rejected <= counts.true_closures / 100);
    CHECK(ate <= 1.05 * clean_ate);
  }
}

// Both files' closures are all true. Their heavier tails keep the first
// gate, which rejects 3 of Intel's 895 and 22 of Manhattan's 1954; tested
// by their innovation against the refined map, every one is readmitted
// (Manhattan's last one in the second round).
TEST_CASE("real front ends' heavier tails keep the first gate, and readmission keeps every closure of "
          "Vertigo's Intel and SE-Sync's Manhattan",
          "[backend][noise-scale][readmit][shared][slow]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  for (const auto& [file, gated] : {std::pair{"vertigo/intel/originalDataset/intel.g2o", 3},
                                    std::pair{"se-sync/manhattan.g2o", 22}}) {
    const AnyPoseGraph graph = ReadGraphFile(root / file).graph;
    const PoseGraphOptimization r = OptimizePoseGraph(graph);
    REQUIRE(r.summary.IsUsable());
    CAPTURE(file, r.inlier_noise_scale.scale, r.inlier_noise_scale.upper_scale);
    CHECK(r.inlier_noise_scale.cycles == 400);
    // Measured 1.86 and 2.55.
    CHECK(r.inlier_noise_scale.upper_scale > 1.5 * r.inlier_noise_scale.scale);
    CHECK_FALSE(r.narrowed);
    CHECK(r.rejected == 0);
    CHECK(r.readmitted == static_cast<std::size_t>(gated));
    REQUIRE(r.readmission);
    PoseGraphOptimizerOptions gate_only;
    gate_only.readmission.enabled = false;
    const PoseGraphOptimization g = OptimizePoseGraph(graph, gate_only);
    CHECK(g.rejected == static_cast<std::size_t>(gated));
    CHECK(g.readmitted == 0);
    // Every closure in: the plain least-squares map (its chi2 without the
    // switches, the notes' 546.46 for Intel).
    PoseGraphOptimizerOptions plain;
    plain.method = RobustMethod::kNone;
    CHECK(Chi2(DropRejected(r.graph, r.closures)) == Approx(OptimizePoseGraph(graph, plain).chi2).epsilon(1e-6));
  }
}

}  // namespace
}  // namespace catgraph
