// The ground-truth label of one loop closure: whether it is an outlier. An
// experiment that injects false closures knows them; evaluation scores the
// back end's decisions against them.
#ifndef CATGRAPH_BACKEND_GRAPH_CLOSURE_LABEL_H_
#define CATGRAPH_BACKEND_GRAPH_CLOSURE_LABEL_H_

#include <optional>

#include "backend/graph/closure.h"
#include "backend/graph/ids.h"

namespace catgraph {

struct ClosureLabel {
  ClosureId id;
  PoseId from, to;
  bool outlier = false;
  ClosureKind kind = ClosureKind::kUnknown;
  std::optional<int> group;         // injection group of an outlier
  std::optional<ClosureId> parent;  // a hierarchical child's false visual closure

  friend bool operator==(const ClosureLabel&, const ClosureLabel&) = default;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_CLOSURE_LABEL_H_
