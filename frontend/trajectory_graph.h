// CAT-Graph's continuous trajectory graph (docs/catgraph-spec.md §1.2–1.4):
// one node per image with its observation, directed edges carrying the
// relative pose u_mn (N_n in the frame of N_m), and local graphs — the
// neighbourhood of a point on an edge laid out in metric coordinates by a
// Dijkstra search along the edges, first (shortest-path) arrival winning, so
// that the graph stays locally Euclidean while it is not globally metric.
//
// Particles live on edges: (edge, fraction α from its start, direction). The
// point at α is α·u (translation and heading interpolated linearly in the
// frame of the edge's start node).
//
// Thread-compatible.
#ifndef CATGRAPH_FRONTEND_TRAJECTORY_GRAPH_H_
#define CATGRAPH_FRONTEND_TRAJECTORY_GRAPH_H_

#include <functional>
#include <optional>
#include <cstdint>
#include <vector>

#include "backend/graph/pose2.h"
#include "frontend/observation_model.h"

namespace catgraph {

enum class EdgeType { kOdometry, kVisualLoop, kOdometricLoop };

struct GraphNode {
  int frame = -1;             // index in the dataset's frames.csv
  double time_s = 0.0;
  double path_length_m = 0.0;  // odometry distance from the first node
  Pose2 odometry_pose;         // dead reckoning from the first node
  Observation observation;
  std::vector<int> edges;      // incident edges, both directions
};

struct GraphEdge {
  int from = -1, to = -1;
  Pose2 u;                     // N_to in the frame of N_from
  EdgeType type = EdgeType::kOdometry;
  double length_m = 0.0;
};

class TrajectoryGraph {
 public:
  int AddNode(int frame, double time_s, double path_length_m, const Pose2& odometry_pose, Observation observation);
  // Throws std::invalid_argument on unknown nodes or a self-edge.
  int AddEdge(int from, int to, const Pose2& u, EdgeType type);

  const std::vector<GraphNode>& nodes() const { return nodes_; }
  const std::vector<GraphEdge>& edges() const { return edges_; }
  const GraphNode& node(int id) const { return nodes_.at(static_cast<std::size_t>(id)); }
  const GraphEdge& edge(int id) const { return edges_.at(static_cast<std::size_t>(id)); }

 private:
  std::vector<GraphNode> nodes_;
  std::vector<GraphEdge> edges_;
};

// The point at fraction alpha along u: (α·Δx, α·Δy, α·Δθ).
inline Pose2 PointOnEdge(const Pose2& u, double alpha) {
  return {alpha * u.x(), alpha * u.y(), alpha * u.theta()};
}

// A local graph: node poses in the frame of one anchor node, and the edges
// whose both ends were reached. Flat arrays sorted by id: a local graph is
// built for every occupied edge at every step, so no hashing.
struct LocalGraph {
  struct Node {
    int id;
    Pose2 pose;  // in the anchor's frame
  };
  struct Segment {
    int edge;
    Pose2 from, to;  // the end nodes' poses
  };
  std::vector<Node> nodes;        // sorted by id
  std::vector<Segment> segments;  // the edges with both ends reached, sorted by edge id

  const Pose2* Find(int node) const;
  bool Contains(int node) const { return Find(node) != nullptr; }
  // Throws std::out_of_range when the node is not in the local graph.
  const Pose2& PoseOf(int node) const;
  // The pose of the point at alpha on edge e (between the two node poses,
  // as the projection sees it: with loops, an end may have been reached by
  // another path than e), or nullopt when e is not in the local graph.
  std::optional<Pose2> PointPose(int edge, double alpha) const;
};

// Builds local graphs, reusing its buffers (a visited stamp per graph node),
// so that a build costs O(nodes reached), not O(graph). Thread-compatible.
class LocalGraphBuilder {
 public:
  // Nodes within `radius_m` (straight-line, in the anchor's frame) of the
  // anchor node, reached along edges through eligible nodes, shortest path
  // first. `eligible` may be empty (every node); the anchor is always
  // included.
  void Build(const TrajectoryGraph& graph, int anchor, double radius_m,
             const std::function<bool(int)>& eligible, LocalGraph& out);

 private:
  struct Entry {
    double g;
    int node;
    Pose2 pose;
  };
  std::vector<std::uint32_t> stamp_;
  std::uint32_t current_ = 0;
  std::vector<Entry> fringe_;
};

// One-off form of LocalGraphBuilder::Build.
LocalGraph BuildLocalGraph(const TrajectoryGraph& graph, int anchor, double radius_m,
                           const std::function<bool(int)>& eligible = {});

// The nearest point of the local graph's edges to `y` (x, y only): edge,
// fraction along it, path heading there, and the distance. Edges shorter
// than 1 µm are skipped. Empty when the local graph has no usable edge.
struct Projection {
  int edge = -1;
  double alpha = 0.0;
  Pose2 pose;          // position on the edge, path heading θ_s
  double distance_m = 0.0;
};
std::optional<Projection> ProjectOntoLocalGraph(const LocalGraph& local, const Pose2& y);

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_TRAJECTORY_GRAPH_H_
