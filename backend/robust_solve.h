// The stages of a robust pose-graph solve (OptimizePoseGraph), one method
// each, over the graph they change in turn (docs/backend.md):
//
//   ScaleGate       noise_scale    the gate, widened by the noise the graph's
//                                  short cycles show (GateOptions)
//   Initialise      initial_guess  the poses the options ask for; the
//                                  method's switches and the closures held off
//   SolveRobustly   robust_solve   the method at the gate (GNC's rounds
//                                  included); every loop closure decided
//   Narrow          narrow         the accepted closures decided again at the
//                                  calibrated gate, when their noise allows
//   Refine          refine         the poses re-solved by least squares over
//                                  the odometry and the accepted closures
//   Readmit         readmit        the rejected closures tested against the
//                                  refined map, the map refined with those
//                                  that pass
//   Finish          costs          chi2 and the chordal cost; the result
//
// Run calls them in order; each skips itself where the options or the
// stages before leave it nothing to do, and records its StageTime when it
// runs. A caller (a test, a bench) may call them one by one, in the same
// order, and look at the graph and the result between them. Defined for
// Pose2 and Pose3. Thread-compatible.
#ifndef CATGRAPH_BACKEND_ROBUST_SOLVE_H_
#define CATGRAPH_BACKEND_ROBUST_SOLVE_H_

#include <chrono>
#include <functional>
#include <map>
#include <set>
#include <vector>

#include "backend/factor_graph.h"
#include "backend/graph/pose_graph.h"
#include "backend/pose_graph_optimizer.h"
#include "backend/robust_losses.h"

namespace catgraph {

template <typename PoseT>
class RobustSolve {
 public:
  // Throws std::invalid_argument on bad options (Validate).
  RobustSolve(PoseGraph<PoseT> graph, const PoseGraphOptimizerOptions& options);

  // Every stage in order.
  PoseGraphOptimization Run();

  void ScaleGate();
  // Throws std::invalid_argument for disabled or coupled closures the graph
  // does not have.
  void Initialise();
  void SolveRobustly();
  void Narrow();
  void Refine();
  void Readmit();
  // The result; the object is spent.
  PoseGraphOptimization Finish();

  // The gate the method decides at (after ScaleGate: widened by the noise scale).
  double gate() const { return gate_; }
  const PoseGraph<PoseT>& graph() const { return graph_; }
  // The result so far (`graph` is filled in by Finish).
  const PoseGraphOptimization& result() const { return out_; }

 private:
  using Poses = std::map<PoseId, Vertex<PoseT>>;

  // Ends a stage: its time is the wall clock since the last stage ended.
  double EndStage(const char* stage, int iterations);
  // Whether the method applies to constraint c.
  bool IsRobust(const Constraint<PoseT>& c) const;
  // The poses as variables of `factors`, and the gauge.
  void AddPoses(FactorGraph& factors, Values& values, const Poses& poses) const;
  void TakePoses(const Values& values);
  // The poses and the switches the solve may change.
  void TakeSolution(const Values& values);
  // One solve of the whole graph; `gnc_weights`, when given, scales each
  // robust closure's chi2 (a zero weight leaves the closure out).
  Summary Solve(const std::map<ClosureId, double>* gnc_weights, int max_iterations);
  // The robust solve at the gate g, over the closures not held off.
  Summary SolveAtGate(double g);
  // What the last solve decided about loop closure c ...
  ClosureDecision Decide(const Constraint<PoseT>& c) const;
  // ... about every loop closure, in graph order; where `kept` (an earlier
  // solve's decisions) rejected one, that decision.
  std::vector<ClosureDecision> DecideAll(const std::vector<ClosureDecision>* kept) const;
  // The odometry and the accepted closures at full weight, over `poses`.
  void AddMap(FactorGraph& factors, Values& values, const Poses& poses) const;
  // Least squares over the map from the current poses and, with
  // `from_initial_guess`, from the initial guess; the lower cost wins.
  Summary RefineFrom(bool from_initial_guess);
  double Psi(double s) const;

  PoseGraph<PoseT> graph_;
  const PoseGraphOptimizerOptions options_;
  PoseGraphOptimization out_;
  std::chrono::steady_clock::time_point stage_start_;

  double gate_ = 0.0;
  RobustLoss loss_;
  Poses initial_poses_;
  bool method_decides_any_ = false;  // closures without the file's switches
  bool robust_solve_ = false;        // any method, or the file's switches
  std::set<SwitchId> added_switches_;  // the method's, as opposed to the file's
  // Closure -> switch, for the coupled switches; the disabled closures'
  // switches. Closures held off are left out of a solve: the disabled ones,
  // and in the narrowed solve the ones the first rejected, whose switches
  // are then held at their values (`frozen_switches_`).
  std::map<ClosureId, SwitchId> switch_of_;
  std::set<SwitchId> disabled_switches_, frozen_switches_;
  std::set<ClosureId> held_off_;
  std::map<ClosureId, std::vector<SwitchId>> coupled_switches_;
  std::map<ClosureId, double> gnc_weights_;
  // The robust solve's stop test (RefinementOptions::stop_when_settled).
  std::function<bool(const Values&, double)> settled_;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_ROBUST_SOLVE_H_
