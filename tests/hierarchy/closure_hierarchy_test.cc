// The closure hierarchy: the record, the pure decision rule, and the three
// policies on a simulated graph with false visual closures and their
// odometry-inferred children.
#include <algorithm>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "tests/catch.h"

#include "hierarchy/closure_hierarchy.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

ClosureId C(int id) { return ClosureId(id); }

TEST_CASE("hierarchy record: parents, ancestors nearest first, children, cycles refused", "[hierarchy]") {
  ClosureHierarchy h;
  h.Add(C(10), {C(1), C(2)});
  h.Add(C(20), {C(10)});
  h.Add(C(21), {C(10), C(2)});
  h.Add(C(10), {C(2)});  // already recorded: no duplicate
  CHECK(h.ParentsOf(C(10)) == std::vector<ClosureId>{C(1), C(2)});
  CHECK(h.ParentsOf(C(1)).empty());
  CHECK(h.AncestorsOf(C(21)) == std::vector<ClosureId>{C(10), C(2), C(1)});
  CHECK(h.ChildrenOf(C(10)) == std::vector<ClosureId>{C(20), C(21)});
  CHECK(h.ChildrenOf(C(2)) == std::vector<ClosureId>{C(10), C(21)});
  CHECK(h.NumChildren() == 3);
  CHECK_THROWS_AS(h.Add(C(1), {C(20)}), std::invalid_argument);  // 1 <- 20 <- 10 <- 1
  CHECK_THROWS_AS(h.Add(C(5), {C(5)}), std::invalid_argument);
  CHECK(h.ParentsOf(C(1)).empty());  // the refused edge left no trace

  PoseGraph2 graph;
  for (int i = 0; i < 3; ++i) graph.vertices[PoseId(i)] = {PoseId(i), Pose2(i, 0, 0)};
  graph.constraints.push_back({C(0), PoseId(0), PoseId(2), {}, ClosureKind::kVisual, {}, {}, {}, {}});
  graph.constraints.push_back({C(1), PoseId(0), PoseId(1), {}, ClosureKind::kOdometryInferred, {{C(0)}}, {}, {}, {}});
  CHECK(ClosureHierarchy::FromGraph(AnyPoseGraph(graph)).ParentsOf(C(1)) == std::vector<ClosureId>{C(0)});
  graph.constraints.push_back({C(2), PoseId(1), PoseId(2), {}, ClosureKind::kOdometryInferred, {{C(7)}}, {}, {}, {}});
  CHECK_THROWS_AS(ClosureHierarchy::FromGraph(AnyPoseGraph(graph)), std::invalid_argument);
}

TEST_CASE("PropagateRejections turns off every child of an off parent, transitively, and nothing else",
          "[hierarchy]") {
  std::mt19937_64 rng(81);
  for (int trial = 0; trial < 300; ++trial) {
    // A random forest of dependencies over 30 closures: parents have smaller ids.
    ClosureHierarchy h;
    std::map<ClosureId, bool> accepted;
    std::set<ClosureId> already_off;
    for (int id = 0; id < 30; ++id) {
      if (id > 0 && rng() % 2 == 0) {
        std::vector<ClosureId> parents;
        for (int k = 0, n = 1 + static_cast<int>(rng() % 2); k < n; ++k) parents.push_back(C(static_cast<int>(rng() % id)));
        h.Add(C(id), parents);
      }
      if (rng() % 4 == 0) accepted[C(id)] = false;
      else if (rng() % 3 != 0) accepted[C(id)] = true;  // else absent: counts as accepted
      if (rng() % 10 == 0) already_off.insert(C(id));
    }
    const std::vector<HierarchyDecision> decisions = PropagateRejections(h, accepted, already_off);

    // Reference: a closure is off when rejected, already off, or a parent is off.
    std::function<bool(ClosureId)> off = [&](ClosureId c) {
      const auto found = accepted.find(c);
      if ((found != accepted.end() && !found->second) || already_off.contains(c)) return true;
      const auto& parents = h.ParentsOf(c);
      return std::any_of(parents.begin(), parents.end(), off);
    };
    std::set<ClosureId> expected;
    for (int id = 0; id < 30; ++id) {
      const auto found = accepted.find(C(id));
      const bool on_by_itself = (found == accepted.end() || found->second) && !already_off.contains(C(id));
      if (on_by_itself && off(C(id))) expected.insert(C(id));
    }
    std::set<ClosureId> decided;
    for (const HierarchyDecision& d : decisions) {
      CHECK(decided.insert(d.child).second);  // each child once
      const auto& parents = h.ParentsOf(d.child);
      CHECK(std::find(parents.begin(), parents.end(), d.parent) != parents.end());
      CHECK(off(d.parent));
    }
    REQUIRE(decided == expected);
  }
}

// Manhattan world with false visual closures, each with odometry-inferred
// children consistent with it (the hierarchical injection). The children are
// given a weak information, as inferences after a long odometry stretch
// would carry, so that alone each passes the switch's chi2 gate: only the
// hierarchy can turn them off.
struct Scenario {
  AnyPoseGraph graph;
  std::set<ClosureId> false_parents, false_children;
};

Scenario MakeScenario() {
  ManhattanWorldOptions world;
  world.num_poses = 400;
  world.seed = 5;
  SimulatedPoseGraph2 sim = SimulateManhattanWorld(world);
  OutlierOptions outliers;
  outliers.policy = OutlierPolicy::kHierarchical;
  outliers.count = 24;
  outliers.group_size = 6;
  outliers.seed = 3;
  Scenario s;
  for (const InjectedClosure& c : InjectOutliers(sim.graph, outliers)) {
    (c.parent ? s.false_children : s.false_parents).insert(c.id);
  }
  for (auto& c : sim.graph.constraints) {
    if (s.false_children.contains(c.id)) c.measurement.information *= 1e-4;
  }
  s.graph = sim.graph;
  return s;
}

std::set<ClosureId> Accepted(const HierarchicalOptimization& r) {
  std::set<ClosureId> ids;
  for (const ClosureDecision& d : r.optimization.closures) {
    if (d.accepted) ids.insert(d.id);
  }
  return ids;
}

TEST_CASE("cascade and coupled turn off the children of rejected false parents, flat lets them survive",
          "[hierarchy][optimizer]") {
  const Scenario s = MakeScenario();
  const ClosureHierarchy h = ClosureHierarchy::FromGraph(s.graph);
  REQUIRE(h.NumChildren() == s.false_children.size());
  const PoseGraphOptimizerOptions options;  // switchable, defaults

  std::map<HierarchyPolicy, HierarchicalOptimization> results;
  for (HierarchyPolicy policy : {HierarchyPolicy::kFlat, HierarchyPolicy::kCascade, HierarchyPolicy::kCoupled}) {
    results[policy] = OptimizeWithHierarchy(s.graph, h, options, {policy});
    const HierarchicalOptimization& r = results[policy];
    INFO(ToString(policy));
    REQUIRE(r.optimization.summary.IsUsable());
    // Every false parent rejected; the true closures accepted, up to the
    // chi2 gate's own rate (0.1 % of true closures lie beyond it).
    int true_closures = 0, true_accepted = 0;
    for (const ClosureDecision& d : r.optimization.closures) {
      if (s.false_parents.contains(d.id)) CHECK_FALSE(d.accepted);
      if (s.false_parents.contains(d.id) || s.false_children.contains(d.id)) continue;
      ++true_closures;
      true_accepted += d.accepted ? 1 : 0;
    }
    CHECK(true_accepted >= 0.99 * true_closures);
  }
  // The hierarchy changes nothing about closures without parents.
  for (const ClosureDecision& d : results[HierarchyPolicy::kFlat].optimization.closures) {
    if (s.false_children.contains(d.id)) continue;
    for (HierarchyPolicy policy : {HierarchyPolicy::kCascade, HierarchyPolicy::kCoupled}) {
      CHECK(Accepted(results[policy]).contains(d.id) == d.accepted);
    }
  }
  // Flat: the weak children pass on their own.
  const HierarchicalOptimization& flat = results[HierarchyPolicy::kFlat];
  CHECK(flat.turned_off.empty());
  CHECK(flat.surviving_children.size() >= s.false_children.size() / 2);
  for (const HierarchyDecision& d : flat.surviving_children) {
    CHECK(s.false_children.contains(d.child));
    CHECK(Accepted(flat).contains(d.child));
  }
  // Cascade and coupled: every child of a rejected parent ends off, and the
  // hierarchy turned off nothing but such children.
  for (HierarchyPolicy policy : {HierarchyPolicy::kCascade, HierarchyPolicy::kCoupled}) {
    const HierarchicalOptimization& r = results[policy];
    INFO(ToString(policy));
    CHECK(r.surviving_children.empty());
    for (const ClosureId child : s.false_children) CHECK_FALSE(Accepted(r).contains(child));
    std::visit(
        [&](const auto& g) {
          for (const auto& c : g.constraints) {
            if (s.false_children.contains(c.id)) CHECK(g.switches.at(*c.switch_id).value == 0.0);
          }
        },
        r.optimization.graph);
    CHECK_FALSE(r.turned_off.empty());
    for (const HierarchyDecision& d : r.turned_off) {
      CHECK(s.false_children.contains(d.child));
      CHECK(s.false_parents.contains(d.parent));
    }
  }
  CHECK(results[HierarchyPolicy::kCascade].solves == 2);
  CHECK(results[HierarchyPolicy::kCoupled].solves == 1);
  CHECK(Accepted(results[HierarchyPolicy::kCascade]) == Accepted(results[HierarchyPolicy::kCoupled]));
}

TEST_CASE("coupled needs switches, bad options are refused", "[hierarchy]") {
  const Scenario s = MakeScenario();
  const ClosureHierarchy h = ClosureHierarchy::FromGraph(s.graph);
  PoseGraphOptimizerOptions dcs;
  dcs.method = RobustMethod::kDcs;
  CHECK_THROWS_AS(OptimizeWithHierarchy(s.graph, h, dcs, {HierarchyPolicy::kCoupled}), std::invalid_argument);
  CHECK_THROWS_AS(OptimizeWithHierarchy(s.graph, h, {}, {HierarchyPolicy::kCascade, 0}), std::invalid_argument);
  CHECK(HierarchyPolicyFromString("coupled") == HierarchyPolicy::kCoupled);
  CHECK_FALSE(HierarchyPolicyFromString("tree").has_value());
}

}  // namespace
}  // namespace catgraph
