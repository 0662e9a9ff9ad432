// Robust optimisation of a PoseGraph: builds the FactorGraph for the chosen
// method, solves it, and reports what it decided about every loop closure.
//
// Robust treatment applies to loop closures (every constraint whose kind is
// not odometry); odometry is trusted unless `robust_odometry` is set.
// Constraints that already carry a switch (Vertigo's switchable tags) are
// optimised as written, with their own switches and priors, whatever the
// method.
#ifndef CATGRAPH_BACKEND_POSE_GRAPH_OPTIMIZER_H_
#define CATGRAPH_BACKEND_POSE_GRAPH_OPTIMIZER_H_

#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "backend/factors.h"
#include "backend/graph/pose_graph.h"
#include "backend/noise_scale.h"
#include "backend/optimizer.h"

namespace catgraph {

enum class RobustMethod {
  kNone,        // plain least squares
  kSwitchable,  // switchable constraints (Suenderhauf & Protzel 2012)
  kDcs,         // dynamic covariance scaling (Agarwal et al. 2013)
  kCauchy,      // Ceres' Cauchy loss
  kHuber,       // Ceres' Huber loss
  kGnc,         // truncated least squares by graduated non-convexity (Yang et al. 2020)
};

std::string_view ToString(RobustMethod method);
std::optional<RobustMethod> RobustMethodFromString(std::string_view text);
std::vector<std::string> RobustMethodNames();  // every spelling RobustMethodFromString accepts

enum class InitialGuess {
  kFile,          // the file's poses; missing ones chained along a spanning tree
  kSpanningTree,  // every pose chained along a spanning tree, odometry first
  kChordal,       // chordal (rotation-first) initialisation of every pose
  // kFile or kChordal, whichever has the lower robust cost: the cost (chi2,
  // or the chordal cost with `cost` kChordal) of the trusted constraints
  // plus, for the robust ones, min(cost, gate) (the truncated least-squares
  // cost the gate decides by; the plain cost for method none). A file's
  // poorly chained odometry (MIT) loses to chordal; a chordal guess bent by
  // false closures loses to the file's.
  kAuto,
};

std::string_view ToString(InitialGuess guess);
std::optional<InitialGuess> InitialGuessFromString(std::string_view text);

// The chi2 gate every method decides at, scaled by the noise the graph
// shows, and narrowed after the robust solve (docs/backend.md).
struct GateOptions {
  // The default needs no per-dataset tuning. For one closure with
  // chi2 = e^T Omega e, the switchable objective s^2 chi2 + xi (1 - s)^2 is
  // least at s = xi / (xi + chi2), so s > 0.5 exactly when chi2 < xi: the
  // switch-prior information xi is a chi2 gate. Measured in each closure's
  // own information, it is the same for every dataset: xi is set to the
  // chi2(dof) quantile at `probability` (2D: 16.27, 3D: 22.46).
  // With the chordal cost, chi2 is the closure's chordal cost and the gate
  // its quantile under the closure's own noise (ChordalCostQuantile: 2D
  // 24.58, 3D 68.48).
  // A fixed xi = 1 (Vertigo's) instead rejects a true closure whenever its
  // error exceeds one sigma overall (docs/backend.md).
  double probability = 0.999;  // (0, 1)
  // The gate assumes the information is right (or conservative). When short
  // cycles of the graph show its noise to be at least
  // `noise_scale_threshold` times the variance its information states
  // (EstimateNoiseScale, noise_scale.h), every gate-derived default (the
  // switch prior, DCS's Phi, the loss scales, GNC's threshold, kAuto's
  // truncation) is widened by the factor measured. A graph whose
  // information is right or conservative is unaffected. Off: false.
  bool estimate_noise_scale = true;
  double noise_scale_threshold = 3.0;  // > 1
  NoiseScaleOptions noise_scale;
  // The other way: a file whose information states more noise than its
  // measurements carry lets false closures near the truth pass the gate. After
  // the robust solve the short cycles of the accepted closures
  // alone measure the noise again (the rejected ones belong to no cycle).
  // When at least `narrow_min_cycles` of them show Gaussian noise of one
  // variance (the scale at NoiseScaleOptions' upper quantile at most
  // `narrow_max_tail_ratio` times the scale at its lower one; real front
  // ends' heavier tails measure 1.8 and more) and the calibrated gate below is
  // at most the gate over `noise_scale_threshold`, the accepted closures are
  // decided again, from the solve's poses, with the rejected ones held off as
  // they are. The calibrated gate is the upper scale times the quantile at
  // 1 - (1 - probability) / n for the n closures tested: in the
  // noise's own units, and family-wise, so that with probability
  // `probability` no true closure among them is rejected. Needs
  // `estimate_noise_scale` and a method deciding at the gate (no explicit
  // switch prior, Phi or loss scale).
  // The second solve starts from the first one's map, which the false
  // closures it accepted have bent; when they bent it far, the tight gate
  // switches off true closures before the map can unbend. So when it
  // rejects more than `narrow_max_rejected_share` of the closures the first
  // accepted (the calibrated gate expects none of them but the false ones),
  // the first solve's result stands.
  bool narrow = true;
  double narrow_max_tail_ratio = 1.25;     // >= 1
  int narrow_min_cycles = 100;             // >= 1
  double narrow_max_rejected_share = 0.1;  // (0, 1]
};

// The refinement after a robust solve (docs/backend.md).
struct RefinementOptions {
  // After a robust solve (any method but none, or a file with switches), keep
  // its decisions and re-solve the poses by plain least squares without the
  // rejected closures and with the accepted ones at full weight: a rejected
  // closure keeps a weight of up to 0.5 in the robust solve, and many of
  // them together bend the map (docs/backend.md).
  bool enabled = true;
  // When enabled, the robust solve's map is replaced, and only its
  // decisions are kept: it ends as soon as they have settled, that is when
  // no decision has changed over the last `settled_iterations` iterations
  // that lowered the cost and the last of them lowered it by less than
  // `settled_decrease` (relative), instead of polishing a map the
  // refinement re-solves. Not for GNC, whose rounds have their own schedule.
  // Off: false.
  bool stop_when_settled = true;
  int settled_iterations = 2;      // >= 1
  double settled_decrease = 1e-4;  // > 0
};

// The test of the rejected closures after the refinement (docs/backend.md).
struct ReadmissionOptions {
  // The gate decides each closure by its own chi2, on a map
  // that false closures may still bend, and at a per-closure level: of n
  // true closures it rejects n (1 - probability) on average,
  // and more where the noise has heavier tails than one Gaussian (SE-Sync's
  // manhattan: 22 of 1954). So after the refinement every closure the
  // method rejected by its own weight is tested once more, on the refined
  // map (the odometry and the accepted closures): by its innovation r^T (I +
  // J Sigma J^T)^-1 r (whitened residual r, Jacobian J, the map's joint
  // covariance Sigma of the closure's poses), which counts the map's own
  // uncertainty as a closure's chi2 does not, at the family-wise gate: the
  // gate's factor times the quantile at 1 - (1 - probability) /
  // n for the n closures the method decided. A closure that passes is
  // accepted (`readmitted`, weight and switch 1), and the map refined again
  // with it. Needs the refinement, the g2o cost and a method deciding at the gate;
  // not after a narrowed solve, whose gate is already family-wise in the
  // noise's own units. Off: false.
  bool enabled = true;
};

struct PoseGraphOptimizerOptions {
  RobustMethod method = RobustMethod::kSwitchable;
  InitialGuess initial_guess = InitialGuess::kAuto;
  // The objective; kChordal is SE-Sync's F (with switches: Psi(s)^2 times
  // each closure's chordal cost).
  RelativePoseCostType cost = RelativePoseCostType::kG2o;
  SwitchFunction switch_function = SwitchFunction::kLinear;
  GateOptions gate;
  // Xi^-1 given explicitly (> 0) overrides the gate; 0 = use the gate.
  double switch_prior_information = 0.0;
  // DCS: Phi, the chi2 beyond which a closure is down-weighted; > 0, or 0
  // for gate / 3, which puts DCS's decision (scale > 0.5) at the switchable
  // gate: 5.42 in 2D, 7.49 in 3D (Agarwal et al. use 1 in 2D).
  double dcs_phi = 0.0;
  // Huber / Cauchy: the residual norm, in sigmas, where the loss bends; > 0,
  // or 0 to put the decision at the gate: Cauchy sqrt(gate / 3) (2.33 in
  // 2D), Huber sqrt(gate / 16) (1.01 in 2D).
  double loss_scale_sigma = 0.0;
  // GNC: mu grows by this factor per round (Yang et al. use 1.4); > 1. The
  // truncation threshold is the same chi2 gate as the switch prior's.
  double gnc_mu_step = 1.4;
  int gnc_max_rounds = 100;  // weighted solves at most; >= 1
  int gnc_round_iterations = 50;  // LM iterations per solve after the first; >= 1
  bool robust_odometry = false;  // also apply the method to odometry
  // Coupled switches (the closure hierarchy's `coupled` policy): the residual
  // of closure c is also scaled by the switches of the closures in
  // coupled_closures[c], so that switching one of them off switches c off
  // in the same solve. Every closure named must have a switch (method
  // switchable, or switches in the file). Closure c is then accepted when its
  // own switch and every coupled switch are above 0.5; its weight is the
  // product it was scaled by.
  std::map<ClosureId, std::vector<ClosureId>> coupled_closures;
  // Closures held off (the closure hierarchy's `cascade` policy): left out of
  // the solve, reported rejected with weight 0, their switches (if any) at 0.
  std::set<ClosureId> disabled_closures;
  RefinementOptions refinement;
  ReadmissionOptions readmission;
  OptimizerOptions solver;
};

void Validate(const PoseGraphOptimizerOptions& options);

// The gate every method decides at (docs/backend.md), before any noise
// scaling: the quantile at `probability` of a true closure's squared
// residual norm, chi2(dof) for g2o's error (2D 16.27, 3D 22.46 at 0.999),
// the chordal cost's own distribution for the chordal one. Defined for
// Pose2 and Pose3.
template <typename PoseT>
double Gate(RelativePoseCostType cost, double probability);

// What the optimiser decided about one loop closure.
struct ClosureDecision {
  ClosureId id;
  PoseId from, to;
  ClosureKind kind = ClosureKind::kUnknown;
  // What the residual is scaled by: the switch Psi(s), or sqrt(rho'(chi2))
  // for a robust loss (DCS: its scale min(1, 2 Phi / (Phi + chi2))), GNC's
  // final weight; 1 for `none`.
  double weight = 1.0;
  // The closure's own switch or loss weight: `weight` without the coupled
  // switches (PoseGraphOptimizerOptions::coupled_closures).
  double own_weight = 1.0;
  // own_weight > 0.5, and every coupled switch too; false for a disabled
  // closure; true for a readmitted one.
  bool accepted = true;
  // Rejected by the robust solve, accepted by the innovation test
  // (PoseGraphOptimizerOptions::readmission); its weight is then 1.
  bool readmitted = false;
};

// One stage of OptimizePoseGraph and its wall-clock time: everything the
// stage does, building its problems included.
struct StageTime {
  // noise_scale, initial_guess, robust_solve, narrow (the inliers' noise
  // measured and, when it ran, the second robust solve), refine, readmit (the
  // innovation tests and the refinements after them), costs (chi2 and the
  // chordal cost of the result).
  std::string stage;
  double time_s = 0.0;
  int iterations = 0;  // solver iterations; 0 for a stage that solves nothing
};

struct PoseGraphOptimization {
  // The input with optimised poses; with switches (new and old) and their
  // solved values; new switches are attached to their constraints.
  AnyPoseGraph graph;
  // The initial guess used: kAuto's choice, or the one asked for.
  InitialGuess initial_guess = InitialGuess::kFile;
  // Seconds spent on the initial guess (kAuto: both guesses and their costs);
  // not part of TotalTimeS().
  double initial_guess_time_s = 0.0;
  // The noise scale measured (PoseGraphOptimizerOptions::estimate_noise_scale)
  // and the factor the gate was widened by: the scale, or 1 below the
  // threshold, without an estimate, or when not asked for.
  NoiseScaleEstimate noise_scale;
  double gate_factor = 1.0;
  Summary summary;  // the robust solve
  // Narrowing (GateOptions::narrow): the noise measured on
  // the accepted closures' cycles (cycles 0 when not measured), the
  // calibrated gate over the first (1 when it did not run or its result was
  // not kept), the second robust solve, when it ran, and how many closures
  // the first accepted it rejected. When it succeeded and rejected at most
  // narrow_max_rejected_share of them, its decisions are `closures`;
  // otherwise the first solve's result stands.
  NoiseScaleEstimate inlier_noise_scale;
  double narrow_factor = 1.0;
  std::optional<Summary> narrowed;
  std::size_t narrow_newly_rejected = 0;
  // The refinement solve, when it ran (RefinementOptions).
  // If it failed, `graph` holds the robust solve's poses.
  std::optional<Summary> refinement;
  // Readmission (PoseGraphOptimizerOptions::readmission): how many closures it
  // accepted, the seconds its test took, and the refinement with them, when
  // it ran. If that failed, the first refinement and its decisions stand.
  std::size_t readmitted = 0;
  double readmit_test_time_s = 0.0;
  std::optional<Summary> readmission;
  // The times (Summary::time_s and its breakdown) of the robust solves, the
  // refinements and the readmission test together; TotalTimeS() is their
  // time_s.
  Summary SolveTimes() const {
    Summary times;
    times.AddTimes(summary);
    if (narrowed) times.AddTimes(*narrowed);
    if (refinement) times.AddTimes(*refinement);
    if (readmission) times.AddTimes(*readmission);
    times.time_s += readmit_test_time_s;
    return times;
  }
  double TotalTimeS() const { return SolveTimes().time_s; }
  // The stages that ran, in order: from the noise scale to the result's costs,
  // the whole solve but for copying the input.
  std::vector<StageTime> stages;
  double WallTimeS() const;
  std::vector<ClosureDecision> closures;  // every loop closure, in graph order
  std::size_t accepted = 0;
  std::size_t rejected = 0;
  double chi2 = 0.0;  // g2o's chi2 of `graph` (see Chi2())
  double chordal_cost = 0.0;  // SE-Sync's F of `graph` (see ChordalCost())
};

// Poses are first initialised as `options.initial_guess` says. Throws
// std::invalid_argument on bad options.
PoseGraphOptimization OptimizePoseGraph(const AnyPoseGraph& graph,
                                        const PoseGraphOptimizerOptions& options = {});

// g2o's chi2 at the graph's poses: sum over constraints of e^T Omega e,
// scaled by Psi(s)^2 for switched constraints, plus the switch priors'
// information * (gamma - s)^2. Linear Psi.
double Chi2(const AnyPoseGraph& graph);

// SE-Sync's objective F at the graph's poses (robust-backend-notes.md §3):
// sum over constraints of kappa |R_j - R_i R_ij|_F^2 + tau |t_j - t_i - R_i t_ij|^2,
// switches ignored. Compare with SE-Sync's certified optima.
double ChordalCost(const AnyPoseGraph& graph);

// Removes every constraint whose switch is <= 0.5 or whose id is in
// `rejected`, and every switch: the graph to hand to a planner.
AnyPoseGraph DropRejected(const AnyPoseGraph& graph, const std::vector<ClosureDecision>& decisions);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_POSE_GRAPH_OPTIMIZER_H_
