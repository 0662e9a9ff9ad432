#include <filesystem>
#include <random>
#include <sstream>
#include <string>
#include <variant>

#include "tests/catch.h"

#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "tests/io/graph_equality.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

GraphFile ReadString(const std::string& text, const std::string& name = "test.g2o",
                     GraphFormat format = GraphFormat::kAuto) {
  std::istringstream in(text);
  ReadGraphOptions options;
  options.format = format;
  return ReadGraph(in, name, options);
}

AnyPoseGraph RoundTrip(const AnyPoseGraph& graph) {
  std::ostringstream out;
  WriteG2o(graph, out);
  return ReadString(out.str()).graph;
}

TEST_CASE("an edge from a vertex to itself is left out with its line, and the other edges keep their ids",
          "[io][g2o]") {
  const std::string info = " 1 0 0 1 0 1";
  std::istringstream in("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
                        "EDGE_SE2 0 1 1 0 0" + info + "\nEDGE_SE2 1 1 0 0 0" + info + "\n"
                        "EDGE_SE2 1 2 1 0 0" + info + "\nEDGE_SE2 2 0 -2 0 0" + info + "\n");
  const GraphFile file = ReadGraph(in, "self.g2o");
  CHECK(file.self_edge_lines == std::vector<int>{5});
  const auto& graph = std::get<PoseGraph2>(file.graph);
  REQUIRE(graph.constraints.size() == 3);
  CHECK(graph.constraints[0].id == ClosureId(0));
  CHECK(graph.constraints[1].id == ClosureId(2));
  CHECK(graph.constraints[2].id == ClosureId(3));
  for (const auto& c : graph.constraints) CHECK(c.from != c.to);

  // Edges only: a vertex named by a self edge alone is not made.
  std::istringstream edges_only("EDGE_SE2 0 1 1 0 0" + info + "\nEDGE_SE2 5 5 0 0 0" + info + "\n");
  const GraphFile e = ReadGraph(edges_only, "self.g2o");
  CHECK(e.self_edge_lines == std::vector<int>{2});
  CHECK(std::get<PoseGraph2>(e.graph).vertices.size() == 2);
}

TEST_CASE("g2o 2D edges keep the upper-triangle information order", "[io][g2o]") {
  const auto file = ReadString(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 2 0.5 11 12 13 22 23 33\n");
  const auto& g = std::get<PoseGraph2>(file.graph);
  const auto& info = g.constraints.at(0).measurement.information;
  // A full, positive-definite matrix: every entry lands in its own place.
  CHECK(info(0, 0) == 11);
  CHECK(info(0, 1) == 12);
  CHECK(info(1, 0) == 12);
  CHECK(info(0, 2) == 13);
  CHECK(info(1, 1) == 22);
  CHECK(info(2, 1) == 23);
  CHECK(info(2, 2) == 33);
  CHECK(g.constraints.at(0).measurement.mean.y() == 2.0);
  CHECK(g.constraints.at(0).kind == ClosureKind::kOdometry);
}

TEST_CASE("Vertigo's robust tags are read with their switches, priors and weights",
          "[io][g2o]") {
  const auto file = ReadGraphFile(testing::Fixture("vertigo_switchable_2d.g2o"));
  const auto& g = std::get<PoseGraph2>(file.graph);
  REQUIRE(g.vertices.size() == 4);
  REQUIRE(g.switches.size() == 1);
  const SwitchVariable& s = g.switches.at(SwitchId(4));
  CHECK(s.value == 1.0);
  REQUIRE(s.prior.has_value());
  CHECK(s.prior->information == 1.0);
  REQUIRE(g.constraints.size() == 5);
  CHECK(g.constraints[3].switch_id == SwitchId(4));
  CHECK(g.constraints[3].measurement.information(0, 1) == 10.0);
  CHECK(g.constraints[3].kind == ClosureKind::kUnknown);
  CHECK(g.constraints[4].maxmix_weight == Approx(0.001));
  CHECK(g.vertices.at(PoseId(0)).fixed);
  CHECK_FALSE(g.vertices.at(PoseId(1)).fixed);
  CHECK(testing::GraphsEqual(file.graph, RoundTrip(file.graph)));
}

TEST_CASE("TORO edges map Ixx Ixy Iyy Itt Ixt Iyt to the right matrix entries", "[io][toro]") {
  const auto file = ReadGraphFile(testing::Fixture("small_toro.graph"));
  CHECK(file.format == GraphFormat::kToro);
  const auto& info = std::get<PoseGraph2>(file.graph).constraints.at(0).measurement.information;
  CHECK(info(0, 0) == 10);
  CHECK(info(0, 1) == 1);
  CHECK(info(1, 1) == 20);
  CHECK(info(2, 2) == 30);
  CHECK(info(0, 2) == 2);
  CHECK(info(1, 2) == 3);
  CHECK(info(2, 0) == 2);
}

TEST_CASE("iSAM edges hold square-root information, squared on reading", "[io][isam]") {
  const auto file = ReadString("EDGE2 0 1 1 0 0 50 1 0 50 0 100\n", "gt.txt");
  CHECK(file.format == GraphFormat::kIsam);
  const auto& g = std::get<PoseGraph2>(file.graph);
  const auto& info = g.constraints.at(0).measurement.information;
  // R = [[50, 1, 0], [0, 50, 0], [0, 0, 100]]; Omega = R^T R.
  CHECK(info(0, 0) == Approx(2500));
  CHECK(info(0, 1) == Approx(50));
  CHECK(info(1, 1) == Approx(2501));
  CHECK(info(2, 2) == Approx(10000));
  // Edges only: both vertices exist without an initial pose.
  CHECK(g.vertices.size() == 2);
  CHECK_FALSE(g.HasAllInitialPoses());
}

TEST_CASE("iSAM EDGE3 reads roll, pitch and yaw", "[io][isam]") {
  std::string line = "EDGE3 0 1 1 2 3 0 0 1.5707963267948966";
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) line += r == c ? " 2" : " 0";
  }
  const auto file = ReadString(line + "\n", "gt.txt");
  const auto& c = std::get<PoseGraph3>(file.graph).constraints.at(0);
  const Eigen::Vector3d x = c.measurement.mean.rotation() * Eigen::Vector3d::UnitX();
  CHECK(x.y() == Approx(1.0));  // yaw of 90 degrees turns x into y
  CHECK(c.measurement.information(5, 5) == Approx(4.0));
}

TEST_CASE("g2o 3D quaternions are read in qx qy qz qw order", "[io][g2o]") {
  std::string edge = "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0.7071067811865476 0.7071067811865476";
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) edge += r == c ? " 1" : " 0";
  }
  const auto file = ReadString(
      "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n" + edge + "\n");
  const auto& c = std::get<PoseGraph3>(file.graph).constraints.at(0);
  CHECK(c.measurement.mean.rotation().z() == Approx(std::sqrt(0.5)));
  CHECK(c.measurement.mean.rotation().w() == Approx(std::sqrt(0.5)));
}

TEST_CASE("edges-only files are accepted and their poses flagged missing", "[io][g2o]") {
  const auto file = ReadString("EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n");
  const auto& g = std::get<PoseGraph2>(file.graph);
  CHECK(g.vertices.size() == 3);
  CHECK_FALSE(g.vertices.at(PoseId(2)).pose.has_value());
  // Writing keeps it edges-only.
  const auto again = std::get<PoseGraph2>(RoundTrip(file.graph));
  CHECK_FALSE(again.HasAllInitialPoses());
}

TEST_CASE("closure kinds and provenance survive write and read", "[io][g2o]") {
  std::mt19937_64 rng(5);
  PoseGraph2 g;
  for (int k = 0; k < 6; ++k) g.vertices.emplace(PoseId(k), Vertex<Pose2>{PoseId(k), testing::RandomPose2(rng), false});
  auto add = [&](int id, int from, int to, ClosureKind kind, std::vector<ClosureId> parents) {
    Constraint<Pose2> c;
    c.id = ClosureId(id);
    c.from = PoseId(from);
    c.to = PoseId(to);
    c.measurement.mean = testing::RandomPose2(rng);
    c.measurement.information << 4, 1, 0, 1, 3, 0.5, 0, 0.5, 2;
    c.kind = kind;
    c.provenance.parents = std::move(parents);
    g.constraints.push_back(c);
  };
  add(0, 0, 1, ClosureKind::kOdometry, {});
  add(1, 1, 2, ClosureKind::kOdometry, {});
  add(7, 4, 0, ClosureKind::kVisual, {});
  add(8, 5, 1, ClosureKind::kOdometryInferred, {ClosureId(7), ClosureId(9)});
  add(9, 5, 2, ClosureKind::kInjected, {});
  add(10, 3, 4, ClosureKind::kUnknown, {});  // consecutive ids but not odometry
  CHECK(testing::GraphsEqual(AnyPoseGraph(g), RoundTrip(g)));
  // A robust solve's decisions, exactly, beside the metadata or alone.
  g.constraints[2].decision = RobustDecision{false, 0.012345678901234567};
  g.constraints[4].decision = RobustDecision{true, 1.0};
  const AnyPoseGraph back = RoundTrip(g);
  CHECK(testing::GraphsEqual(AnyPoseGraph(g), back));
  CHECK_FALSE(std::get<PoseGraph2>(back).IsAccepted(std::get<PoseGraph2>(back).constraints[2]));
}

TEST_CASE("a malformed or misplaced decision comment names its line", "[io][g2o][bad-input]") {
  auto error = [](const std::string& text) {
    std::istringstream in(text);
    try {
      ReadGraph(in, "d.g2o");
    } catch (const FileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string vertices = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\n";
  const std::string edge = "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  CHECK(error(vertices + "#CATGRAPH_DECISION maybe 1\n" + edge).starts_with("d.g2o:3: #CATGRAPH_DECISION: expected"));
  CHECK(error(vertices + "#CATGRAPH_DECISION rejected 1.5\n" + edge).starts_with("d.g2o:3: #CATGRAPH_DECISION"));
  CHECK(error("#CATGRAPH_DECISION rejected 0\n" + vertices + edge)
            .starts_with("d.g2o:2: #CATGRAPH_DECISION must be followed by an edge line"));
  CHECK(error(vertices + edge + "#CATGRAPH_DECISION rejected 0\n").find("at the end of the file") != std::string::npos);
  CHECK(error(vertices + "#CATGRAPH_DECISION rejected 0.25\n" + edge) == "no error");
}

TEST_CASE("an edge appended to a file catgraph wrote gets an id of its own", "[io][g2o]") {
  // catgraph numbers closures sparsely (ids survive dropping); an edge a user
  // appends has no id comment, and its position (3) is taken.
  const auto file = ReadString(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
      "#CATGRAPH_CLOSURE 0 odometry\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n"
      "#CATGRAPH_CLOSURE 3 visual\nEDGE_SE2 2 0 -2 0 0 1 0 0 1 0 1\n"
      "EDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n"
      "EDGE_SE2 2 1 -1 0 0 1 0 0 1 0 1\n");
  const auto& g = std::get<PoseGraph2>(file.graph);
  REQUIRE(g.constraints.size() == 4);
  CHECK(g.constraints[0].id == ClosureId(0));
  CHECK(g.constraints[1].id == ClosureId(3));
  CHECK(g.constraints[2].id == ClosureId(2));  // its position, free
  CHECK(g.constraints[3].id == ClosureId(4));  // its position (3) is taken: next above all
}

TEST_CASE("random 2D and 3D graphs round-trip exactly", "[io][g2o]") {
  std::mt19937_64 rng(6);
  for (int trial = 0; trial < 20; ++trial) {
    PoseGraph3 g;
    for (int k = 0; k < 10; ++k) g.vertices.emplace(PoseId(k), Vertex<Pose3>{PoseId(k), testing::RandomPose3(rng), k == 0});
    for (int k = 1; k < 10; ++k) {
      Constraint<Pose3> c;
      c.id = ClosureId(k - 1);
      c.from = PoseId(k - 1);
      c.to = PoseId(k);
      c.kind = ClosureKind::kOdometry;
      c.measurement.mean = testing::RandomPose3(rng);
      Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Identity();
      a(0, 3) = 0.3;
      c.measurement.information = a.transpose() * a;
      g.constraints.push_back(c);
    }
    REQUIRE(testing::GraphsEqual(AnyPoseGraph(g), RoundTrip(g), 1e-12));
  }
}

TEST_CASE("WriteG2oFile replaces the file atomically and leaves no temporary", "[io]") {
  const auto dir = std::filesystem::temp_directory_path() / "catgraph_atomic_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const auto path = dir / "out.g2o";
  const auto file = ReadGraphFile(testing::Fixture("vertigo_switchable_2d.g2o"));
  WriteG2oFile(file.graph, path);
  WriteG2oFile(file.graph, path);
  CHECK(testing::GraphsEqual(file.graph, ReadGraphFile(path).graph));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  CHECK(entries == 1);
  // A writer that fails leaves the old file as it was.
  PoseGraph3 bad;
  bad.vertices.emplace(PoseId(0), Vertex<Pose3>{PoseId(0), Pose3(), false});
  bad.vertices.emplace(PoseId(1), Vertex<Pose3>{PoseId(1), Pose3(), false});
  Constraint<Pose3> c;
  c.from = PoseId(0);
  c.to = PoseId(1);
  c.maxmix_weight = 0.5;  // no 3D max-mixture tag exists
  bad.constraints.push_back(c);
  CHECK_THROWS_AS(WriteG2oFile(bad, path), std::invalid_argument);
  CHECK(testing::GraphsEqual(file.graph, ReadGraphFile(path).graph));
  entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir)) ++entries;
  CHECK(entries == 1);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace catgraph
