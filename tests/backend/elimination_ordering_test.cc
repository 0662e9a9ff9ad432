#include <algorithm>
#include <set>
#include <stdexcept>
#include <vector>

#include "tests/catch.h"

#include "backend/elimination_ordering.h"
#include "backend/factors.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

// A switchable solve's factor graph: odometry as between factors, every
// loop closure with a switch and a switch prior, the first pose constant.
struct SwitchableGraph {
  FactorGraph factors;
  Values values;
};

SwitchableGraph SwitchableGraphOf(const PoseGraph2& graph) {
  SwitchableGraph g;
  for (const auto& [id, vertex] : graph.vertices) g.values.Insert(id, vertex.pose.value_or(Pose2()));
  std::int64_t next_switch = 0;
  for (const auto& c : graph.constraints) {
    if (c.IsBetweenConsecutivePoses()) {
      g.factors.Emplace<BetweenFactor<Pose2>>(c.from, c.to, c.measurement);
      continue;
    }
    const SwitchId s(next_switch++);
    g.values.Insert(s, 1.0);
    g.factors.Emplace<SwitchableBetweenFactor<Pose2>>(c.from, c.to, s, c.measurement);
    g.factors.Emplace<SwitchPriorFactor>(s, SwitchPrior{});
  }
  g.factors.SetConstant(PoseKey(graph.vertices.begin()->first));
  return g;
}

PoseGraph2 WorldWithOutliers(int poses, int outliers) {
  ManhattanWorldOptions world;
  world.num_poses = poses;
  world.grid_cells = 20;
  world.seed = 3;
  PoseGraph2 graph = SimulateManhattanWorld(world).graph;
  OutlierOptions false_closures;
  false_closures.count = outliers;
  false_closures.seed = 3;
  InjectOutliers(graph, false_closures);
  return graph;
}

// The order Optimize() gives Ceres: FillReducingOrder's, or Ceres' own
// (minimum degree) where that is empty.
std::vector<Key> OrderUsed(const SwitchableGraph& g) {
  std::vector<Key> order = FillReducingOrder(g.factors, g.values);
  return order.empty() ? MinimumDegreeOrder(g.factors, g.values) : order;
}

TEST_CASE("the fill-reducing order lists every variable once, the switches first, and depends only on the factors",
          "[ordering]") {
  const PoseGraph2 world = WorldWithOutliers(2000, 100);
  const SwitchableGraph g = SwitchableGraphOf(world);
  const std::vector<Key> order = FillReducingOrder(g.factors, g.values);
  REQUIRE_FALSE(order.empty());
  const std::set<Key> listed(order.begin(), order.end());
  CHECK(order.size() == listed.size());
  CHECK(order.size() == g.values.size() - 1);
  CHECK_FALSE(listed.contains(PoseKey(world.vertices.begin()->first)));
  // A switch's elimination makes no fill: the switches come first, with at
  // most the poses at the trajectory's ends (one factor reads each, beside
  // the constant first pose).
  const auto switches = std::count_if(order.begin(), order.end(), [](Key k) { return k.type == KeyType::kSwitch; });
  const auto last_switch = std::find_if(order.rbegin(), order.rend(), [](Key k) { return k.type == KeyType::kSwitch; });
  CHECK(switches == std::count_if(world.constraints.begin(), world.constraints.end(),
                                  [](const auto& c) { return !c.IsBetweenConsecutivePoses(); }));
  CHECK(order.rend() - last_switch <= switches + 2);
  // The same factors give the same order, built again.
  const SwitchableGraph again = SwitchableGraphOf(world);
  CHECK(FillReducingOrder(again.factors, again.values) == order);
}

TEST_CASE("among random long closures the fill-reducing order's factor costs a fraction of minimum degree's, and "
          "never more",
          "[ordering]") {
  for (const int outliers : {0, 100, 400}) {
    CAPTURE(outliers);
    const SwitchableGraph g = SwitchableGraphOf(WorldWithOutliers(2000, outliers));
    const FactorFill ours = FillOf(g.factors, g.values, OrderUsed(g));
    const FactorFill minimum_degree = FillOf(g.factors, g.values, MinimumDegreeOrder(g.factors, g.values));
    REQUIRE(ours.flops > 0.0);
    REQUIRE(minimum_degree.flops > 0.0);
    CHECK(ours.nonzeros > 0.0);
    CHECK(ours.flops <= minimum_degree.flops);
    if (outliers >= 100) CHECK(ours.flops < 0.8 * minimum_degree.flops);
  }
}

TEST_CASE("an order that misses a variable or repeats one has no fill; a factor without a value is an error",
          "[ordering]") {
  SwitchableGraph g = SwitchableGraphOf(WorldWithOutliers(50, 0));
  std::vector<Key> order = MinimumDegreeOrder(g.factors, g.values);
  REQUIRE(FillOf(g.factors, g.values, order).flops > 0.0);
  order.back() = order.front();
  CHECK(FillOf(g.factors, g.values, order).flops == 0.0);
  order.pop_back();
  CHECK(FillOf(g.factors, g.values, order).flops == 0.0);

  g.factors.Emplace<SwitchPriorFactor>(SwitchId(999), SwitchPrior{});
  CHECK_THROWS_AS(FillReducingOrder(g.factors, g.values), std::invalid_argument);
}

TEST_CASE("a graph too small to gain, or whose every variable is constant, keeps Ceres' order", "[ordering]") {
  const SwitchableGraph small = SwitchableGraphOf(WorldWithOutliers(100, 10));
  CHECK(FillReducingOrder(small.factors, small.values).empty());

  Values values;
  values.Insert(PoseId(0), Pose2());
  values.Insert(PoseId(1), Pose2(1, 0, 0));
  FactorGraph graph;
  graph.Emplace<BetweenFactor<Pose2>>(PoseId(0), PoseId(1), RelativePoseMeasurement<Pose2>{Pose2(1, 0, 0)});
  graph.SetConstant(PoseKey(PoseId(0)));
  graph.SetConstant(PoseKey(PoseId(1)));
  CHECK(FillReducingOrder(graph, values).empty());
}

}  // namespace
}  // namespace catgraph
