// A pose graph built in code, GTSAM-style: a robot drives a 4 x 4 m square
// twice; one loop closure is true, one is a false match across the square.
// Each closure gets a switch (Suenderhauf & Protzel 2012) whose prior is the
// chi2 gate; the solver switches the false one off.
#include <cmath>
#include <cstdio>
#include <numbers>
#include <vector>

#include <catgraph/backend/chi_square.h>
#include <catgraph/backend/factors.h>
#include <catgraph/backend/optimizer.h>

namespace cg = catgraph;

int main() {
  cg::Values initial;
  cg::FactorGraph graph;
  // Odometry: 1 m forward, a 90-degree turn every 4 poses, 32 poses. Slightly
  // wrong (1.02 m per step), so that the initial guess drifts.
  const cg::Pose2 step(1.0, 0.0, 0.0), corner(1.0, 0.0, std::numbers::pi / 2);
  cg::Pose2 pose(0, 0, 0);
  initial.Insert(cg::PoseId(0), pose);
  for (int i = 1; i < 32; ++i) {
    const cg::Pose2& move = (i % 4 == 0) ? corner : step;
    cg::RelativePoseMeasurement<cg::Pose2> odometry{move};
    odometry.information.diagonal() << 100, 100, 400;  // 0.1 m, 0.05 rad
    graph.Emplace<cg::BetweenFactor<cg::Pose2>>(cg::PoseId(i - 1), cg::PoseId(i), odometry);
    pose = pose * cg::Pose2(1.02 * move.x(), move.y(), move.theta());
    initial.Insert(cg::PoseId(i), pose);
  }
  graph.SetConstant(cg::PoseKey(cg::PoseId(0)));

  // Two closures, each with a switch: pose 16 is where pose 0 was (true);
  // pose 22 "matches" pose 2 across the corner (false: they are 2.8 m apart).
  struct Closure {
    int from, to;
    cg::SwitchId id;
  };
  const std::vector<Closure> closures = {{0, 16, cg::SwitchId(1000)}, {2, 22, cg::SwitchId(1001)}};
  // The switch prior's information is the chi2 quantile: a closure is kept
  // (s > 0.5) exactly when its chi2 is below it.
  const double gate = cg::ChiSquareQuantile(3, 0.999);
  for (const Closure& c : closures) {
    cg::RelativePoseMeasurement<cg::Pose2> z{cg::Pose2(0, 0, 0)};
    z.information.diagonal() << 100, 100, 400;
    graph.Emplace<cg::SwitchableBetweenFactor<cg::Pose2>>(cg::PoseId(c.from), cg::PoseId(c.to), c.id, z);
    graph.Emplace<cg::SwitchPriorFactor>(c.id, cg::SwitchPrior{1.0, gate});
    initial.Insert(c.id, 1.0);
  }

  const cg::OptimizationResult result = cg::Optimize(graph, initial);
  std::printf("%s\n", result.summary.BriefReport().c_str());
  if (!result.summary.IsUsable()) return 1;
  for (const Closure& c : closures) {
    const double s = result.values.AtSwitch(c.id);
    std::printf("closure %2d -> %2d: switch %.3f, %s\n", c.from, c.to, s, s > 0.5 ? "accepted" : "rejected");
  }
  const cg::Pose2 end = result.values.AtPose2(cg::PoseId(16));
  std::printf("pose 16 at (%.3f, %.3f), where pose 0 is (0, 0)\n", end.x(), end.y());
  return 0;
}
