// The pose-graph model shared by every layer: vertices (poses), relative-pose
// constraints with full information matrices, and switch variables.
//
// PoseGraph<Pose2> and PoseGraph<Pose3> are plain containers with no solver
// attached: the file readers fill them, the front end builds them, the back
// end optimises them. A vertex may have no initial pose (files with edges
// only); the back end initialises those.
//
// Thread-compatible: concurrent reads are safe, writes need exclusive access.
#ifndef CATGRAPH_BACKEND_GRAPH_POSE_GRAPH_H_
#define CATGRAPH_BACKEND_GRAPH_POSE_GRAPH_H_

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <map>
#include <optional>
#include <type_traits>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "backend/graph/closure.h"
#include "backend/graph/ids.h"
#include "backend/graph/pose2.h"
#include "backend/graph/pose3.h"

namespace catgraph {

template <typename PoseT>
using InformationMatrix = Eigen::Matrix<double, PoseT::kTangentDim, PoseT::kTangentDim>;

// A measured relative pose T_from^-1 * T_to with its information matrix (the
// inverse covariance, in the tangent order (x, y, theta) for 2D and
// (translation, rotation) for 3D, as g2o writes it).
template <typename PoseT>
struct RelativePoseMeasurement {
  PoseT mean;
  InformationMatrix<PoseT> information = InformationMatrix<PoseT>::Identity();
};

// What a robust solve decided about a loop closure, kept with the corrected
// graph (g2o: a #CATGRAPH_DECISION comment before the edge) so that every
// reader counts it as the solver did, whatever the method.
struct RobustDecision {
  bool accepted = true;
  double weight = 1.0;  // the residual's scale at the solution (switch or loss weight)
  friend bool operator==(const RobustDecision&, const RobustDecision&) = default;
};

template <typename PoseT>
struct Vertex {
  PoseId id;
  std::optional<PoseT> pose;  // nullopt: no initial guess in the source
  bool fixed = false;         // held constant by the solver (g2o FIX)
};

template <typename PoseT>
struct Constraint {
  ClosureId id;
  PoseId from;
  PoseId to;
  RelativePoseMeasurement<PoseT> measurement;
  ClosureKind kind = ClosureKind::kUnknown;
  Provenance provenance;
  std::optional<SwitchId> switch_id;     // set for a switchable constraint
  std::optional<double> maxmix_weight;   // set for a max-mixture constraint
  std::optional<RobustDecision> decision;  // set by a robust solve

  // Odometry in the sense of Vertigo's generator and the benchmark READMEs:
  // an edge between consecutive pose ids. Everything else is a loop closure.
  bool IsBetweenConsecutivePoses() const {
    return to.value() == from.value() + 1 || from.value() == to.value() + 1;
  }
};

template <typename PoseT>
struct PoseGraph {
  using Pose = PoseT;
  static constexpr int kDimension = std::is_same_v<PoseT, Pose2> ? 2 : 3;

  std::map<PoseId, Vertex<PoseT>> vertices;
  std::vector<Constraint<PoseT>> constraints;  // in source order
  std::map<SwitchId, SwitchVariable> switches;

  bool HasAllInitialPoses() const {
    for (const auto& [id, vertex] : vertices) {
      if (!vertex.pose) return false;
    }
    return true;
  }
  // The next unused ClosureId: one past the largest in use.
  ClosureId NextClosureId() const {
    ClosureId::ValueType next = 0;
    for (const auto& c : constraints) next = std::max(next, c.id.value() + 1);
    return ClosureId(next);
  }
  // False when `c` has a switch at 0.5 or below: a closure the robust back end
  // turned off (Suenderhauf & Protzel's decision rule).
  bool IsSwitchedOn(const Constraint<PoseT>& c) const {
    return !c.switch_id || switches.at(*c.switch_id).value > 0.5;
  }
  // Whether `c` counts as accepted: a robust solve's decision where it left
  // one (any method, readmission included), else its switch.
  bool IsAccepted(const Constraint<PoseT>& c) const {
    return c.decision ? c.decision->accepted : IsSwitchedOn(c);
  }
  // Gives every constraint that has no switch and satisfies `selected` a new
  // switch (initial value 1) with `prior`. Switch ids continue after every
  // vertex and switch id in use, as g2o's shared id space requires.
  template <typename Predicate>
  void AddSwitches(Predicate selected, const SwitchPrior& prior) {
    std::int64_t next = 0;
    for (const auto& [id, v] : vertices) next = std::max(next, id.value() + 1);
    for (const auto& [id, s] : switches) next = std::max(next, id.value() + 1);
    for (auto& c : constraints) {
      if (c.switch_id || !selected(c)) continue;
      const SwitchId id(next++);
      c.switch_id = id;
      switches.emplace(id, SwitchVariable{id, 1.0, prior});
    }
  }
};

using PoseGraph2 = PoseGraph<Pose2>;
using PoseGraph3 = PoseGraph<Pose3>;
// A graph whose dimension is known only at run time (read from a file).
using AnyPoseGraph = std::variant<PoseGraph2, PoseGraph3>;

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_POSE_GRAPH_H_
