#include "frontend/observation_model.h"

#include <algorithm>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr NameTable<ObservationKind, 2> kObservationKindNames = {{
    {ObservationKind::kFabMap, "fabmap"},
    {ObservationKind::kHolistic, "holistic"},
}};

}  // namespace

std::vector<std::size_t> EvenlySpread(std::size_t count, int wanted) {
  std::vector<std::size_t> out;
  if (wanted <= 0) return out;
  const double stride = std::max(1.0, static_cast<double>(count) / wanted);
  for (double k = 0.0; k < static_cast<double>(count); k += stride) out.push_back(static_cast<std::size_t>(k));
  return out;
}

std::string_view ToString(ObservationKind kind) { return NameOf(kObservationKindNames, kind); }

std::optional<ObservationKind> ObservationKindFromString(std::string_view text) {
  return ValueOf(kObservationKindNames, text);
}

std::vector<std::string> ObservationKindNames() { return NamesOf(kObservationKindNames); }

}  // namespace catgraph
