#include "hierarchy/closure_hierarchy.h"

#include <algorithm>
#include <stdexcept>
#include <string>
#include <variant>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr NameTable<HierarchyPolicy, 3> kPolicyNames = {{
    {HierarchyPolicy::kCascade, "cascade"},
    {HierarchyPolicy::kCoupled, "coupled"},
    {HierarchyPolicy::kFlat, "flat"},
}};

std::map<ClosureId, bool> OwnAcceptance(const std::vector<ClosureDecision>& decisions) {
  std::map<ClosureId, bool> accepted;
  for (const ClosureDecision& d : decisions) accepted[d.id] = d.own_weight > 0.5;
  return accepted;
}

// Applies the hierarchy's decisions to the last solve's result: each child
// turned off gets switch 0 in the graph (if it has a switch) and is rejected
// in the decisions.
void MarkTurnedOff(PoseGraphOptimization& r, const std::vector<HierarchyDecision>& turned_off) {
  std::set<ClosureId> off;
  for (const HierarchyDecision& d : turned_off) off.insert(d.child);
  std::visit(
      [&off](auto& graph) {
        for (const auto& c : graph.constraints) {
          if (c.switch_id && off.contains(c.id)) graph.switches.at(*c.switch_id).value = 0.0;
        }
      },
      r.graph);
  for (ClosureDecision& d : r.closures) {
    if (!off.contains(d.id) || !d.accepted) continue;
    d.accepted = false;
    ++r.rejected;
    --r.accepted;
  }
}

}  // namespace

std::string_view ToString(HierarchyPolicy policy) { return NameOf(kPolicyNames, policy); }

std::optional<HierarchyPolicy> HierarchyPolicyFromString(std::string_view text) {
  return ValueOf(kPolicyNames, text);
}

template <typename PoseT>
ClosureHierarchy ClosureHierarchy::FromGraph(const PoseGraph<PoseT>& graph) {
  std::set<ClosureId> ids;
  for (const auto& c : graph.constraints) ids.insert(c.id);
  ClosureHierarchy hierarchy;
  for (const auto& c : graph.constraints) {
    if (c.provenance.parents.empty()) continue;
    for (const ClosureId parent : c.provenance.parents) {
      if (!ids.contains(parent)) {
        throw std::invalid_argument("closure " + std::to_string(c.id.value()) + " names parent " +
                                    std::to_string(parent.value()) + ", which is not in the graph");
      }
    }
    hierarchy.Add(c.id, c.provenance.parents);
  }
  return hierarchy;
}
template ClosureHierarchy ClosureHierarchy::FromGraph(const PoseGraph2&);
template ClosureHierarchy ClosureHierarchy::FromGraph(const PoseGraph3&);

ClosureHierarchy ClosureHierarchy::FromGraph(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return FromGraph(g); }, graph);
}

void ClosureHierarchy::Add(ClosureId child, const std::vector<ClosureId>& parents) {
  for (const ClosureId parent : parents) {
    if (parent == child) {
      throw std::invalid_argument("closure " + std::to_string(child.value()) + " cannot be its own parent");
    }
    const std::vector<ClosureId> above = AncestorsOf(parent);
    if (std::find(above.begin(), above.end(), child) != above.end()) {
      throw std::invalid_argument("closure " + std::to_string(child.value()) + " cannot depend on closure " +
                                  std::to_string(parent.value()) + ", which depends on it (a cycle)");
    }
    std::vector<ClosureId>& recorded = parents_[child];
    if (std::find(recorded.begin(), recorded.end(), parent) != recorded.end()) continue;
    recorded.push_back(parent);
    children_[parent].insert(child);
  }
}

const std::vector<ClosureId>& ClosureHierarchy::ParentsOf(ClosureId child) const {
  static const std::vector<ClosureId> kNone;
  const auto found = parents_.find(child);
  return found == parents_.end() ? kNone : found->second;
}

std::vector<ClosureId> ClosureHierarchy::AncestorsOf(ClosureId child) const {
  // Breadth first, the list its own queue: nearest first.
  std::vector<ClosureId> ancestors;
  std::set<ClosureId> seen;
  auto visit = [&](ClosureId c) {
    for (const ClosureId parent : ParentsOf(c)) {
      if (seen.insert(parent).second) ancestors.push_back(parent);
    }
  };
  visit(child);
  for (std::size_t i = 0; i < ancestors.size(); ++i) visit(ancestors[i]);
  return ancestors;
}

std::vector<ClosureId> ClosureHierarchy::ChildrenOf(ClosureId parent) const {
  const auto found = children_.find(parent);
  if (found == children_.end()) return {};
  return {found->second.begin(), found->second.end()};
}

std::vector<HierarchyDecision> PropagateRejections(const ClosureHierarchy& hierarchy,
                                                   const std::map<ClosureId, bool>& accepted,
                                                   const std::set<ClosureId>& already_off) {
  std::set<ClosureId> off = already_off;
  for (const auto& [id, is_accepted] : accepted) {
    if (!is_accepted) off.insert(id);
  }
  std::vector<HierarchyDecision> decisions;
  for (;;) {
    std::vector<HierarchyDecision> depth;  // decided on this pass
    for (const auto& [child, parents] : hierarchy.parents()) {
      if (off.contains(child)) continue;
      const auto parent = std::find_if(parents.begin(), parents.end(),
                                       [&off](ClosureId p) { return off.contains(p); });
      if (parent != parents.end()) depth.push_back({child, *parent});
    }
    if (depth.empty()) return decisions;
    for (const HierarchyDecision& d : depth) off.insert(d.child);
    decisions.insert(decisions.end(), depth.begin(), depth.end());
  }
}

void Validate(const HierarchyOptions& options) {
  if (options.max_rounds < 1) {
    throw std::invalid_argument("HierarchyOptions: max_rounds must be >= 1, got " + std::to_string(options.max_rounds));
  }
}

HierarchicalOptimization OptimizeWithHierarchy(const AnyPoseGraph& graph, const ClosureHierarchy& hierarchy,
                                               const PoseGraphOptimizerOptions& options,
                                               const HierarchyOptions& hierarchy_options) {
  Validate(hierarchy_options);
  HierarchicalOptimization out;
  PoseGraphOptimizerOptions o = options;
  auto solve = [&] {
    PoseGraphOptimization r = OptimizePoseGraph(graph, o);
    ++out.solves;
    out.time_s += r.TotalTimeS();
    return r;
  };
  switch (hierarchy_options.policy) {
    case HierarchyPolicy::kFlat: {
      out.optimization = solve();
      out.surviving_children = PropagateRejections(hierarchy, OwnAcceptance(out.optimization.closures));
      break;
    }
    case HierarchyPolicy::kCoupled: {
      for (const auto& [child, parents] : hierarchy.parents()) o.coupled_closures[child] = hierarchy.AncestorsOf(child);
      out.optimization = solve();
      out.turned_off = PropagateRejections(hierarchy, OwnAcceptance(out.optimization.closures));
      break;
    }
    case HierarchyPolicy::kCascade: {
      for (int round = 1;; ++round) {
        out.optimization = solve();
        std::vector<HierarchyDecision> decided =
            PropagateRejections(hierarchy, OwnAcceptance(out.optimization.closures), o.disabled_closures);
        for (HierarchyDecision& d : decided) d.round = round;
        out.turned_off.insert(out.turned_off.end(), decided.begin(), decided.end());
        // At the round limit the last decisions stand without a re-solve
        // (MarkTurnedOff below applies them to the result).
        if (decided.empty() || round == hierarchy_options.max_rounds) break;
        for (const HierarchyDecision& d : decided) o.disabled_closures.insert(d.child);
      }
      break;
    }
  }
  MarkTurnedOff(out.optimization, out.turned_off);
  return out;
}

}  // namespace catgraph
