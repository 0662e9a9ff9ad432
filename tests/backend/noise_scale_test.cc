#include <set>
#include <stdexcept>
#include <vector>

#include "tests/catch.h"

#include "backend/io/graph_io.h"
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

  // False closures, one for every six true ones, move the low quantile
  // little.
  PoseGraph2 spoiled = sim.graph;
  OutlierOptions outliers;
  outliers.count = 1500;
  outliers.policy = OutlierPolicy::kLocal;
  InjectOutliers(spoiled, outliers);
  CHECK(EstimateNoiseScale(spoiled).scale < 1.5);

  // Without closures there are no cycles and no estimate.
  PoseGraph2 chain = sim.graph;
  std::erase_if(chain.constraints, [](const auto& c) { return c.kind != ClosureKind::kOdometry; });
  const NoiseScaleEstimate none = EstimateNoiseScale(chain);
  CHECK(none.cycles == 0);
  CHECK(none.scale == 1.0);

  NoiseScaleOptions bad;
  bad.quantile = 1.0;
  CHECK_THROWS_AS(EstimateNoiseScale(sim.graph, bad), std::invalid_argument);
}

TEST_CASE("the gate widens by the measured noise scale on overconfident information, and only there",
          "[backend][noise-scale][switchable]") {
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
  fixed.estimate_noise_scale = false;
  const PoseGraphOptimization kept = OptimizePoseGraph(graph, fixed);
  CHECK(kept.gate_factor == 1.0);
  CHECK(testing::CountInjected(kept, injected).true_rejected > counts.true_closures / 10);

  // Right information: measured about 1, below the threshold; the gate stays.
  const PoseGraphOptimization right = OptimizePoseGraph(sim.graph);
  CHECK(right.noise_scale.scale < 1.5);
  CHECK(right.gate_factor == 1.0);
}

TEST_CASE("switchable constraints keep sphere_bignoise's closures: its information states a "
          "15th of its noise",
          "[backend][noise-scale][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const AnyPoseGraph sphere = ReadGraphFile(root / "se-sync/sphere_bignoise_vertex3.g2o").graph;
  const PoseGraphOptimization r = OptimizePoseGraph(sphere);
  REQUIRE(r.summary.IsUsable());
  CHECK(r.noise_scale.cycles == 400);
  CHECK(r.gate_factor == Approx(14.64).epsilon(0.01));
  // Measured 288 of 6448 (4.5 %); with the gate where the information puts
  // it, 6384. The noise is heavier-tailed than chi2(6) scaled.
  CHECK(r.rejected < 6448 / 20);
}

}  // namespace
}  // namespace catgraph
