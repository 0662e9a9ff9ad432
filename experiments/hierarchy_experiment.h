// What the closure hierarchy buys against false visual matches at the
// source: for each seed, the front end without and with injected false
// matches (false_matches.h), and with them vetoed from the start (the
// oracle: perfect rejection and feedback), each mapped under every
// hierarchy policy with the back end's verdict fed back
// (mapping::SolveWithFeedback). Behind `catgraph hierarchy-experiment`
// (docs/mapping.md).
#ifndef CATGRAPH_EXPERIMENTS_HIERARCHY_EXPERIMENT_H_
#define CATGRAPH_EXPERIMENTS_HIERARCHY_EXPERIMENT_H_

#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "backend/io/dataset.h"
#include "backend/pose_graph_optimizer.h"
#include "experiments/false_matches.h"
#include "frontend/localization.h"
#include "frontend/observation_model.h"
#include "mapping/map_dataset.h"

namespace catgraph {

struct HierarchyExperimentOptions {
  LocalizationOptions front_end;        // its seed is each run's
  PoseGraphOptimizerOptions back_end;
  std::vector<std::string> hierarchies = {"cascade", "coupled", "flat"};  // mapping::HierarchyOptionsFor
  std::vector<std::uint64_t> seeds = {1, 2, 3, 4, 5};                    // the filter's and the plan's
  FalseMatchOptions injection{.count = 10};                              // its seed is each run's
  int feedback_reruns = mapping::kDefaultFeedbackReruns;
};

struct HierarchyExperimentRow {
  std::uint64_t seed = 0;
  std::string hierarchy;
  mapping::InjectionOutcome injection;  // of the first solve with the false matches
  // ATE (RMSE after alignment) of the final map without and with the false
  // matches, and with them vetoed from the start.
  double ate_without_m = NAN, ate_with_m = NAN, ate_oracle_m = NAN;
  int solves = 0;
  int reruns = 0;  // of the front end, by feedback
};

// One row per seed and policy, seed major; `on_row` as each is done.
// Throws std::invalid_argument for a dataset without ground truth, an
// unknown policy, or a plan that cannot be made (PlanFalseVisualMatches).
std::vector<HierarchyExperimentRow> RunHierarchyExperiment(
    const Dataset& d, const std::vector<Observation>& observations, const ObservationModel& model,
    const HierarchyExperimentOptions& options,
    const std::function<void(const HierarchyExperimentRow&)>& on_row = {});

}  // namespace catgraph

#endif  // CATGRAPH_EXPERIMENTS_HIERARCHY_EXPERIMENT_H_
