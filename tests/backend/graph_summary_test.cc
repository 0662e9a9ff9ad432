#include <sstream>

#include "tests/catch.h"

#include "backend/graph_summary.h"
#include "backend/io/graph_io.h"

namespace catgraph {
namespace {

AnyPoseGraph Read(const std::string& text) {
  std::istringstream in(text);
  return ReadGraph(in, "summary.g2o").graph;
}

TEST_CASE("the summary counts odometry, closures, switches and components", "[backend][summary]") {
  const auto g = Read(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\nVERTEX_SE2 3 3 0 0\n"
      "VERTEX_SE2 4 4 0 0\nVERTEX_SWITCH 5 1\n"
      "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 2 1 -1 0 0 1 0 0 1 0 1\n"
      "EDGE_SE2_SWITCHABLE 2 0 5 -2 0 0 1 0 0 1 0 1\nEDGE_SE2 3 4 1 0 0 1 0 0 1 0 1\n");
  const GraphSummary s = Summarize(g);
  CHECK(s.dimension == 2);
  CHECK(s.vertices == 5);
  CHECK(s.edges == 4);
  CHECK(s.odometry_edges == 3);  // 0-1, 2-1 (|i-j| = 1 either way) and 3-4
  CHECK(s.loop_closures == 1);
  CHECK(s.switchable_edges == 1);
  CHECK(s.switches == 1);
  CHECK(s.connected_components == 2);  // {0,1,2} and {3,4}
  CHECK_FALSE(s.connected);
  CHECK(s.edges_by_kind.at(ClosureKind::kOdometry) == 3);
  CHECK(s.edges_by_kind.at(ClosureKind::kUnknown) == 1);
  CHECK_FALSE(s.looks_like_square_root_information);
}

TEST_CASE("information of 44.7214 = sqrt(2000) raises the square-root warning, 2000 does not",
          "[backend][summary]") {
  const std::string vertices = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
  const GraphSummary sqrt_info =
      Summarize(Read(vertices + "EDGE_SE2 0 1 1 0 0 44.7214 0 0 44.7214 0 44.7214\n"));
  CHECK(sqrt_info.looks_like_square_root_information);
  CHECK(sqrt_info.square_root_information_example == "44.7214 = sqrt(2000)");
  CHECK_FALSE(Summarize(Read(vertices + "EDGE_SE2 0 1 1 0 0 2000 0 0 2000 0 2000\n"))
                  .looks_like_square_root_information);
  CHECK_FALSE(Summarize(Read(vertices + "EDGE_SE2 0 1 1 0 0 123.456 0 0 77.7 0 1\n"))
                  .looks_like_square_root_information);
}

TEST_CASE("indefinite coupling between positive-definite blocks is read and counted",
          "[backend][summary]") {
  // Translation block diag(1, 1), rotation 1, but x-theta coupling 5 makes
  // the whole matrix indefinite (as on 5021 edges of se-sync/cubicle.g2o).
  const GraphSummary s = Summarize(
      Read("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 5 1 0 1\n"));
  CHECK(s.indefinite_information_edges == 1);
}

}  // namespace
}  // namespace catgraph
