#include "backend/io/internal/closure_metadata.h"

#include <charconv>
#include <cstdio>
#include <sstream>
#include <vector>

namespace catgraph {
namespace {

std::optional<std::int64_t> ParseId(const std::string& token) {
  std::int64_t value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec != std::errc() || end != token.data() + token.size() || value < 0) return std::nullopt;
  return value;
}

}  // namespace

std::optional<ClosureMetadata> ParseClosureMetadata(std::string_view line, std::string* error) {
  std::istringstream in{std::string(line)};
  std::string tag, id_text, kind_text;
  in >> tag >> id_text >> kind_text;
  const std::string usage = std::string(kClosureMetadataTag) +
                            ": expected '<closure-id> <kind> [<parent-id> ...]' with kind one of "
                            "odometry, visual, inferred, injected, unknown";
  const auto id = ParseId(id_text);
  const auto kind = ClosureKindFromString(kind_text);
  if (tag != kClosureMetadataTag || !id || !kind) {
    *error = usage;
    return std::nullopt;
  }
  ClosureMetadata metadata{ClosureId(*id), *kind, {}};
  std::string parent_text;
  while (in >> parent_text) {
    const auto parent = ParseId(parent_text);
    if (!parent) {
      *error = usage + "; found parent '" + parent_text + "'";
      return std::nullopt;
    }
    metadata.provenance.parents.emplace_back(*parent);
  }
  return metadata;
}

std::optional<RobustDecision> ParseDecision(std::string_view line, std::string* error) {
  std::istringstream in{std::string(line)};
  std::string tag, verdict, weight_text, extra;
  in >> tag >> verdict >> weight_text;
  double weight = 0.0;
  const auto [end, ec] = std::from_chars(weight_text.data(), weight_text.data() + weight_text.size(), weight);
  if (tag != kDecisionTag || (verdict != "accepted" && verdict != "rejected") || weight_text.empty() ||
      ec != std::errc() || end != weight_text.data() + weight_text.size() || !(weight >= 0.0 && weight <= 1.0) ||
      (in >> extra)) {
    *error = std::string(kDecisionTag) + ": expected 'accepted|rejected <weight in [0, 1]>'";
    return std::nullopt;
  }
  return RobustDecision{verdict == "accepted", weight};
}

std::string FormatDecision(const RobustDecision& decision) {
  char weight[32];
  std::snprintf(weight, sizeof weight, "%.17g", decision.weight);
  return std::string(kDecisionTag) + (decision.accepted ? " accepted " : " rejected ") + weight;
}

std::string FormatClosureMetadata(const ClosureMetadata& metadata) {
  std::ostringstream line;
  line << kClosureMetadataTag << ' ' << metadata.id << ' ' << ToString(metadata.kind);
  for (const ClosureId parent : metadata.provenance.parents) line << ' ' << parent;
  return line.str();
}

}  // namespace catgraph
