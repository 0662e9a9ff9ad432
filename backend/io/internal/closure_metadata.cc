#include "backend/io/internal/closure_metadata.h"

#include <charconv>
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

std::string FormatClosureMetadata(const ClosureMetadata& metadata) {
  std::ostringstream line;
  line << kClosureMetadataTag << ' ' << metadata.id << ' ' << ToString(metadata.kind);
  for (const ClosureId parent : metadata.provenance.parents) line << ' ' << parent;
  return line.str();
}

}  // namespace catgraph
