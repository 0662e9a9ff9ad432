// Scoring an estimate against ground truth: trajectory error (ATE, anchored
// RMSE, RPE) and the precision and recall of the loop closures a robust back
// end accepted. The definitions follow robust-backend-notes.md §2 and the TUM
// benchmark (Sturm et al. 2012); docs/evaluation.md spells them out.
#ifndef CATGRAPH_BACKEND_EVALUATION_H_
#define CATGRAPH_BACKEND_EVALUATION_H_

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "backend/graph/closure_label.h"
#include "backend/graph/pose_graph.h"
#include "backend/graph/trajectory.h"

namespace catgraph {

// Summary of a list of non-negative errors; all zero for an empty list.
struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};

ErrorStatistics StatisticsOf(std::vector<double> errors);

struct TrajectoryEvaluation {
  std::size_t poses = 0;  // poses compared: every pose of the estimate
  // Absolute trajectory error: position error after the rigid SE(2)/SE(3)
  // alignment (no scale) of the estimate's positions onto the truth's that
  // minimises it (Umeyama 1991).
  ErrorStatistics ate_m;
  // Position RMSE after moving the estimate so that its first pose coincides
  // with the truth's first pose (position and orientation).
  double rmse_anchored_m = 0.0;
  // Relative pose error between consecutive poses (by id): the translation
  // and rotation of (T_truth_k^-1 T_truth_k+1)^-1 (T_est_k^-1 T_est_k+1).
  ErrorStatistics rpe_translation_m;
  ErrorStatistics rpe_rotation_rad;
};

// Every pose of `estimate` must be in `truth` (extra truth poses are
// ignored); throws std::invalid_argument naming the first missing id, or for
// fewer than 2 poses. A 3D truth of a 2D estimate (or the reverse) is
// converted as trajectory.h does.
template <typename PoseT>
TrajectoryEvaluation EvaluateTrajectory(const Trajectory<PoseT>& estimate,
                                        const Trajectory<PoseT>& truth);
TrajectoryEvaluation EvaluateTrajectory(const AnyTrajectory& estimate, const AnyTrajectory& truth);

// The rigid transform T (no scale) for which T * estimate's positions lie
// closest to the truth's in the least-squares sense: the alignment behind
// the ATE above, for drawing an estimate where the ATE measured it. Same
// requirements and errors as EvaluateTrajectory.
template <typename PoseT>
PoseT AlignmentOnto(const Trajectory<PoseT>& estimate, const Trajectory<PoseT>& truth);

// What the back end decided about one loop closure of its output.
struct ClosureOutcome {
  PoseId from, to;
  bool accepted = true;
  // The closure's chi2 at the true poses (AttachChi2AtTruth); NaN unknown.
  double chi2_at_truth = std::numeric_limits<double>::quiet_NaN();
};

// The loop closures of an optimised graph: accepted unless switched off
// (switch <= 0.5). Constraints between consecutive poses are not loop closures.
std::vector<ClosureOutcome> ClosureOutcomesOf(const AnyPoseGraph& graph);

struct ClosureScores {
  std::size_t true_positives = 0;   // inliers accepted
  std::size_t false_positives = 0;  // outliers accepted
  std::size_t true_negatives = 0;   // outliers rejected
  std::size_t false_negatives = 0;  // inliers rejected
  // TP / (TP + FP); 1 when nothing was accepted (no false acceptance).
  double precision = 1.0;
  // TP / (TP + FN); 1 when there is no inlier.
  double recall = 1.0;
  double f1 = 1.0;  // harmonic mean of precision and recall; 0 when both are 0
  // Labelled false, yet explained by the ground truth: chi2 at the true
  // poses within the truth gate. Vertigo's protocol draws a false
  // measurement near the identity (robust-backend-notes.md §2), so a
  // "local" pair whose poses really lie that close is false by its label
  // only. Zero without chi2_at_truth.
  std::size_t outliers_explained_by_truth = 0;
  std::size_t explained_outliers_accepted = 0;
  // Share of the outliers rejected: TN / (TN + FP), and the same among the
  // outliers the truth does not explain; 1 when there are none.
  double outlier_rejection = 1.0;
  double unexplained_outlier_rejection = 1.0;
};

// Matches every label to the first unused outcome with the same endpoints
// (either direction), in order, so that a false edge duplicating a true
// closure's endpoints is told apart by position, as inject appends it after
// the original. A label without an outcome counts as rejected (an output
// written with rejected closures dropped).
// `truth_gate`: an outlier whose chi2_at_truth is at most this counts as
// explained by the truth (the optimiser's gate: ChiSquareQuantile(dof,
// 0.999)).
ClosureScores ScoreClosures(const std::vector<ClosureOutcome>& outcomes,
                            const std::vector<ClosureLabel>& labels, double truth_gate = 0.0);

// What keeps `labels` from scoring the loop closures of `graph`, else
// nothing: a label naming a pose the graph lacks, more labels than closures
// between two poses (a row repeated), or a closure without a label (rows
// missing). `label` is the index of the label at fault, when one is.
struct LabelMismatch {
  std::optional<std::size_t> label;
  std::string message;
};
std::optional<LabelMismatch> FindLabelMismatch(const AnyPoseGraph& graph, const std::vector<ClosureLabel>& labels);

// Sets each outcome's chi2_at_truth from the loop closure of `graph` with the
// same endpoints (either direction, matched in order as ScoreClosures does)
// at the poses of `truth`: the closures' measurements come from the graph,
// the decisions may come from elsewhere (an optimiser's report). Left NaN
// where the graph lacks the closure or the truth an endpoint.
void AttachChi2AtTruth(std::vector<ClosureOutcome>& outcomes, const AnyPoseGraph& graph,
                       const AnyTrajectory& truth);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_EVALUATION_H_
