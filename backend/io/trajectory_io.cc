#include "backend/io/trajectory_io.h"

#include <cctype>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <sstream>
#include <vector>

#include "backend/graph/name_table.h"
#include "backend/io/atomic_file.h"
#include "backend/io/graph_io.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {
namespace {

constexpr NameTable<TrajectoryFormat, 4> kTrajectoryFormatNames = {{
    {TrajectoryFormat::kAuto, "auto"},
    {TrajectoryFormat::kGraph, "graph"},
    {TrajectoryFormat::kPoses, "poses"},
    {TrajectoryFormat::kTum, "tum"},
}};

constexpr std::size_t kMaxLineBytes = 64 * 1024;

struct NumberedLine {
  int number;
  std::string text;
};

std::vector<NumberedLine> ContentLines(std::istream& in, const std::string& name) {
  std::vector<NumberedLine> lines;
  std::string text;
  int number = 0;
  while (ReadBoundedLine(in, text, kMaxLineBytes, name, number, "one pose per line")) {
    ++number;
    const auto tokens = Tokenize(text);
    if (tokens.empty() || tokens.front().starts_with("#")) continue;
    lines.push_back({number, text});
  }
  if (in.bad()) throw FileError(name, number, "read error");
  if (lines.empty()) throw FileError(name, std::max(number, 1), "no pose in the file");
  return lines;
}

TrajectoryFormat Detect(const std::vector<NumberedLine>& lines, const std::string& name) {
  const auto tokens = Tokenize(lines.front().text);
  if (std::isalpha(static_cast<unsigned char>(tokens.front().front()))) {
    return TrajectoryFormat::kGraph;
  }
  if (tokens.size() == 3 || tokens.size() == 4) return TrajectoryFormat::kPoses;
  if (tokens.size() == 8) return TrajectoryFormat::kTum;
  throw FileError(name, lines.front().number,
                  "found " + std::to_string(tokens.size()) +
                      " values; expected a trajectory: 'x y theta' or 'id x y theta' (poses), "
                      "'timestamp x y z qx qy qz qw' (TUM) or a pose graph");
}

Trajectory2 ParsePoses(const std::vector<NumberedLine>& lines, const std::string& name) {
  Trajectory2 trajectory;
  const std::size_t columns = Tokenize(lines.front().text).size();
  if (columns != 3 && columns != 4) {
    throw FileError(name, lines.front().number,
                    "found " + std::to_string(columns) + " values; expected 3 (x y theta) or 4 (id x y theta)");
  }
  std::int64_t row = 0;
  for (const NumberedLine& l : lines) {
    const Line line(name, l.number, Tokenize(l.text), "pose");
    if (line.size() != columns) {
      line.Fail("found " + std::to_string(line.size()) + " values; expected " +
                std::to_string(columns) + " like line " + std::to_string(lines.front().number) +
                (columns == 3 ? " (x y theta)" : " (id x y theta)"));
    }
    const std::size_t first = columns - 3;
    const PoseId id(first == 1 ? line.Id(0, "id", std::int64_t{1} << 40) : row);
    const Pose2 pose(line.Number(first, "x"), line.Number(first + 1, "y"),
                     line.Number(first + 2, "theta"));
    if (!trajectory.emplace(id, pose).second) {
      line.Fail("pose " + std::to_string(id.value()) + " is listed twice; expected one line per pose");
    }
    ++row;
  }
  return trajectory;
}

Trajectory3 ParseTum(const std::vector<NumberedLine>& lines, const std::string& name) {
  Trajectory3 trajectory;
  std::int64_t row = 0;
  double previous_time = -std::numeric_limits<double>::infinity();
  int previous_line = 0;
  for (const NumberedLine& l : lines) {
    const Line line(name, l.number, Tokenize(l.text), "TUM pose");
    if (line.size() != 8) {
      line.Fail("found " + std::to_string(line.size()) +
                " values; expected 8 (timestamp x y z qx qy qz qw)");
    }
    // Poses pair with another trajectory's by order: a repeated or
    // misplaced row would shift every pose after it.
    const double time = line.Number(0, "timestamp");
    if (!(time > previous_time)) {
      line.Fail("timestamp " + std::string(line.token(0)) + " is not after line " + std::to_string(previous_line) +
                "'s; expected strictly increasing timestamps");
    }
    previous_time = time;
    previous_line = l.number;
    const Eigen::Vector3d t(line.Number(1, "x"), line.Number(2, "y"), line.Number(3, "z"));
    const Eigen::Quaterniond q(line.Number(7, "qw"), line.Number(4, "qx"), line.Number(5, "qy"),
                               line.Number(6, "qz"));
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) < 1e-3)) {
      line.Fail("the quaternion has norm " + std::to_string(norm) + "; expected a unit quaternion");
    }
    trajectory.emplace_hint(trajectory.end(), PoseId(row++), Pose3(t, q));
  }
  return trajectory;
}

}  // namespace

std::string_view ToString(TrajectoryFormat format) { return NameOf(kTrajectoryFormatNames, format); }
std::optional<TrajectoryFormat> TrajectoryFormatFromString(std::string_view text) {
  return ValueOf(kTrajectoryFormatNames, text);
}

AnyTrajectory ReadTrajectory(std::istream& in, const std::string& name, TrajectoryFormat format) {
  auto from_graph = [&name](std::istream& graph_in) {
    const GraphFile file = ReadGraph(graph_in, name);
    try {
      return TrajectoryOf(file.graph);
    } catch (const std::invalid_argument& e) {
      throw FileError(name, 0, std::string(e.what()) + "; expected a graph with every pose");
    }
  };
  if (format == TrajectoryFormat::kGraph) return from_graph(in);
  std::stringstream copy;  // kept for the graph reader if the content is a graph
  copy << in.rdbuf();
  const std::vector<NumberedLine> lines = ContentLines(copy, name);
  if (format == TrajectoryFormat::kAuto) format = Detect(lines, name);
  if (format == TrajectoryFormat::kPoses) return ParsePoses(lines, name);
  if (format == TrajectoryFormat::kTum) return ParseTum(lines, name);
  copy.clear();
  copy.seekg(0);
  return from_graph(copy);
}

AnyTrajectory ReadTrajectoryFile(const std::filesystem::path& path, TrajectoryFormat format) {
  std::ifstream in = OpenForReading(path, "a trajectory (poses, TUM or a pose graph)");
  return ReadTrajectory(in, path.string(), format);
}

void WriteTum(const AnyTrajectory& trajectory, std::ostream& out, const std::map<PoseId, double>* times) {
  const Trajectory3 poses = std::visit(
      [](const auto& t) { return ConvertTrajectory<Pose3>(t); }, trajectory);
  if (!times) {
    out << "# timestamp tx ty tz qx qy qz qw (timestamp = catgraph pose id)\n";
    for (const auto& [id, pose] : poses) out << (LineWriter() << id << pose).str() << '\n';
    return;
  }
  out << "# timestamp tx ty tz qx qy qz qw (timestamp in seconds)\n";
  for (const auto& [id, pose] : poses) {
    const auto time = times->find(id);
    if (time == times->end()) {
      throw std::invalid_argument("WriteTum: pose " + std::to_string(id.value()) + " has no timestamp");
    }
    out << (LineWriter() << time->second << pose).str() << '\n';
  }
}

void WriteTumFile(const AnyTrajectory& trajectory, const std::filesystem::path& path,
                  const std::map<PoseId, double>* times) {
  WriteFileAtomically(path, [&](std::ostream& out) { WriteTum(trajectory, out, times); });
}

}  // namespace catgraph
