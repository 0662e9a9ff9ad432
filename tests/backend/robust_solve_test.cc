// The stages of the robust solve (backend/robust_solve.h) one by one, on
// simulated worlds with injected false closures: what each stage changes,
// and that running them by hand gives OptimizePoseGraph's answer.
#include <cstdint>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "tests/catch.h"

#include "backend/pose_graph_optimizer.h"
#include "backend/robust_solve.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

struct StageWorld {
  PoseGraph2 graph;
  std::set<ClosureId> injected;
  std::size_t closures = 0;  // loop closures, true and false
};

// A Manhattan world whose information is `information_factor` times what
// its noise has, with `outliers` false closures of the stated information.
StageWorld MakeWorld(int poses, double information_factor, int outliers, std::uint64_t seed) {
  ManhattanWorldOptions world;
  world.num_poses = poses;
  world.seed = seed;
  StageWorld out{SimulateManhattanWorld(world).graph, {}, 0};
  for (auto& c : out.graph.constraints) c.measurement.information *= information_factor;
  OutlierOptions o;
  o.count = outliers;
  o.seed = seed + 1;
  o.policy = OutlierPolicy::kLocal;
  for (const InjectedClosure& c : InjectOutliers(out.graph, o)) out.injected.insert(c.id);
  for (const auto& c : out.graph.constraints) out.closures += c.kind != ClosureKind::kOdometry;
  return out;
}

std::vector<std::string> StageNames(const PoseGraphOptimization& r) {
  std::vector<std::string> names;
  for (const StageTime& s : r.stages) names.push_back(s.stage);
  return names;
}

std::size_t FalseAccepted(const std::vector<ClosureDecision>& decisions, const std::set<ClosureId>& injected) {
  std::size_t n = 0;
  for (const ClosureDecision& d : decisions) n += d.accepted && injected.contains(d.id);
  return n;
}

TEST_CASE("stage by stage: the gate widens, switches are added, the robust solve decides, the refinement "
          "lowers the map's cost, and the result is OptimizePoseGraph's",
          "[backend][stages]") {
  // Information ten times what the noise has: the gate widens by ~10.
  const StageWorld world = MakeWorld(500, 10.0, 30, 7);
  const double gate = Gate<Pose2>(RelativePoseCostType::kG2o, 0.999);
  RobustSolve<Pose2> solve(world.graph, {});
  CHECK(solve.gate() == gate);

  solve.ScaleGate();
  const double factor = solve.result().gate_factor;
  CHECK(factor == solve.result().noise_scale.scale);
  CHECK(factor == Approx(10.0).epsilon(0.3));
  CHECK(solve.gate() == Approx(factor * gate));

  solve.Initialise();
  // A switch on every loop closure, its prior information the gate.
  CHECK(solve.graph().switches.size() == world.closures);
  for (const auto& [id, s] : solve.graph().switches) {
    REQUIRE(s.prior);
    CHECK(s.prior->information == solve.gate());
    CHECK(s.value == 1.0);
  }

  solve.SolveRobustly();
  const std::vector<ClosureDecision> robust = solve.result().closures;
  CHECK(robust.size() == world.closures);
  CHECK(FalseAccepted(robust, world.injected) == 0);

  // Overconfident information: the accepted closures' cycles show the noise
  // wider than stated, so the gate is not narrowed and nothing changes.
  solve.Narrow();
  CHECK(solve.result().narrow_factor == 1.0);
  CHECK_FALSE(solve.result().narrowed);

  // The refinement keeps the decisions and lowers the cost of the map
  // without the rejected closures (least squares from the robust poses).
  auto map_chi2 = [&] {
    return Chi2(DropRejected(AnyPoseGraph(solve.graph()), solve.result().closures));
  };
  const double before = map_chi2();
  solve.Refine();
  REQUIRE(solve.result().refinement);
  CHECK(solve.result().refinement->IsUsable());
  CHECK(map_chi2() <= before);
  for (std::size_t k = 0; k < robust.size(); ++k) CHECK(solve.result().closures[k].accepted == robust[k].accepted);

  solve.Readmit();
  CHECK(FalseAccepted(solve.result().closures, world.injected) == 0);
  const PoseGraphOptimization staged = solve.Finish();
  const std::vector<std::string> stages = {"noise_scale", "initial_guess", "robust_solve", "narrow",
                                           "refine",      "readmit",       "costs"};
  CHECK(StageNames(staged) == stages);

  // By hand as OptimizePoseGraph runs them: the same decisions and poses.
  const PoseGraphOptimization whole = OptimizePoseGraph(world.graph);
  REQUIRE(whole.closures.size() == staged.closures.size());
  for (std::size_t k = 0; k < whole.closures.size(); ++k) {
    CHECK(whole.closures[k].accepted == staged.closures[k].accepted);
    CHECK(whole.closures[k].weight == staged.closures[k].weight);
  }
  CHECK(whole.chi2 == staged.chi2);
  CHECK(whole.readmitted == staged.readmitted);
}

TEST_CASE("Initialise holds the disabled closures off and refuses closures the graph does not have",
          "[backend][stages]") {
  const StageWorld world = MakeWorld(200, 1.0, 5, 3);
  PoseGraphOptimizerOptions options;
  std::set<ClosureId> disabled;
  for (const auto& c : world.graph.constraints) {
    if (c.kind != ClosureKind::kOdometry && disabled.size() < 3) disabled.insert(c.id);
  }
  options.disabled_closures = disabled;
  RobustSolve<Pose2> solve(world.graph, options);
  solve.Initialise();
  std::size_t off = 0;
  for (const auto& c : solve.graph().constraints) {
    if (disabled.contains(c.id)) {
      REQUIRE(c.switch_id);
      CHECK(solve.graph().switches.at(*c.switch_id).value == 0.0);
      ++off;
    }
  }
  CHECK(off == disabled.size());
  solve.SolveRobustly();
  for (const ClosureDecision& d : solve.result().closures) {
    if (disabled.contains(d.id)) {
      CHECK_FALSE(d.accepted);
      CHECK(d.weight == 0.0);
    }
  }

  options.disabled_closures = {ClosureId(1'000'000)};
  RobustSolve<Pose2> unknown(world.graph, options);
  CHECK_THROWS_AS(unknown.Initialise(), std::invalid_argument);
  PoseGraphOptimizerOptions bad;
  bad.gate.probability = 1.5;
  CHECK_THROWS_AS(RobustSolve<Pose2>(world.graph, bad), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph
