// What the pose-graph pictures draw: every closure in its decision's and
// kind's series, counted in full in the legend, thinned evenly when many.
#include "apps/plot/graph_figure.h"

#include <string>

#include "tests/catch.h"

namespace catgraph::plot {
namespace {

// A line of `n` poses with `visual` accepted visual closures, `inferred`
// accepted inferred ones and `rejected` closures a solve turned off, each
// from pose k + 2 back to pose k.
PoseGraph2 GraphWith(int n, int visual, int inferred, int rejected) {
  PoseGraph2 g;
  for (int i = 0; i < n; ++i) g.vertices[PoseId(i)] = {PoseId(i), Pose2(i, 0.5 * i, 0.0), i == 0};
  int next = 0;
  auto add = [&](int from, int to, ClosureKind kind, bool accepted) {
    Constraint<Pose2> c;
    c.id = ClosureId(next++);
    c.from = PoseId(from);
    c.to = PoseId(to);
    c.kind = kind;
    if (!accepted) c.decision = RobustDecision{false, 0.01};
    g.constraints.push_back(c);
  };
  for (int i = 0; i + 1 < n; ++i) add(i, i + 1, ClosureKind::kOdometry, true);
  int k = 0;
  for (int i = 0; i < visual; ++i, ++k) add(k + 2, k, ClosureKind::kVisual, true);
  for (int i = 0; i < inferred; ++i, ++k) add(k + 2, k, ClosureKind::kOdometryInferred, true);
  for (int i = 0; i < rejected; ++i, ++k) add(k + 2, k, ClosureKind::kVisual, false);
  return g;
}

TEST_CASE("closures are drawn by decision and kind, thinned beyond the cap, counted in full", "[plot]") {
  const PoseGraph2 g = GraphWith(1000, 450, 30, 7);
  const std::vector<Series> series = ClosureSeries(g, TrajectoryOf(g));
  REQUIRE(series.size() == 3);  // rejected, visual, inferred (no closure of another kind)
  CHECK(series[0].label == "rejected closure (7)");
  CHECK(series[0].dashed);
  CHECK(series[0].x.size() == 2 * 7);
  CHECK(series[1].label == "visual closure (450, 1 in 3 drawn)");
  CHECK(series[1].x.size() == 2 * 150);
  CHECK(series[1].x.size() / 2 <= kMaxDrawnClosures);
  CHECK(series[2].label == "inferred closure (30)");
  // Endpoints are the poses given: closure k + 2 -> k of the first visual one.
  CHECK(series[1].x[0] == 2.0);
  CHECK(series[1].y[1] == 0.0);
  CHECK(series[1].color.g == kVisualClosureColor.g);
  CHECK(series[2].color.r == kInferredClosureColor.r);
}

TEST_CASE("a graph figure draws the closures first and the trajectory over them", "[plot]") {
  const PoseGraph2 g = GraphWith(20, 3, 0, 2);
  const Axes axes = GraphAxes(AnyPoseGraph(g), "t");
  REQUIRE(axes.series.size() == 3);
  CHECK(axes.series.back().label == "trajectory");
  CHECK(axes.series.back().x.size() == 20);
  CHECK(axes.equal_aspect);
  Trajectory2 missing = TrajectoryOf(g);
  missing.erase(PoseId(3));
  CHECK_THROWS_AS(ClosureSeries(g, missing), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph::plot
