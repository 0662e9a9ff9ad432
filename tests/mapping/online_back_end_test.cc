// The Mapper's online back end against the batch solve it stands for: a
// graph fed as it grows reaches the decisions and the map of one
// OptimizeWithHierarchy call on the whole, and the hierarchy's cascade turns
// the children of false visual closures off.
#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <vector>

#include "hierarchy/closure_hierarchy.h"
#include "mapping/mapper.h"
#include "mapping/online_back_end.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"
#include "tests/catch.h"

namespace catgraph::mapping {
namespace {

// A Manhattan world with false visual closures and the inferences hanging
// from them, its constraints in the order a robot meets them (by their later
// pose; parents before their children).
struct StreamedWorld {
  PoseGraph2 graph;
  std::set<ClosureId> injected;
  // A true closure recorded as the child of a false visual one: accepted on
  // its own, turned off by the hierarchy.
  ClosureId adopted;
};

StreamedWorld MakeWorld() {
  ManhattanWorldOptions world;
  world.num_poses = 400;
  world.seed = 3;
  StreamedWorld out;
  out.graph = SimulateManhattanWorld(world).graph;
  OutlierOptions outliers;
  outliers.policy = OutlierPolicy::kHierarchical;
  outliers.count = 30;
  outliers.group_size = 5;
  outliers.seed = 2;
  for (const InjectedClosure& c : InjectOutliers(out.graph, outliers)) out.injected.insert(c.id);
  auto later = [](const Constraint<Pose2>& c) { return std::max(c.from.value(), c.to.value()); };
  auto& constraints = out.graph.constraints;
  std::stable_sort(constraints.begin(), constraints.end(),
                   [&](const auto& a, const auto& b) { return later(a) < later(b); });
  const auto parent = std::find_if(constraints.begin(), constraints.end(),
                                   [](const auto& c) { return c.kind == ClosureKind::kVisual; });
  const auto child = std::find_if(parent, constraints.end(), [&](const auto& c) {
    return !c.IsBetweenConsecutivePoses() && !out.injected.contains(c.id);
  });
  REQUIRE(child != constraints.end());
  child->provenance.parents = {parent->id};
  out.adopted = child->id;
  return out;
}

TEST_CASE("the online back end, fed a graph as it grows, reaches the batch solve's decisions and map",
          "[mapping][online]") {
  const StreamedWorld world = MakeWorld();
  const PoseGraph2& whole = world.graph;
  // Each update runs to convergence, so that the last equals a batch solve.
  const PoseGraphOptimizerOptions options = OnlineSolveOptions(PoseGraphOptimizerOptions{}, 200);
  OnlineBackEnd online(options, HierarchyOptions{});
  PoseGraph2 prefix;
  std::size_t next = 0;
  int updates = 0;
  for (const auto& [id, vertex] : whole.vertices) {
    prefix.vertices.emplace(id, vertex);
    for (; next < whole.constraints.size() &&
           std::max(whole.constraints[next].from, whole.constraints[next].to) <= id;
         ++next) {
      prefix.constraints.push_back(whole.constraints[next]);
    }
    if (id.value() % 50 == 49) {
      const OnlineBackEnd::Solve solved = online.Update(prefix);
      REQUIRE(solved.summary.IsUsable());
      ++updates;
    }
  }
  REQUIRE(next == whole.constraints.size());
  REQUIRE(updates == 8);

  const HierarchicalOptimization batch =
      OptimizeWithHierarchy(AnyPoseGraph(whole), ClosureHierarchy::FromGraph(whole), options, HierarchyOptions{});
  REQUIRE(batch.optimization.summary.IsUsable());
  REQUIRE(online.decisions().size() == batch.optimization.closures.size());
  int false_accepted = 0;
  for (const ClosureDecision& d : batch.optimization.closures) {
    const ClosureDecision& o = online.decisions().at(d.id);
    CAPTURE(d.id.value(), d.weight, o.weight);
    CHECK(o.accepted == d.accepted);
    false_accepted += o.accepted && world.injected.contains(d.id) ? 1 : 0;
  }
  CHECK(false_accepted == 0);
  CHECK_FALSE(online.decisions().at(world.adopted).accepted);
  CHECK(online.decisions().at(world.adopted).weight == 0.0);
  CHECK(std::any_of(batch.turned_off.begin(), batch.turned_off.end(),
                    [&](const HierarchyDecision& d) { return d.child == world.adopted; }));
  const Trajectory2 poses = online.Poses();
  const PoseGraph2& solved = std::get<PoseGraph2>(batch.optimization.graph);
  double worst_m = 0.0;
  for (const auto& [id, vertex] : solved.vertices) {
    worst_m = std::max(worst_m, (poses.at(id).translation() - vertex.pose->translation()).norm());
  }
  CAPTURE(worst_m);
  CHECK(worst_m < 1e-3);
}

TEST_CASE("the online back end refuses what it cannot solve incrementally", "[mapping][online]") {
  const StreamedWorld world = MakeWorld();
  PoseGraphOptimizerOptions dcs = OnlineSolveOptions(PoseGraphOptimizerOptions{}, 3);
  dcs.method = RobustMethod::kDcs;
  CHECK_FALSE(OnlineBackEnd::Supports(dcs, HierarchyOptions{}));
  CHECK_THROWS_AS(OnlineBackEnd(dcs, HierarchyOptions{}), std::invalid_argument);
  const PoseGraphOptimizerOptions options = OnlineSolveOptions(PoseGraphOptimizerOptions{}, 3);
  CHECK_FALSE(OnlineBackEnd::Supports(options, HierarchyOptions{HierarchyPolicy::kCoupled, 50}));
  CHECK(OnlineBackEnd::Supports(options, HierarchyOptions{}));
  CHECK_FALSE(OnlineBackEnd::Supports(PoseGraphOptimizerOptions{}, HierarchyOptions{}));  // the offline stages

  OnlineBackEnd online(options, HierarchyOptions{});
  PoseGraph2 first = world.graph;
  first.constraints.resize(first.constraints.size() / 2);
  REQUIRE(online.Update(first).summary.IsUsable());
  PoseGraph2 shorter = first;
  shorter.constraints.pop_back();
  CHECK_THROWS_WITH(online.Update(shorter), Catch::Contains("does not extend"));
  PoseGraph2 switched = world.graph;
  switched.constraints[first.constraints.size()].switch_id = SwitchId(0);
  CHECK_THROWS_WITH(online.Update(switched), Catch::Contains("switch"));
}

}  // namespace
}  // namespace catgraph::mapping
