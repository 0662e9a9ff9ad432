#include <sstream>

#include "tests/catch.h"

#include "backend/graph_summary.h"
#include "backend/io/graph_io.h"
#include "simulation/manhattan_world.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

std::string AsG2o(const PoseGraph2& g) {
  std::ostringstream out;
  WriteG2o(g, out);
  return out.str();
}

TEST_CASE("the same seed gives the same graph and another seed a different one",
          "[simulation]") {
  ManhattanWorldOptions options;
  options.num_poses = 300;
  const std::string a = AsG2o(SimulateManhattanWorld(options).graph);
  CHECK(a == AsG2o(SimulateManhattanWorld(options).graph));
  options.seed = 2;
  CHECK(a != AsG2o(SimulateManhattanWorld(options).graph));
}

TEST_CASE("the ground truth is consistent and the noise has the stated covariance",
          "[simulation]") {
  ManhattanWorldOptions options;
  options.num_poses = 2000;
  options.seed = 3;
  const SimulatedPoseGraph2 sim = SimulateManhattanWorld(options);
  const GraphSummary s = Summarize(sim.graph);
  CHECK(s.vertices == 2000);
  CHECK(s.odometry_edges == 1999);
  CHECK(s.loop_closures > 100);
  CHECK(s.connected);
  REQUIRE(sim.truth.constraints.size() == sim.graph.constraints.size());
  double chi2 = 0.0;
  for (std::size_t k = 0; k < sim.graph.constraints.size(); ++k) {
    const auto& truth_edge = sim.truth.constraints[k];
    const Pose2& from = *sim.truth.vertices.at(truth_edge.from).pose;
    const Pose2& to = *sim.truth.vertices.at(truth_edge.to).pose;
    // Exact measurements agree with the true poses.
    REQUIRE(testing::ApproxEqual(truth_edge.measurement.mean, from.Between(to), 1e-9));
    // Noisy ones scatter with the stated information: E[chi2] = 3 per edge.
    const auto& edge = sim.graph.constraints[k];
    const Eigen::Vector3d e = truth_edge.measurement.mean.Between(edge.measurement.mean).ToVector();
    chi2 += e.dot(edge.measurement.information * e);
  }
  const double dof = 3.0 * static_cast<double>(sim.graph.constraints.size());
  // chi2 over n dof has standard deviation sqrt(2n); allow 5 of them.
  CHECK(std::abs(chi2 - dof) < 5.0 * std::sqrt(2.0 * dof));
  // The walk stays on the grid, in the square.
  for (const auto& [id, v] : sim.truth.vertices) {
    REQUIRE(std::abs(v.pose->x()) <= options.grid_cells / 2 * options.grid_step_m + 1e-9);
    REQUIRE(std::abs(v.pose->y()) <= options.grid_cells / 2 * options.grid_step_m + 1e-9);
  }
  // The initial guess is the chained noisy odometry: it drifts but starts at the origin.
  CHECK(testing::ApproxEqual(*sim.graph.vertices.at(PoseId(0)).pose, Pose2()));
  CHECK(sim.graph.vertices.at(PoseId(0)).fixed);
}

TEST_CASE("invalid simulation options name the field", "[simulation]") {
  ManhattanWorldOptions options;
  options.num_poses = 1;
  CHECK_THROWS_WITH(SimulateManhattanWorld(options), Catch::Contains("num_poses"));
  options = {};
  options.odometry_sigma_m = 0.0;
  CHECK_THROWS_WITH(SimulateManhattanWorld(options), Catch::Contains("odometry_sigma_m"));
}

TEST_CASE("a world's expected edges are near the generated count, and a world expected to exceed the bound is "
          "refused before it is built",
          "[simulation]") {
  for (const int cells : {10, 30}) {
    ManhattanWorldOptions options;
    options.num_poses = 5000;
    options.grid_cells = cells;
    const double generated = static_cast<double>(SimulateManhattanWorld(options).graph.constraints.size());
    CAPTURE(cells, generated);
    CHECK(ExpectedManhattanEdges(options) == Approx(generated).epsilon(0.15));
  }
  ManhattanWorldOptions options;
  options.num_poses = 60'000;  // on the default 10-step square: about 9 million edges
  CHECK_THROWS_WITH(SimulateManhattanWorld(options), Catch::Contains("widen the square"));
  options.grid_cells = 300;  // about 80,000
  CHECK_NOTHROW(Validate(options));
}

}  // namespace
}  // namespace catgraph
