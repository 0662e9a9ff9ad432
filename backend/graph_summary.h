// A summary of a pose graph: what `catgraph info` prints.
#ifndef CATGRAPH_BACKEND_GRAPH_SUMMARY_H_
#define CATGRAPH_BACKEND_GRAPH_SUMMARY_H_

#include <cstddef>
#include <map>
#include <string>

#include "backend/graph/pose_graph.h"

namespace catgraph {

struct GraphSummary {
  int dimension = 2;
  std::size_t vertices = 0;
  std::size_t vertices_without_pose = 0;  // edges-only files: initialise first
  std::size_t fixed_vertices = 0;
  std::size_t edges = 0;
  std::size_t odometry_edges = 0;  // between consecutive pose ids
  std::size_t loop_closures = 0;   // every other edge
  std::size_t switchable_edges = 0;
  std::size_t maxmix_edges = 0;
  std::size_t switches = 0;
  std::map<ClosureKind, std::size_t> edges_by_kind;
  // Edges whose translation and rotation blocks are positive definite but whose
  // whole information matrix is not (the reader accepts them; see
  // docs/file-formats.md).
  std::size_t indefinite_information_edges = 0;
  std::size_t connected_components = 0;
  bool connected = false;
  // Heuristic: most edges have a diagonal information entry that is the square
  // root of a round number (44.7214 = sqrt(2000)), the mark of files that hold
  // square-root information where information belongs (g2o issue #47).
  bool looks_like_square_root_information = false;
  std::string square_root_information_example;  // e.g. "44.7214 = sqrt(2000)"
};

GraphSummary Summarize(const AnyPoseGraph& graph);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_SUMMARY_H_
