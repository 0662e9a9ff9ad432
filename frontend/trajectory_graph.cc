#include "frontend/trajectory_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace catgraph {

int TrajectoryGraph::AddNode(int frame, double time_s, double path_length_m, const Pose2& odometry_pose,
                             Observation observation) {
  GraphNode node;
  node.frame = frame;
  node.time_s = time_s;
  node.path_length_m = path_length_m;
  node.odometry_pose = odometry_pose;
  node.observation = std::move(observation);
  nodes_.push_back(std::move(node));
  return static_cast<int>(nodes_.size()) - 1;
}

int TrajectoryGraph::AddEdge(int from, int to, const Pose2& u, EdgeType type) {
  const int n = static_cast<int>(nodes_.size());
  if (from < 0 || from >= n || to < 0 || to >= n || from == to) {
    throw std::invalid_argument("trajectory graph: edge " + std::to_string(from) + " -> " +
                                std::to_string(to) + " needs two distinct existing nodes");
  }
  const int id = static_cast<int>(edges_.size());
  edges_.push_back({from, to, u, type, u.translation().norm()});
  nodes_[static_cast<std::size_t>(from)].edges.push_back(id);
  nodes_[static_cast<std::size_t>(to)].edges.push_back(id);
  return id;
}

const Pose2* LocalGraph::Find(int node) const {
  const auto it = std::lower_bound(nodes.begin(), nodes.end(), node,
                                   [](const Node& n, int id) { return n.id < id; });
  return it != nodes.end() && it->id == node ? &it->pose : nullptr;
}

const Pose2& LocalGraph::PoseOf(int node) const {
  const Pose2* pose = Find(node);
  if (pose == nullptr) throw std::out_of_range("local graph: node " + std::to_string(node) + " not reached");
  return *pose;
}

std::optional<Pose2> LocalGraph::PointPose(int edge, double alpha) const {
  const auto it = std::lower_bound(segments.begin(), segments.end(), edge,
                                   [](const Segment& s, int id) { return s.edge < id; });
  if (it == segments.end() || it->edge != edge) return std::nullopt;
  return Interpolate(it->from, it->to, alpha);
}

void LocalGraphBuilder::Build(const TrajectoryGraph& graph, int anchor, double radius_m,
                              const std::function<bool(int)>& eligible, LocalGraph& out) {
  out.nodes.clear();
  out.segments.clear();
  const std::size_t n_nodes = graph.nodes().size();
  if (stamp_.size() < n_nodes) stamp_.resize(std::max(n_nodes, 2 * stamp_.size()), 0);
  if (++current_ == 0) {  // wrapped: forget every old stamp
    std::fill(stamp_.begin(), stamp_.end(), 0);
    current_ = 1;
  }
  // Dijkstra on path length; a visited node carries the current stamp.
  auto later = [](const Entry& a, const Entry& b) { return a.g > b.g; };
  fringe_.clear();
  fringe_.push_back({0.0, anchor, Pose2()});
  while (!fringe_.empty()) {
    std::pop_heap(fringe_.begin(), fringe_.end(), later);
    const Entry top = fringe_.back();
    fringe_.pop_back();
    std::uint32_t& seen = stamp_[static_cast<std::size_t>(top.node)];
    if (seen == current_) continue;  // the first arrival is the shortest
    seen = current_;
    out.nodes.push_back({top.node, top.pose});
    for (const int id : graph.node(top.node).edges) {
      const GraphEdge& e = graph.edge(id);
      const int m = e.from == top.node ? e.to : e.from;
      if (stamp_[static_cast<std::size_t>(m)] == current_ || (eligible && !eligible(m))) continue;
      const Pose2 next = e.from == top.node ? top.pose * e.u : top.pose * e.u.Inverse();
      if (next.translation().squaredNorm() > radius_m * radius_m) continue;
      fringe_.push_back({top.g + e.length_m, m, next});
      std::push_heap(fringe_.begin(), fringe_.end(), later);
    }
  }
  std::sort(out.nodes.begin(), out.nodes.end(),
            [](const LocalGraph::Node& a, const LocalGraph::Node& b) { return a.id < b.id; });
  for (const LocalGraph::Node& n : out.nodes) {
    for (const int id : graph.node(n.id).edges) {
      const GraphEdge& e = graph.edge(id);
      // Each edge once: from its start node.
      if (e.from == n.id && stamp_[static_cast<std::size_t>(e.to)] == current_) {
        out.segments.push_back({id, n.pose, out.PoseOf(e.to)});
      }
    }
  }
  std::sort(out.segments.begin(), out.segments.end(),
            [](const LocalGraph::Segment& a, const LocalGraph::Segment& b) { return a.edge < b.edge; });
}

LocalGraph BuildLocalGraph(const TrajectoryGraph& graph, int anchor, double radius_m,
                           const std::function<bool(int)>& eligible) {
  LocalGraphBuilder builder;
  LocalGraph local;
  builder.Build(graph, anchor, radius_m, eligible, local);
  return local;
}

std::optional<Projection> ProjectOntoLocalGraph(const LocalGraph& local, const Pose2& y) {
  std::optional<Projection> best;
  const Eigen::Vector2d p = y.translation();
  double best_d2 = std::numeric_limits<double>::infinity();
  for (const LocalGraph::Segment& s : local.segments) {
    const Eigen::Vector2d a = s.from.translation();
    const Eigen::Vector2d ab = s.to.translation() - a;
    const double len2 = ab.squaredNorm();
    if (len2 < 1e-12) continue;
    const double t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
    const Eigen::Vector2d q = a + t * ab;
    const double d2 = (p - q).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      // The path heading along a straight segment between the two node poses.
      const double heading = s.from.theta() + t * WrapAngle(s.to.theta() - s.from.theta());
      best = Projection{s.edge, t, Pose2(q.x(), q.y(), heading), 0.0};
    }
  }
  if (best) best->distance_m = std::sqrt(best_d2);
  return best;
}

}  // namespace catgraph
