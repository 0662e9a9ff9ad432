// The Mapper's back end between frames: the front end's pose graph as it
// grows, on one IncrementalOptimizer that keeps its variables and factors
// from solve to solve. Switchable constraints as PoseGraphOptimizer builds
// them (a switch per loop closure, its prior at the gate's information,
// odometry plain); poses and switches start from the last solve, new poses
// chained to the last solved one by odometry; the hierarchy's cascade turns
// the children of rejected closures off (their factors out, their switches
// held at 0) and solves again, as OptimizeWithHierarchy does; a child
// stays off until a solve accepts all its parents, and then comes back on
// from its prior (OptimizeWithHierarchy, from scratch each call, starts
// with every child on).
//
// What it saves against a PoseGraphOptimizer call per frame is the copy of
// the graph, the problem's construction and teardown and the elimination
// order's analysis (BENCHMARKS.md); the map it converges to is the same
// problem's. Thread-compatible.
#ifndef CATGRAPH_MAPPING_ONLINE_BACK_END_H_
#define CATGRAPH_MAPPING_ONLINE_BACK_END_H_

#include <map>
#include <set>

#include "backend/graph/pose_graph.h"
#include "backend/graph/trajectory.h"
#include "backend/optimizer.h"
#include "backend/pose_graph_optimizer.h"
#include "hierarchy/closure_hierarchy.h"

namespace catgraph::mapping {

class OnlineBackEnd {
 public:
  // Whether `options` and the hierarchy can be solved incrementally: the
  // switchable method on loop closures only, from the last solution
  // without the stages that measure or re-decide from scratch (as
  // OnlineSolveOptions leaves them), no closures disabled or coupled by the
  // caller, and a hierarchy policy other than coupled. The Mapper re-solves
  // from scratch otherwise.
  static bool Supports(const PoseGraphOptimizerOptions& options, const HierarchyOptions& hierarchy);

  // Throws std::invalid_argument when Supports() is false or an option is
  // out of range.
  OnlineBackEnd(const PoseGraphOptimizerOptions& options, const HierarchyOptions& hierarchy);

  // Takes the vertices and constraints `graph` has beyond those of the last
  // call (the front end only appends; a vertex or constraint it holds must
  // not change) and solves. The first vertex (and any fixed one) is held
  // constant. Throws std::invalid_argument when `graph` does not extend
  // the last one, or a constraint carries a switch of its own.
  struct Solve {
    Summary summary;  // the last solve of the call (the cascade's last round)
    int solves = 0;   // rounds
    std::size_t accepted = 0, rejected = 0;  // closures, the hierarchy's decisions applied
  };
  Solve Update(const PoseGraph2& graph);

  // The last solve's poses.
  Trajectory2 Poses() const;
  // What the last solve decided about each closure (children turned off
  // rejected, with weight 0).
  const std::map<ClosureId, ClosureDecision>& decisions() const { return decisions_; }

 private:
  struct Closure {
    Constraint<Pose2> constraint;
    IncrementalOptimizer::FactorHandle factor = 0, prior = 0;
    bool on = true;
  };
  void Add(const Constraint<Pose2>& c);
  void TurnOn(Closure& closure, bool on);
  void Decide();

  const PoseGraphOptimizerOptions options_;
  const HierarchyOptions hierarchy_options_;
  SwitchPrior prior_;
  IncrementalOptimizer optimizer_;
  ClosureHierarchy hierarchy_;
  std::map<PoseId, Pose2> odometry_;  // the vertices taken, at their odometry poses
  std::size_t constraints_ = 0;       // of the graph taken
  std::map<ClosureId, Closure> closures_;
  std::map<ClosureId, ClosureDecision> decisions_;
};

}  // namespace catgraph::mapping

#endif  // CATGRAPH_MAPPING_ONLINE_BACK_END_H_
