// What a constraint of the pose graph is and where it came from.
//
// Every relative-pose constraint carries a ClosureKind and its provenance: the
// ids of the closures it depends on. An odometry-inferred closure of
// CAT-Graph+ names the visual closure it hangs from and the one that validated
// it; when the back end switches a parent off, the hierarchy layer turns its
// children off too.
#ifndef CATGRAPH_BACKEND_GRAPH_CLOSURE_H_
#define CATGRAPH_BACKEND_GRAPH_CLOSURE_H_

#include <array>
#include <optional>
#include <string_view>
#include <vector>

#include "backend/graph/ids.h"

namespace catgraph {

enum class ClosureKind {
  kOdometry,          // consecutive poses, from wheel or visual odometry
  kVisual,            // appearance-based loop closure (CAT-Graph)
  kOdometryInferred,  // inferred from odometry where vision failed (CAT-Graph+)
  kInjected,          // a false closure added by an experiment
  kUnknown,           // a loop closure read from a file that does not say
};

inline constexpr std::array<ClosureKind, 5> kAllClosureKinds = {
    ClosureKind::kOdometry, ClosureKind::kVisual, ClosureKind::kOdometryInferred,
    ClosureKind::kInjected, ClosureKind::kUnknown};

// The stable spelling used in files and JSON ("inferred" is the key
// closures.json uses for odometry-inferred closures).
constexpr std::string_view ToString(ClosureKind kind) {
  switch (kind) {
    case ClosureKind::kOdometry: return "odometry";
    case ClosureKind::kVisual: return "visual";
    case ClosureKind::kOdometryInferred: return "inferred";
    case ClosureKind::kInjected: return "injected";
    case ClosureKind::kUnknown: return "unknown";
  }
  return "unknown";
}

inline std::optional<ClosureKind> ClosureKindFromString(std::string_view text) {
  for (ClosureKind kind : kAllClosureKinds) {
    if (ToString(kind) == text) return kind;
  }
  return std::nullopt;
}

// The provenance of a constraint: the closures it depends on. Empty for
// odometry, for visual closures and for anything read from a plain file.
struct Provenance {
  std::vector<ClosureId> parents;

  friend bool operator==(const Provenance&, const Provenance&) = default;
};

// The prior that pulls a switch towards its expected value gamma:
// residual sqrt(information) * (gamma - s).
struct SwitchPrior {
  double mean = 1.0;         // gamma; Vertigo and the SC papers use 1.
  double information = 1.0;  // 1 / sigma^2 of the prior (Xi^-1); > 0.

  friend bool operator==(const SwitchPrior&, const SwitchPrior&) = default;
};

// A switch variable s of a switchable constraint (Suenderhauf & Protzel 2012).
// s near 1 keeps the constraint, s near 0 switches it off; a closure counts as
// accepted when s > 0.5.
struct SwitchVariable {
  SwitchId id;
  double value = 1.0;  // initial (or solved) value
  std::optional<SwitchPrior> prior;

  friend bool operator==(const SwitchVariable&, const SwitchVariable&) = default;
};

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_GRAPH_CLOSURE_H_
