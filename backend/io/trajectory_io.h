// Reading trajectories (ground truth, estimates) and writing TUM files.
//
// Formats (docs/file-formats.md):
//   graph  any pose-graph file ReadGraphFile reads; its vertices.
//   poses  one pose per line, "x y theta" (line k is pose k, 0-based) or
//          "id x y theta" — Olson's Manhattan ground truth and Vertigo's ring
//          poses.txt. 2D.
//   tum    "timestamp x y z qx qy qz qw" per line (TUM RGB-D, evo): row k is
//          pose k; the timestamp is not used to match. 3D.
// Lines starting with '#' and blank lines are skipped. Every problem is a
// FileError naming the file and the line.
#ifndef CATGRAPH_BACKEND_IO_TRAJECTORY_IO_H_
#define CATGRAPH_BACKEND_IO_TRAJECTORY_IO_H_

#include <filesystem>
#include <map>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>

#include "backend/graph/trajectory.h"

namespace catgraph {

enum class TrajectoryFormat { kAuto, kGraph, kPoses, kTum };

std::string_view ToString(TrajectoryFormat format);
std::optional<TrajectoryFormat> TrajectoryFormatFromString(std::string_view text);

// kAuto decides from the first content line: a graph tag (VERTEX_SE2, EDGE2,
// ...) means graph, 3 or 4 numbers poses, 8 numbers tum.
AnyTrajectory ReadTrajectoryFile(const std::filesystem::path& path,
                                 TrajectoryFormat format = TrajectoryFormat::kAuto);
AnyTrajectory ReadTrajectory(std::istream& in, const std::string& name,
                             TrajectoryFormat format = TrajectoryFormat::kAuto);

// TUM lines "timestamp x y z qx qy qz qw" (TUM RGB-D, evo); a 2D trajectory
// is written in the plane z = 0. The timestamp is the pose's time in seconds
// from `times` when given (every pose must have one; evo pairs trajectories
// by it), else the pose id; the header line says which.
void WriteTum(const AnyTrajectory& trajectory, std::ostream& out, const std::map<PoseId, double>* times = nullptr);
void WriteTumFile(const AnyTrajectory& trajectory, const std::filesystem::path& path,
                  const std::map<PoseId, double>* times = nullptr);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_TRAJECTORY_IO_H_
