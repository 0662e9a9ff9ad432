#include "mapping/map_dataset.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

namespace catgraph::mapping {

Trajectory2 TruthAtFrames(const Dataset& d) {
  Trajectory2 truth;
  PoseId::ValueType frame = 0;
  for (const Pose2& pose : PosesAtFrames(d, d.ground_truth)) truth.emplace_hint(truth.end(), PoseId(frame++), pose);
  return truth;
}

MapOutcome SolveMap(const LocalizationResult& r, const PoseGraphOptimizerOptions& optimizer,
                    const HierarchyOptions& hierarchy, const Trajectory2& truth) {
  MapOutcome m;
  const AnyPoseGraph front_graph(r.graph);
  PoseGraphOptimizerOptions held_off = optimizer;
  for (const LoopClosure& c : r.closures) {
    if (c.vetoed) held_off.disabled_closures.insert(ClosureId(c.id));
  }
  m.solved = OptimizeWithHierarchy(front_graph, ClosureHierarchy::FromGraph(front_graph), held_off, hierarchy);
  const PoseGraphOptimization& result = m.solved.optimization;
  if (!result.summary.IsUsable()) throw std::runtime_error("the solver failed: " + result.summary.message);
  for (const ClosureDecision& c : result.closures) m.decision_of.emplace(c.id, c);
  for (const HierarchyDecision& h : m.solved.turned_off) m.turned_off_by[h.child] = h.parent;
  std::set<int> injected;
  for (const LoopClosure& c : r.closures) {
    const ClosureDecision& decision = m.decision_of.at(ClosureId(c.id));
    KindCounts& k = m.by_kind[c.kind];
    ++k.count;
    k.accepted += decision.accepted ? 1 : 0;
    if (!std::isnan(c.error_m)) {
      k.errors.push_back(c.error_m);
      if (decision.accepted) k.accepted_errors.push_back(c.error_m);
    }
    InjectionOutcome& i = m.injection;
    if (c.injected) {
      injected.insert(c.id);
      ++i.parents;
      i.parents_rejected += decision.accepted ? 0 : 1;
    }
    // Children come after their parents.
    const auto false_parent = [&](int p) { return injected.count(p) > 0; };
    const auto rejected_false_parent = [&](int p) {
      return false_parent(p) && !m.decision_of.at(ClosureId(p)).accepted;
    };
    if (std::none_of(c.parents.begin(), c.parents.end(), false_parent)) continue;
    ++i.children;
    i.children_accepted += decision.accepted ? 1 : 0;
    if (decision.accepted && !std::isnan(c.error_m)) i.accepted_child_errors.push_back(c.error_m);
    if (std::any_of(c.parents.begin(), c.parents.end(), rejected_false_parent)) {
      ++i.children_of_rejected;
      i.children_of_rejected_accepted += decision.accepted ? 1 : 0;
      i.children_turned_off += static_cast<int>(m.turned_off_by.count(decision.id));
    }
  }
  for (const ClosureKind kind : {ClosureKind::kVisual, ClosureKind::kOdometryInferred}) m.by_kind[kind];
  for (auto& [kind, k] : m.by_kind) {
    k.all = StatisticsOf(k.errors);
    k.kept = StatisticsOf(k.accepted_errors);
  }
  if (!truth.empty()) {
    m.ate_odometry = EvaluateTrajectory(TrajectoryOf(r.graph), truth);
    m.ate_corrected = EvaluateTrajectory(TrajectoryOf(std::get<PoseGraph2>(result.graph)), truth);
  }
  return m;
}

MappingResult SolveWithFeedback(const Dataset& d, const std::vector<Observation>& observations,
                                const ObservationModel& model, LocalizationResult front,
                                const PoseGraphOptimizerOptions& optimizer, const HierarchyOptions& hierarchy,
                                const Trajectory2& truth, int max_reruns) {
  MappingResult out;
  LocalizationOptions localization = front.options;
  out.outcome = SolveMap(front, optimizer, hierarchy, truth);
  out.first = out.outcome;
  // Without CAT-Graph+ a veto changes nothing a re-run would compute.
  const bool feedback = hierarchy.policy != HierarchyPolicy::kFlat && localization.filter.inference.enabled;
  while (feedback && out.reruns < max_reruns) {
    bool vetoed_more = false;
    for (const LoopClosure& c : front.closures) {
      if (c.kind != ClosureKind::kVisual || out.outcome.decision_of.at(ClosureId(c.id)).accepted) continue;
      vetoed_more = localization.vetoed_frames.insert(c.frame).second || vetoed_more;
    }
    if (!vetoed_more) break;
    front = Localize(d, observations, model, localization);
    ++out.reruns;
    out.outcome = SolveMap(front, optimizer, hierarchy, truth);
  }
  out.front = std::move(front);
  return out;
}

MappingResult MapDataset(const Dataset& d, const std::vector<Observation>& observations,
                         const ObservationModel& model, const LocalizationOptions& front_end,
                         const PoseGraphOptimizerOptions& optimizer, const HierarchyOptions& hierarchy,
                         int max_reruns) {
  return SolveWithFeedback(d, observations, model, Localize(d, observations, model, front_end), optimizer, hierarchy,
                           TruthAtFrames(d), max_reruns);
}

void CheckHierarchyForFrontEnd(const HierarchyOptions& hierarchy, const PoseGraphOptimizerOptions& optimizer) {
  if (hierarchy.policy == HierarchyPolicy::kCoupled && optimizer.method != RobustMethod::kSwitchable) {
    throw std::invalid_argument("the coupled hierarchy needs the switchable method (it couples switches), not " +
                                std::string(ToString(optimizer.method)));
  }
}

HierarchyOptions HierarchyOptionsFor(const std::string& policy, const PoseGraphOptimizerOptions& optimizer) {
  HierarchyOptions h;
  const std::optional<HierarchyPolicy> parsed = HierarchyPolicyFromString(policy);
  if (!parsed) throw std::invalid_argument("unknown hierarchy policy '" + policy + "' (cascade, coupled or flat)");
  h.policy = *parsed;
  CheckHierarchyForFrontEnd(h, optimizer);
  return h;
}

}  // namespace catgraph::mapping
