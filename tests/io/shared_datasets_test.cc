// Every shared benchmark graph reads without error, matches the counts of
// ../shared/datasets/pose-graphs/README.md, and round-trips through the g2o
// writer. Skipped with a message when the shared folder is absent.
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "tests/catch.h"

#include "backend/graph_summary.h"
#include "backend/io/graph_io.h"
#include "tests/io/graph_equality.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

struct Expected {
  const char* path;
  GraphFormat format;
  int dimension;
  std::size_t vertices;
  std::size_t edges;
  long odometry;        // -1: the README does not say
  long loop_closures;   // -1: the README does not say
  std::size_t without_pose;
  bool square_root_information;  // the README's warning 1
};

// The README's table; "edges only" files imply their vertices.
const std::vector<Expected> kFiles = {
    {"vertigo/manhattan/originalDataset/Olson/manhattanOlson3500.g2o", GraphFormat::kG2o, 2, 3500, 5598, 3499, 2099, 0, true},
    {"vertigo/manhattan/originalDataset/g2o/manhattanOlson3500.g2o", GraphFormat::kG2o, 2, 3500, 5598, 3499, 2099, 0, true},
    {"vertigo/intel/originalDataset/intel.g2o", GraphFormat::kG2o, 2, 943, 1837, 942, 895, 0, false},
    {"vertigo/ring/originalDataset/ring.g2o", GraphFormat::kG2o, 2, 434, 459, 433, 26, 0, false},
    {"vertigo/ring/groundTruth/ring.g2o", GraphFormat::kG2o, 2, 434, 459, 433, 26, 0, false},
    {"se-sync/manhattan.g2o", GraphFormat::kG2o, 2, 3500, 5453, 3499, 1954, 3500, false},
    {"se-sync/CSAIL.g2o", GraphFormat::kG2o, 2, 1045, 1172, 1044, 128, 1045, false},
    {"se-sync/intel.g2o", GraphFormat::kG2o, 2, 1728, 2512, 1727, 785, 0, false},
    {"se-sync/MIT.g2o", GraphFormat::kG2o, 2, 808, 827, 807, 20, 0, false},
    {"se-sync/ais2klinik.g2o", GraphFormat::kG2o, 2, 15115, 16727, 15113, 1614, 0, false},
    {"se-sync/kitti_00.g2o", GraphFormat::kG2o, 2, 4541, 4677, 4540, 137, 4541, false},
    {"se-sync/kitti_02.g2o", GraphFormat::kG2o, 2, 4661, 4703, 4660, 43, 4661, false},
    {"se-sync/kitti_05.g2o", GraphFormat::kG2o, 2, 2761, 2826, 2760, 66, 2761, false},
    {"se-sync/parking-garage.g2o", GraphFormat::kG2o, 3, 1661, 6275, 1660, 4615, 0, false},
    {"se-sync/cubicle.g2o", GraphFormat::kG2o, 3, 5750, 16869, 9248, 7621, 0, false},
    {"se-sync/torus3D.g2o", GraphFormat::kG2o, 3, 5000, 9048, 4999, 4049, 0, false},
    {"se-sync/sphere_bignoise_vertex3.g2o", GraphFormat::kG2o, 3, 2200, 8647, 2199, 6448, 0, false},
    {"se-sync/smallGrid3D.g2o", GraphFormat::kG2o, 3, 125, 297, -1, -1, 0, false},
    {"se-sync/tinyGrid3D.g2o", GraphFormat::kG2o, 3, 9, 11, -1, -1, 0, false},
    {"carlone/input_M3500_g2o.g2o", GraphFormat::kG2o, 2, 3500, 5453, 3499, 1954, 0, true},
    {"carlone/input_M3500b_g2o.g2o", GraphFormat::kG2o, 2, 3500, 5453, -1, -1, 0, true},  // same 44.72
    {"carlone/input_INTEL_g2o.g2o", GraphFormat::kG2o, 2, 1228, 1483, 1227, 256, 0, false},
    {"carlone/CSAIL_P_toro.graph", GraphFormat::kToro, 2, 1045, 1172, 1044, 128, 0, false},
    {"carlone/FR079_P_toro.graph", GraphFormat::kToro, 2, 989, 1217, 988, 229, 0, false},
    {"carlone/FRH_P_toro.graph", GraphFormat::kToro, 2, 1316, 2820, 1315, 1505, 0, false},
    {"isam-groundtruth/manhattanOlson3500_groundtruth.txt", GraphFormat::kIsam, 2, 3500, 5598, 3499, 2099, 3500, false},
};

TEST_CASE("every shared pose graph reads with the README's counts and round-trips",
          "[io][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  for (const Expected& e : kFiles) {
    SECTION(e.path) {
      const GraphFile file = ReadGraphFile(root / e.path);
      const GraphSummary s = Summarize(file.graph);
      CHECK(file.format == e.format);
      CHECK(s.dimension == e.dimension);
      CHECK(s.vertices == e.vertices);
      CHECK(s.edges == e.edges);
      if (e.odometry >= 0) CHECK(s.odometry_edges == static_cast<std::size_t>(e.odometry));
      if (e.loop_closures >= 0) CHECK(s.loop_closures == static_cast<std::size_t>(e.loop_closures));
      CHECK(s.vertices_without_pose == e.without_pose);
      CHECK(s.connected);
      // Only cubicle has indefinite coupling between positive-definite blocks.
      CHECK((s.indefinite_information_edges > 0) == (std::string(e.path) == "se-sync/cubicle.g2o"));
      CHECK(s.looks_like_square_root_information == e.square_root_information);
      std::ostringstream out;
      WriteG2o(file.graph, out);
      std::istringstream in(out.str());
      CHECK(testing::GraphsEqual(file.graph, ReadGraph(in, "roundtrip.g2o").graph));
    }
  }
}

TEST_CASE("the iSAM ground truth squares 50 and 100 into information 2500 and 10000",
          "[io][shared]") {
  CATGRAPH_SHARED_POSE_GRAPHS_OR_SKIP(root);
  const GraphFile file = ReadGraphFile(root / "isam-groundtruth/manhattanOlson3500_groundtruth.txt");
  const auto& c = std::get<PoseGraph2>(file.graph).constraints.front();
  CHECK(c.measurement.information(0, 0) == Approx(2500.0));
  CHECK(c.measurement.information(2, 2) == Approx(10000.0));
}

}  // namespace
}  // namespace catgraph
