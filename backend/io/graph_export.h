// Exporting a pose graph for other tools: JSON (the whole graph) and
// GraphViz DOT. TUM trajectories are in trajectory_io.h, g2o in graph_io.h.
// docs/file-formats.md documents both layouts.
#ifndef CATGRAPH_BACKEND_IO_GRAPH_EXPORT_H_
#define CATGRAPH_BACKEND_IO_GRAPH_EXPORT_H_

#include <filesystem>
#include <iosfwd>

#include "backend/graph/pose_graph.h"

namespace catgraph {

// {"format": "catgraph-graph", "version": 1, "dimension": 2|3,
//  "vertices": [{"id", "pose", "fixed"}], "constraints": [{"id", "from", "to",
//  "kind", "parents", "measurement", "information", "switch"?, "accepted"}],
//  "switches": [{"id", "value", "prior_mean"?, "prior_information"?}]}
// A 2D pose is {"x", "y", "theta"}, a 3D pose {"t": [x, y, z], "q": [qx, qy, qz, qw]};
// "information" is the full matrix, row-major. "accepted" is false for a
// constraint whose switch is <= 0.5.
void WriteGraphJson(const AnyPoseGraph& graph, std::ostream& out);

// An undirected GraphViz graph with every vertex pinned at its x-y position
// (10 points per metre; render with `neato -n2 -Tpdf`): odometry grey,
// accepted closures green, rejected ones red and dashed. Needs every pose.
void WriteGraphDot(const AnyPoseGraph& graph, std::ostream& out);

// Atomic file versions; throw FileError.
void WriteGraphJsonFile(const AnyPoseGraph& graph, const std::filesystem::path& path);
void WriteGraphDotFile(const AnyPoseGraph& graph, const std::filesystem::path& path);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_GRAPH_EXPORT_H_
