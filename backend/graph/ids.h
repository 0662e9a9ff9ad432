// Strong integer ids for the things a pose graph talks about.
//
// A PoseId, a SwitchId and a ClosureId are all integers in the files, but they
// are never interchangeable in code: mixing them up is a compile error. Ids are
// cheap value types, ordered and hashable, so they key std::map and
// std::unordered_map directly.
#ifndef CATGRAPH_BACKEND_GRAPH_IDS_H_
#define CATGRAPH_BACKEND_GRAPH_IDS_H_

#include <cstddef>
#include <cstdint>
#include <functional>
#include <ostream>

namespace catgraph {

template <typename Tag>
class StrongId {
 public:
  using ValueType = std::int64_t;

  constexpr StrongId() = default;
  constexpr explicit StrongId(ValueType value) : value_(value) {}

  constexpr ValueType value() const { return value_; }

  friend constexpr auto operator<=>(const StrongId&, const StrongId&) = default;
  friend std::ostream& operator<<(std::ostream& os, const StrongId& id) {
    return os << id.value_;
  }

 private:
  ValueType value_ = 0;
};

struct PoseIdTag {};
struct SwitchIdTag {};
struct ClosureIdTag {};

// A vertex of the pose graph: one robot pose.
using PoseId = StrongId<PoseIdTag>;
// A switch variable of a switchable constraint (Suenderhauf & Protzel 2012).
using SwitchId = StrongId<SwitchIdTag>;
// A relative-pose constraint (odometry or loop closure) of the graph.
using ClosureId = StrongId<ClosureIdTag>;

}  // namespace catgraph

template <typename Tag>
struct std::hash<catgraph::StrongId<Tag>> {
  std::size_t operator()(const catgraph::StrongId<Tag>& id) const noexcept {
    return std::hash<std::int64_t>{}(id.value());
  }
};

#endif  // CATGRAPH_BACKEND_GRAPH_IDS_H_
