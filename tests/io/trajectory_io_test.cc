// Trajectory files, closure labels and graph export: formats, round trips and
// bad input reported with file and line.
#include <sstream>

#include "tests/catch.h"
#include <nlohmann/json.hpp>

#include "backend/io/closure_labels.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_export.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

AnyTrajectory Read(const std::string& text, TrajectoryFormat format = TrajectoryFormat::kAuto) {
  std::istringstream in(text);
  return ReadTrajectory(in, "t.txt", format);
}

std::string ReadError(const std::string& text, TrajectoryFormat format = TrajectoryFormat::kAuto) {
  try {
    Read(text, format);
  } catch (const FileError& e) {
    return e.what();
  }
  return "no error";
}

TEST_CASE("pose lists with and without ids, TUM files and graphs are read", "[io][trajectory]") {
  const auto plain = std::get<Trajectory2>(Read("# x y theta\n0 0 0\n1 0 0.5\n\n2 1 -0.5\n"));
  REQUIRE(plain.size() == 3);
  CHECK(testing::ApproxEqual(plain.at(PoseId(2)), Pose2(2, 1, -0.5)));
  const auto with_ids = std::get<Trajectory2>(Read("10 0 0 0\n12 1 2 0.25\n"));
  CHECK(with_ids.begin()->first == PoseId(10));
  CHECK(testing::ApproxEqual(with_ids.at(PoseId(12)), Pose2(1, 2, 0.25)));
  const auto tum = std::get<Trajectory3>(
      Read("# tum\n1.5 1 2 3 0 0 0 1\n1.6 1 2 4 0 0 0.7071067811865476 0.7071067811865476\n"));
  REQUIRE(tum.size() == 2);
  CHECK(tum.at(PoseId(1)).translation().z() == 4.0);
  CHECK(ToPose2(tum.at(PoseId(1))).theta() == Approx(std::numbers::pi / 2));
  const auto graph = std::get<Trajectory2>(Read("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 3 0 0\n"));
  CHECK(graph.at(PoseId(1)).x() == 3.0);
}

TEST_CASE("TUM written and read back gives the same trajectory", "[io][trajectory]") {
  std::mt19937_64 rng(1);
  Trajectory3 t3;
  for (int i = 0; i < 20; ++i) t3[PoseId(i)] = testing::RandomPose3(rng);
  std::ostringstream out;
  WriteTum(t3, out);
  const auto back = std::get<Trajectory3>(Read(out.str(), TrajectoryFormat::kTum));
  REQUIRE(back.size() == t3.size());
  for (const auto& [id, p] : t3) CHECK(testing::ApproxEqual(back.at(id), p, 1e-12));
  // 2D goes to the plane z = 0 and comes back as the same planar pose.
  Trajectory2 t2{{PoseId(0), Pose2(1, 2, 3)}, {PoseId(1), Pose2(-1, 0, -2)}};
  std::ostringstream out2;
  WriteTum(t2, out2);
  const auto planar = std::get<Trajectory3>(Read(out2.str()));
  CHECK(testing::ApproxEqual(ToPose2(planar.at(PoseId(0))), t2.at(PoseId(0)), 1e-12));
  // With times, the timestamp column is each pose's time in seconds.
  const std::map<PoseId, double> times{{PoseId(0), 1764936000.125}, {PoseId(1), 1764936000.25}};
  std::ostringstream timed;
  WriteTum(t2, timed, &times);
  CHECK(timed.str().starts_with("# timestamp tx ty tz qx qy qz qw (timestamp in seconds)\n1764936000.125 1 2 0 "));
  CHECK(timed.str().find("\n1764936000.25 -1 0 0 ") != std::string::npos);
  const std::map<PoseId, double> partial{{PoseId(0), 0.5}};
  std::ostringstream unused;
  CHECK_THROWS_WITH(WriteTum(t2, unused, &partial), Catch::Contains("pose 1 has no timestamp"));
}

TEST_CASE("bad trajectory files name the file, the line and what was expected",
          "[io][trajectory][bad-input]") {
  CHECK(ReadError("0 0 0\nx 0 0\n") == "t.txt:2: pose: expected a number for x, found 'x'");
  CHECK(ReadError("0 0 0\n1 0\n") ==
        "t.txt:2: found 2 values; expected 3 like line 1 (x y theta)");
  CHECK(ReadError("1 2 3 4 5\n").starts_with("t.txt:1: found 5 values; expected a trajectory"));
  CHECK(ReadError("0 0 0 0\n0 1 1 1\n") ==
        "t.txt:2: pose 0 is listed twice; expected one line per pose");
  CHECK(ReadError("1 0 0 0 0 0 0 2\n").starts_with("t.txt:1: the quaternion has norm 2"));
  CHECK(ReadError("# nothing\n") == "t.txt:1: no pose in the file");
  // A repeated TUM row would pair every later pose with the wrong truth.
  CHECK(ReadError("1.0 0 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n2.0 1 0 0 0 0 0 1\n") ==
        "t.txt:3: timestamp 2.0 is not after line 2's; expected strictly increasing timestamps");
  // Asked for poses, a first line of 2 or 5 values (found by fuzzing: the
  // column count was trusted and indexed past the line).
  CHECK(ReadError("1 2\n3 4\n", TrajectoryFormat::kPoses) ==
        "t.txt:1: found 2 values; expected 3 (x y theta) or 4 (id x y theta)");
  CHECK(ReadError("1 2 3 4 5\n", TrajectoryFormat::kPoses) ==
        "t.txt:1: found 5 values; expected 3 (x y theta) or 4 (id x y theta)");
  CHECK(ReadError("EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n").find("pose 0 has no value") !=
        std::string::npos);
  CHECK_THROWS_WITH(ReadTrajectoryFile("/nonexistent/truth.txt"),
                    Catch::Contains("no such file; expected a trajectory"));
}

TEST_CASE("closure labels round-trip and reject foreign files", "[io][labels]") {
  std::vector<ClosureLabel> labels(3);
  labels[0] = {ClosureId(4), PoseId(1), PoseId(9), false, ClosureKind::kUnknown, {}, {}};
  labels[1] = {ClosureId(7), PoseId(2), PoseId(30), true, ClosureKind::kVisual, 0, {}};
  labels[2] = {ClosureId(8), PoseId(3), PoseId(31), true, ClosureKind::kOdometryInferred, 0,
               ClosureId(7)};
  std::ostringstream out;
  WriteClosureLabels(labels, out);
  std::istringstream in(out.str());
  CHECK(ReadClosureLabels(in, "l.csv") == labels);

  auto error = [](const std::string& text) {
    std::istringstream s(text);
    try {
      ReadClosureLabels(s, "l.csv");
    } catch (const FileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(error("id,from,to\n").starts_with("l.csv:1: expected the header"));
  CHECK(error(std::string(kClosureLabelsHeader) + "\n1,2,3,1,visual,0\n") ==
        "l.csv:2: found 6 fields; expected 7 (closure_id,from,to,outlier,kind,group,parent)");
  CHECK(error(std::string(kClosureLabelsHeader) + "\n1,2,3,1,magic,0,\n")
            .starts_with("l.csv:2: unknown closure kind 'magic'"));
  CHECK(error(std::string(kClosureLabelsHeader) + "\n1,2,3,2,visual,0,\n")
            .starts_with("l.csv:2: closure label: expected a non-negative integer id for outlier"));
  // Silent garbage before: a header alone scored 0 closures as precision 1.
  CHECK(error(std::string(kClosureLabelsHeader) + "\n") == "l.csv: holds the header alone; expected a row per loop closure");
  CHECK(error(std::string(kClosureLabelsHeader) + "\n1,2,3,1,visual,0,\n\n1,5,9,0,visual,,\n") ==
        "l.csv:4: closure_id 1 is labelled again (first on line 2); expected one row per closure");
}

TEST_CASE("the JSON export holds every vertex, constraint and decision", "[io][export]") {
  std::istringstream in(
      "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\nVERTEX_SWITCH 3 0.2\n"
      "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1 0 0 1 0 0 1 0 1\n"
      "EDGE_SE2_SWITCHABLE 0 2 3 2 0 0 4 1 0 5 0 6\n");
  const AnyPoseGraph g = ReadGraph(in, "g.g2o").graph;
  std::ostringstream out;
  WriteGraphJson(g, out);
  const auto j = nlohmann::json::parse(out.str());
  CHECK(j.at("dimension") == 2);
  CHECK(j.at("vertices").size() == 3);
  REQUIRE(j.at("constraints").size() == 3);
  const auto& closure = j.at("constraints")[2];
  CHECK(closure.at("accepted") == false);
  CHECK(closure.at("switch") == 3);
  CHECK(closure.at("information")[0][1] == 1.0);
  CHECK(closure.at("information")[1][0] == 1.0);
  CHECK(j.at("switches")[0].at("value") == 0.2);

  std::ostringstream dot;
  WriteGraphDot(g, dot);
  CHECK(dot.str().find("0 -- 2 [color=red, style=dashed") != std::string::npos);
  CHECK(dot.str().find("1 [pos=\"10,0!\"]") != std::string::npos);
}

}  // namespace
}  // namespace catgraph
