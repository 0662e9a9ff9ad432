// The back end over a front end's result, and the offline pipeline: the
// front end's pose graph solved robustly under the closure hierarchy, the
// back end's verdict fed back to CAT-Graph+, and how the result scores
// against ground truth — closures by kind, injected false visual closures
// and their children, the ATE of odometry alone and of the corrected map.
// Behind `catgraph map` and `hierarchy-experiment` (docs/mapping.md).
#ifndef CATGRAPH_MAPPING_MAP_DATASET_H_
#define CATGRAPH_MAPPING_MAP_DATASET_H_

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "backend/evaluation.h"
#include "backend/graph/trajectory.h"
#include "backend/io/dataset.h"
#include "backend/pose_graph_optimizer.h"
#include "frontend/localization.h"
#include "hierarchy/closure_hierarchy.h"

namespace catgraph::mapping {

// Ground truth at every frame (vertex id = frame index); empty without truth.
Trajectory2 TruthAtFrames(const Dataset& d);

// A front end's pose graph carries no switches, so the coupled hierarchy,
// which couples them, needs the switchable method. Throws
// std::invalid_argument otherwise.
void CheckHierarchyForFrontEnd(const HierarchyOptions& hierarchy, const PoseGraphOptimizerOptions& optimizer);

// The hierarchy options of a policy name ("cascade", "coupled", "flat"),
// checked by CheckHierarchyForFrontEnd. Throws std::invalid_argument.
HierarchyOptions HierarchyOptionsFor(const std::string& policy, const PoseGraphOptimizerOptions& optimizer);

// Closures of one kind and how the back end decided them.
struct KindCounts {
  int count = 0, accepted = 0;
  std::vector<double> errors, accepted_errors;  // against ground truth
  ErrorStatistics all, kept;                    // of errors and accepted_errors
};

// The injected false visual closures (LoopClosure::injected) and their
// children (inferred closures with a false parent), and what became of them.
struct InjectionOutcome {
  int parents = 0, parents_rejected = 0;
  int children = 0, children_accepted = 0;
  std::vector<double> accepted_child_errors;  // against ground truth
  // Children with a rejected false parent: how many, how many the back end
  // still accepted (none under cascade and coupled), and how many the
  // hierarchy turned off (the rest were rejected on their own).
  int children_of_rejected = 0, children_of_rejected_accepted = 0, children_turned_off = 0;
};

struct MapOutcome {
  HierarchicalOptimization solved;
  std::map<ClosureId, ClosureDecision> decision_of;
  std::map<ClosureId, ClosureId> turned_off_by;  // child -> parent
  std::map<ClosureKind, KindCounts> by_kind;     // visual and inferred, present even when empty
  InjectionOutcome injection;
  std::optional<TrajectoryEvaluation> ate_odometry, ate_corrected;  // with ground truth
};

// Solves the front end's graph under the hierarchy and scores it against
// `truth` (TruthAtFrames; may be empty); vetoed closures are held off
// (rejected, as the back end decided before). Throws std::runtime_error when
// the solver fails.
MapOutcome SolveMap(const LocalizationResult& r, const PoseGraphOptimizerOptions& optimizer,
                    const HierarchyOptions& hierarchy, const Trajectory2& truth);

// The back end's verdict fed back to CAT-Graph+. A false visual closure
// does harm beyond its own edge and its children: CAT-Graph+ validated the
// pending inferences at it (d_tot), discarding true ones that disagree, and
// re-initialised its odometric filter there. Hierarchy policies cascade and
// coupled turn the children off; feedback then re-runs the front end with the
// rejected visual closures vetoed (LocalizationOptions::vetoed_frames), so
// CAT-Graph+ carries its inferences across them to the next closure, and
// solves again with the vetoed closures held off; until the back end rejects
// no further visual closure, or after `max_reruns` re-runs. Each re-run uses
// the options `front` was made with (LocalizationResult::options) plus the
// vetoes. Policy flat (the comparison without a hierarchy) and a front end
// without CAT-Graph+ are solved once.
inline constexpr int kDefaultFeedbackReruns = 3;
struct MappingResult {
  LocalizationResult front;  // the last front-end run
  MapOutcome outcome;        // its solve
  MapOutcome first;          // the first solve, before any re-run
  int reruns = 0;
};
MappingResult SolveWithFeedback(const Dataset& d, const std::vector<Observation>& observations,
                                const ObservationModel& model, LocalizationResult front,
                                const PoseGraphOptimizerOptions& optimizer, const HierarchyOptions& hierarchy,
                                const Trajectory2& truth, int max_reruns = kDefaultFeedbackReruns);

// The whole offline pipeline: the front end over every frame (Localize, the
// frames streamed through the Localizer as the online Mapper streams them),
// then SolveWithFeedback, scored against the dataset's ground truth when it
// has one.
MappingResult MapDataset(const Dataset& d, const std::vector<Observation>& observations,
                         const ObservationModel& model, const LocalizationOptions& front_end,
                         const PoseGraphOptimizerOptions& optimizer, const HierarchyOptions& hierarchy,
                         int max_reruns = kDefaultFeedbackReruns);

}  // namespace catgraph::mapping

#endif  // CATGRAPH_MAPPING_MAP_DATASET_H_
