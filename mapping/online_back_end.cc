#include "mapping/online_back_end.h"

#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "backend/factors.h"

namespace catgraph::mapping {
namespace {

SwitchId SwitchOf(ClosureId id) { return SwitchId(id.value()); }

std::string Named(const Constraint<Pose2>& c) { return "constraint " + std::to_string(c.id.value()); }

}  // namespace

bool OnlineBackEnd::Supports(const PoseGraphOptimizerOptions& o, const HierarchyOptions& hierarchy) {
  const bool from_scratch_stages = o.gate.estimate_noise_scale || o.gate.narrow || o.refinement.enabled ||
                                   o.readmission.enabled || o.initial_guess != InitialGuess::kFile;
  return o.method == RobustMethod::kSwitchable && !o.robust_odometry && o.disabled_closures.empty() &&
         o.coupled_closures.empty() && hierarchy.policy != HierarchyPolicy::kCoupled && !from_scratch_stages;
}

OnlineBackEnd::OnlineBackEnd(const PoseGraphOptimizerOptions& options, const HierarchyOptions& hierarchy)
    : options_(options), hierarchy_options_(hierarchy), optimizer_(options.solver) {
  Validate(options_);
  Validate(hierarchy_options_);
  if (!Supports(options_, hierarchy_options_)) {
    throw std::invalid_argument(
        "OnlineBackEnd: solves switchable constraints on loop closures only, from the last solution "
        "(OnlineSolveOptions), without disabled or coupled closures or the coupled hierarchy");
  }
  prior_ = {1.0, options_.switch_prior_information > 0.0 ? options_.switch_prior_information
                                                         : Gate<Pose2>(options_.cost, options_.gate.probability)};
}

void OnlineBackEnd::Add(const Constraint<Pose2>& c) {
  if (c.kind == ClosureKind::kOdometry) {
    optimizer_.Add(std::make_unique<BetweenFactor<Pose2>>(c.from, c.to, c.measurement, RobustLoss{}, options_.cost));
    return;
  }
  if (!c.provenance.parents.empty()) hierarchy_.Add(c.id, c.provenance.parents);
  Closure& closure = closures_[c.id];
  closure.constraint = c;
  closure.on = false;
  optimizer_.Insert(SwitchOf(c.id), prior_.mean);
  TurnOn(closure, true);
}

void OnlineBackEnd::TurnOn(Closure& closure, bool on) {
  if (closure.on == on) return;
  closure.on = on;
  const Constraint<Pose2>& c = closure.constraint;
  const SwitchId s = SwitchOf(c.id);
  if (!on) {
    optimizer_.Remove(closure.factor);
    optimizer_.Remove(closure.prior);
    optimizer_.Set(s, 0.0);
    optimizer_.SetConstant(SwitchKey(s));
    return;
  }
  optimizer_.Set(s, prior_.mean);
  optimizer_.SetConstant(SwitchKey(s), false);
  closure.factor = optimizer_.Add(std::make_unique<SwitchableBetweenFactor<Pose2>>(
      c.from, c.to, s, c.measurement, options_.switch_function, std::vector<SwitchId>{}, options_.cost));
  closure.prior = optimizer_.Add(std::make_unique<SwitchPriorFactor>(s, prior_));
}

void OnlineBackEnd::Decide() {
  for (const auto& [id, closure] : closures_) {
    const Constraint<Pose2>& c = closure.constraint;
    const double own = closure.on ? Psi(optimizer_.values().AtSwitch(SwitchOf(id)), options_.switch_function) : 0.0;
    decisions_.insert_or_assign(id, ClosureDecision{id, c.from, c.to, c.kind, own, own, own > 0.5});
  }
}

OnlineBackEnd::Solve OnlineBackEnd::Update(const PoseGraph2& graph) {
  // What is new, checked before any of it is taken.
  const auto first_new =
      odometry_.empty() ? graph.vertices.begin() : graph.vertices.upper_bound(odometry_.rbegin()->first);
  if (static_cast<std::size_t>(std::distance(graph.vertices.begin(), first_new)) != odometry_.size() ||
      graph.constraints.size() < constraints_) {
    throw std::invalid_argument("OnlineBackEnd: the graph does not extend the one taken before");
  }
  for (auto v = first_new; v != graph.vertices.end(); ++v) {
    if (!v->second.pose) {
      throw std::invalid_argument("OnlineBackEnd: vertex " + std::to_string(v->first.value()) + " has no pose");
    }
  }
  std::set<ClosureId> new_closures;
  for (std::size_t i = constraints_; i < graph.constraints.size(); ++i) {
    const Constraint<Pose2>& c = graph.constraints[i];
    if (c.switch_id || c.maxmix_weight) {
      throw std::invalid_argument("OnlineBackEnd: " + Named(c) + " has a switch or a mixture of its own");
    }
    if (!graph.vertices.contains(c.from) || !graph.vertices.contains(c.to)) {
      throw std::invalid_argument("OnlineBackEnd: " + Named(c) + " joins a pose the graph does not have");
    }
    if (c.kind == ClosureKind::kOdometry) continue;
    for (const ClosureId parent : c.provenance.parents) {
      if (!closures_.contains(parent) && !new_closures.contains(parent)) {
        throw std::invalid_argument("OnlineBackEnd: " + Named(c) + " names parent " + std::to_string(parent.value()) +
                                    ", which is not a closure before it");
      }
    }
    new_closures.insert(c.id);
  }

  // The new vertices, each placed by odometry from the one before it as the
  // last solve left it; the new constraints.
  for (auto next = first_new; next != graph.vertices.end(); ++next) {
    const auto& [id, vertex] = *next;
    if (odometry_.empty()) {
      optimizer_.Insert(id, *vertex.pose);
      optimizer_.SetConstant(PoseKey(id));  // the gauge
    } else {
      const auto& [last, last_odometry] = *odometry_.rbegin();
      optimizer_.Insert(id, optimizer_.values().AtPose2(last) * last_odometry.Between(*vertex.pose));
      if (vertex.fixed) optimizer_.SetConstant(PoseKey(id));
    }
    odometry_.emplace_hint(odometry_.end(), id, *vertex.pose);
  }
  for (; constraints_ < graph.constraints.size(); ++constraints_) Add(graph.constraints[constraints_]);

  // Under cascade, a child the hierarchy turned off comes back on (from its
  // prior) once the last solve accepted all its parents; then solve, turn
  // off the children of closures off or rejected, and solve again while
  // that turns any off. A decision made within a call stands for the call.
  const bool cascade = hierarchy_options_.policy == HierarchyPolicy::kCascade && !hierarchy_.empty();
  if (cascade) {
    for (auto& [id, closure] : closures_) {
      if (closure.on) continue;
      bool parents_accepted = true;
      for (const ClosureId parent : hierarchy_.ParentsOf(id)) {
        const auto d = decisions_.find(parent);
        parents_accepted = parents_accepted && d != decisions_.end() && d->second.accepted;
      }
      if (parents_accepted) TurnOn(closure, true);
    }
  }
  Solve out;
  for (int round = 1;; ++round) {
    out.summary = optimizer_.Solve();
    ++out.solves;
    Decide();
    if (!cascade || round == hierarchy_options_.max_rounds) break;
    std::map<ClosureId, bool> accepted;
    std::set<ClosureId> off;
    for (const auto& [id, closure] : closures_) {
      if (closure.on) {
        accepted.emplace_hint(accepted.end(), id, decisions_.at(id).accepted);
      } else {
        off.insert(off.end(), id);
      }
    }
    const std::vector<HierarchyDecision> turned_off = PropagateRejections(hierarchy_, accepted, off);
    if (turned_off.empty()) break;
    for (const HierarchyDecision& d : turned_off) TurnOn(closures_.at(d.child), false);
  }
  for (const auto& [id, d] : decisions_) ++(d.accepted ? out.accepted : out.rejected);
  return out;
}

Trajectory2 OnlineBackEnd::Poses() const {
  Trajectory2 poses;
  for (const auto& [id, odometry] : odometry_) poses.emplace_hint(poses.end(), id, optimizer_.values().AtPose2(id));
  return poses;
}

}  // namespace catgraph::mapping
