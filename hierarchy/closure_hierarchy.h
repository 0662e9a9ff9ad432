// The closure hierarchy: which loop closures depend on which, and what that
// means for the back end's decisions.
//
// CAT-Graph+ infers loop closures from odometry between two visual closures:
// the one it hangs from and the one that validated it (both in the child's
// Provenance). If the robust back end switches a visual closure off, it was a
// false match, and so are the inferences that hang from it. The hierarchy
// turns those children off. Three policies:
//
//   cascade  solve; every child of a rejected (or turned-off) parent is
//            turned off and the graph re-solved without it, until no new
//            child is turned off. A decision, once made, stands.
//   coupled  one solve in which each child's residual is also scaled by the
//            switches of all its ancestors, so that switching a parent off
//            switches its children off in the same solve.
//   flat     plain switchable constraints; the children that survive their
//            rejected parents are reported, not turned off.
//
// The decisions are pure functions of the record and the back end's
// acceptances (PropagateRejections); OptimizeWithHierarchy runs the solves.
#ifndef CATGRAPH_HIERARCHY_CLOSURE_HIERARCHY_H_
#define CATGRAPH_HIERARCHY_CLOSURE_HIERARCHY_H_

#include <map>
#include <optional>
#include <set>
#include <string_view>
#include <vector>

#include "backend/graph/pose_graph.h"
#include "backend/pose_graph_optimizer.h"

namespace catgraph {

enum class HierarchyPolicy { kCascade, kCoupled, kFlat };

std::string_view ToString(HierarchyPolicy policy);
std::optional<HierarchyPolicy> HierarchyPolicyFromString(std::string_view text);

// The record of which closures depend on which: child -> parents.
class ClosureHierarchy {
 public:
  // The provenance of every constraint of `graph`. Throws std::invalid_argument
  // when a provenance names a closure that is not in the graph, or the
  // parents form a cycle.
  template <typename PoseT>
  static ClosureHierarchy FromGraph(const PoseGraph<PoseT>& graph);
  static ClosureHierarchy FromGraph(const AnyPoseGraph& graph);

  // Records that `child` depends on `parents` (appended to any it already
  // has). Throws std::invalid_argument if that closes a cycle.
  void Add(ClosureId child, const std::vector<ClosureId>& parents);

  // Parents of `child`, in the order they were recorded; empty if none.
  const std::vector<ClosureId>& ParentsOf(ClosureId child) const;
  // Every closure `child` depends on, directly or through other closures;
  // nearest first, each once.
  std::vector<ClosureId> AncestorsOf(ClosureId child) const;
  // The closures that name `parent` among their parents, in id order.
  std::vector<ClosureId> ChildrenOf(ClosureId parent) const;

  // child -> parents, every child with at least one parent.
  const std::map<ClosureId, std::vector<ClosureId>>& parents() const { return parents_; }
  std::size_t NumChildren() const { return parents_.size(); }
  bool empty() const { return parents_.empty(); }

 private:
  std::map<ClosureId, std::vector<ClosureId>> parents_;
  std::map<ClosureId, std::set<ClosureId>> children_;
};

// One decision of the hierarchy: `child` is off because `parent` is off.
struct HierarchyDecision {
  ClosureId child;
  ClosureId parent;
  int round = 1;  // the solve after which it was made (cascade), from 1
  friend bool operator==(const HierarchyDecision&, const HierarchyDecision&) = default;
};

// The children that rejected parents turn off. `accepted` holds the back
// end's acceptance of each closure on its own (closures not in it count as
// accepted); a closure is off when it is not accepted or is in `already_off`.
// Every child that is accepted and not already off, one of whose parents is
// off, gets one decision naming its first such parent; turning a child off
// turns its own children off in the same call. Decisions come in id order
// of the children, grouped by depth.
std::vector<HierarchyDecision> PropagateRejections(const ClosureHierarchy& hierarchy,
                                                   const std::map<ClosureId, bool>& accepted,
                                                   const std::set<ClosureId>& already_off = {});

struct HierarchyOptions {
  HierarchyPolicy policy = HierarchyPolicy::kCascade;
  int max_rounds = 50;  // cascade: solves at most; >= 1
};
// Throws std::invalid_argument for a field out of range.
void Validate(const HierarchyOptions& options);

struct HierarchicalOptimization {
  // The last solve: every closure of the input with its final decision
  // (children the hierarchy turned off are rejected, with weight 0 under
  // cascade and their coupled weight under coupled). In `graph`, the switch
  // of every child turned off is 0, so a reader of the written file sees it
  // off.
  PoseGraphOptimization optimization;
  // cascade and coupled: the children turned off, and by which parent.
  std::vector<HierarchyDecision> turned_off;
  // flat: the accepted children of rejected parents, which the other
  // policies would have turned off.
  std::vector<HierarchyDecision> surviving_children;
  int solves = 0;
  double time_s = 0.0;  // every solve, refinements included
};

// Solves `graph` with `options` under the hierarchy's policy. coupled needs
// switches (method switchable); throws std::invalid_argument otherwise, and
// for bad options.
HierarchicalOptimization OptimizeWithHierarchy(const AnyPoseGraph& graph, const ClosureHierarchy& hierarchy,
                                               const PoseGraphOptimizerOptions& options,
                                               const HierarchyOptions& hierarchy_options = {});

}  // namespace catgraph

#endif  // CATGRAPH_HIERARCHY_CLOSURE_HIERARCHY_H_
