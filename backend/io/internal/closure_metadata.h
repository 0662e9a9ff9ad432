// catgraph's closure metadata in g2o files.
//
// g2o has no place for a closure's kind or provenance, so catgraph writes them
// in a comment line directly before the edge line they describe:
//
//   #CATGRAPH_CLOSURE <closure-id> <kind> [<parent-closure-id> ...]
//
// and a robust solve's decision about it, also directly before its edge:
//
//   #CATGRAPH_DECISION accepted|rejected <weight>
//
// Other g2o readers skip comment lines and load the graph unchanged.
#ifndef CATGRAPH_BACKEND_IO_INTERNAL_CLOSURE_METADATA_H_
#define CATGRAPH_BACKEND_IO_INTERNAL_CLOSURE_METADATA_H_

#include <optional>
#include <string>
#include <string_view>

#include "backend/graph/closure.h"
#include "backend/graph/ids.h"
#include "backend/graph/pose_graph.h"

namespace catgraph {

inline constexpr std::string_view kClosureMetadataTag = "#CATGRAPH_CLOSURE";

struct ClosureMetadata {
  ClosureId id;
  ClosureKind kind = ClosureKind::kUnknown;
  Provenance provenance;
};

// nullopt with *error set when the line is malformed.
std::optional<ClosureMetadata> ParseClosureMetadata(std::string_view line, std::string* error);
std::string FormatClosureMetadata(const ClosureMetadata& metadata);

inline constexpr std::string_view kDecisionTag = "#CATGRAPH_DECISION";

// nullopt with *error set when the line is malformed.
std::optional<RobustDecision> ParseDecision(std::string_view line, std::string* error);
std::string FormatDecision(const RobustDecision& decision);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_INTERNAL_CLOSURE_METADATA_H_
