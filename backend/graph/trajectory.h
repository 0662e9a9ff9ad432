// A trajectory: poses by id, in id order. The estimate of a pose graph, a
// ground truth, or a TUM file read back.
#ifndef CATGRAPH_BACKEND_GRAPH_TRAJECTORY_H_
#define CATGRAPH_BACKEND_GRAPH_TRAJECTORY_H_

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <variant>

#include <Eigen/Geometry>

#include "backend/graph/pose_graph.h"

namespace catgraph {

template <typename PoseT>
using Trajectory = std::map<PoseId, PoseT>;
using Trajectory2 = Trajectory<Pose2>;
using Trajectory3 = Trajectory<Pose3>;
using AnyTrajectory = std::variant<Trajectory2, Trajectory3>;

// The poses of `graph`. Throws std::invalid_argument naming the first vertex
// without a pose (an edges-only graph that was not optimised).
template <typename PoseT>
Trajectory<PoseT> TrajectoryOf(const PoseGraph<PoseT>& graph) {
  Trajectory<PoseT> trajectory;
  for (const auto& [id, vertex] : graph.vertices) {
    if (!vertex.pose) {
      throw std::invalid_argument("pose " + std::to_string(id.value()) +
                                  " has no value (an edges-only graph: optimise it first)");
    }
    trajectory.emplace_hint(trajectory.end(), id, *vertex.pose);
  }
  return trajectory;
}

inline AnyTrajectory TrajectoryOf(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return AnyTrajectory(TrajectoryOf(g)); }, graph);
}

// SE(2) <-> SE(3): the planar pose in the x-y plane with rotation about z;
// down to SE(2) keeps x, y and the yaw of the rotation.
inline Pose3 ToPose3(const Pose2& p) {
  return {Eigen::Vector3d(p.x(), p.y(), 0.0),
          Eigen::Quaterniond(Eigen::AngleAxisd(p.theta(), Eigen::Vector3d::UnitZ()))};
}

inline Pose2 ToPose2(const Pose3& p) {
  const Eigen::Vector3d x_axis = p.rotation() * Eigen::Vector3d::UnitX();
  return {p.translation().x(), p.translation().y(), std::atan2(x_axis.y(), x_axis.x())};
}

template <typename To, typename From>
Trajectory<To> ConvertTrajectory(const Trajectory<From>& from) {
  if constexpr (std::is_same_v<To, From>) {
    return from;
  } else {
    Trajectory<To> to;
    for (const auto& [id, pose] : from) {
      if constexpr (std::is_same_v<To, Pose2>) {
        to.emplace_hint(to.end(), id, ToPose2(pose));
      } else {
        to.emplace_hint(to.end(), id, ToPose3(pose));
      }
    }
    return to;
  }
}

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_TRAJECTORY_H_
