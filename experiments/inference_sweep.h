// CAT-Graph+ over a grid of total-path (d_tot) and local (d_loc) validation
// tolerances, the CAT-Graph+ paper's Table III: how many inferences each
// cell makes and how many of them are false against ground truth, with the
// front end alone or mapped as mapping::MapDataset maps (the back end's
// verdict fed back). Behind `catgraph inference-sweep` (docs/catgraph-plus.md).
#ifndef CATGRAPH_EXPERIMENTS_INFERENCE_SWEEP_H_
#define CATGRAPH_EXPERIMENTS_INFERENCE_SWEEP_H_

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "backend/io/dataset.h"
#include "backend/pose_graph_optimizer.h"
#include "frontend/localization.h"
#include "frontend/observation_model.h"
#include "hierarchy/closure_hierarchy.h"

namespace catgraph {

struct InferenceSweepOptions {
  LocalizationOptions front_end;  // CAT-Graph+ is switched on in every cell
  std::vector<double> d_tot_m = {0.5, 1.0, 2.5, 5.0, 7.5, 10.0, 12.5};
  std::vector<double> d_loc_m = {0.5, 1.0, 2.5, 5.0, 7.5, 10.0};
  double false_threshold_m = 1.0;  // an inference farther than this from the truth is false; > 0
  // Each cell mapped with this back end and hierarchy, the rejected visual
  // closures vetoed and CAT-Graph+ re-run (mapping::SolveWithFeedback);
  // unset: the front end alone.
  struct BackEnd {
    PoseGraphOptimizerOptions optimizer;
    HierarchyOptions hierarchy;
  };
  std::optional<BackEnd> back_end;
};

struct InferenceSweepCell {
  double d_tot_m = 0.0, d_loc_m = 0.0;
  // The inferences of the (last) front-end run, how many are false, the
  // largest error, the mean error of the false ones and of all (m; 0 for none).
  int inferred = 0, wrong = 0;
  double largest_error_m = 0.0, mean_false_error_m = 0.0, mean_error_m = 0.0;
  std::size_t discarded = 0;  // by total-path validation
  std::size_t dropped = 0;    // with no visual closure to validate them
  // With a back end: the false inferences it accepted, and the front end's
  // re-runs.
  std::optional<std::size_t> false_accepted;
  int reruns = 0;
};

// Every cell, d_tot major, in the options' order. `progress(done, total)`
// after each. Throws std::invalid_argument for a dataset without ground
// truth or options out of range.
std::vector<InferenceSweepCell> RunInferenceSweep(
    const Dataset& d, const std::vector<Observation>& observations, const ObservationModel& model,
    const InferenceSweepOptions& options,
    const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace catgraph

#endif  // CATGRAPH_EXPERIMENTS_INFERENCE_SWEEP_H_
