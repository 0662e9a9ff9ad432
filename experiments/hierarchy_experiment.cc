#include "experiments/hierarchy_experiment.h"

#include <stdexcept>

#include "hierarchy/closure_hierarchy.h"

namespace catgraph {
namespace {

double AteOf(const mapping::MapOutcome& m) { return m.ate_corrected ? m.ate_corrected->ate_m.rmse : NAN; }

}  // namespace

std::vector<HierarchyExperimentRow> RunHierarchyExperiment(
    const Dataset& d, const std::vector<Observation>& observations, const ObservationModel& model,
    const HierarchyExperimentOptions& o, const std::function<void(const HierarchyExperimentRow&)>& on_row) {
  std::vector<HierarchyOptions> policies;
  for (const std::string& h : o.hierarchies) policies.push_back(mapping::HierarchyOptionsFor(h, o.back_end));
  const Trajectory2 truth = mapping::TruthAtFrames(d);
  if (truth.empty()) throw std::invalid_argument("the hierarchy experiment needs ground truth");
  LocalizationOptions localization = o.front_end;
  FalseMatchOptions injection = o.injection;
  std::vector<HierarchyExperimentRow> rows;
  auto solve = [&](const LocalizationResult& front, const HierarchyOptions& policy) {
    return mapping::SolveWithFeedback(d, observations, model, front, o.back_end, policy, truth, o.feedback_reruns);
  };
  for (const std::uint64_t seed : o.seeds) {
    localization.filter.seed = injection.seed = seed;
    localization.imposed.clear();
    const LocalizationResult without = Localize(d, observations, model, localization);
    localization.imposed = ImposedDecisions(PlanFalseVisualMatches(d, localization.filter, injection));
    const LocalizationResult with = Localize(d, observations, model, localization);
    LocalizationOptions vetoed = localization;
    for (const LoopClosure& c : with.closures) {
      if (c.injected) vetoed.vetoed_frames.insert(c.frame);
    }
    const LocalizationResult oracle = Localize(d, observations, model, vetoed);
    for (std::size_t p = 0; p < policies.size(); ++p) {
      HierarchyExperimentRow row;
      row.seed = seed;
      row.hierarchy = o.hierarchies[p];
      row.ate_without_m = AteOf(solve(without, policies[p]).outcome);
      const mapping::MappingResult m = solve(with, policies[p]);
      row.ate_with_m = AteOf(m.outcome);
      row.injection = m.first.injection;
      row.solves = m.first.solved.solves;
      row.reruns = m.reruns;
      row.ate_oracle_m = AteOf(solve(oracle, policies[p]).outcome);
      rows.push_back(row);
      if (on_row) on_row(rows.back());
    }
  }
  return rows;
}

}  // namespace catgraph
