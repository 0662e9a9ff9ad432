// The g2o writer of graph_io.h. Numbers are written in the shortest form that
// reads back to the same double, so write -> read is exact.
#include <charconv>
#include <ostream>
#include <stdexcept>
#include <string>
#include <variant>

#include "backend/io/atomic_file.h"
#include "backend/io/graph_io.h"
#include "backend/io/internal/closure_metadata.h"
#include "backend/io/internal/text_line.h"

namespace catgraph {
namespace {



std::ostream& operator<<(std::ostream& out, const LineWriter& line) {
  return out << line.str() << '\n';
}

template <typename PoseT>
void WriteGraph(const PoseGraph<PoseT>& graph, std::ostream& out) {
  constexpr bool k2d = PoseGraph<PoseT>::kDimension == 2;
  if (graph.HasAllInitialPoses()) {
    for (const auto& [id, vertex] : graph.vertices) {
      out << (LineWriter(k2d ? "VERTEX_SE2" : "VERTEX_SE3:QUAT") << id << *vertex.pose);
    }
    for (const auto& [id, vertex] : graph.vertices) {
      if (vertex.fixed) out << (LineWriter("FIX") << id);
    }
  }
  for (const auto& [id, variable] : graph.switches) {
    out << (LineWriter("VERTEX_SWITCH") << id << variable.value);
    if (variable.prior) {
      out << (LineWriter("EDGE_SWITCH_PRIOR") << id << variable.prior->mean
                                           << variable.prior->information);
    }
  }
  std::int64_t index = 0;
  for (const Constraint<PoseT>& c : graph.constraints) {
    if (!k2d && c.maxmix_weight) {
      throw std::invalid_argument("WriteG2o: g2o has no 3D max-mixture edge (closure " +
                                  std::to_string(c.id.value()) + ")");
    }
    // Metadata only where the reader could not infer it from the line.
    const ClosureKind default_kind =
        c.IsBetweenConsecutivePoses() ? ClosureKind::kOdometry : ClosureKind::kUnknown;
    if (c.id.value() != index || c.kind != default_kind || !c.provenance.parents.empty()) {
      out << FormatClosureMetadata({c.id, c.kind, c.provenance}) << '\n';
    }
    if (c.decision) out << FormatDecision(*c.decision) << '\n';
    ++index;
    LineWriter line(c.switch_id        ? (k2d ? "EDGE_SE2_SWITCHABLE" : "EDGE_SE3_SWITCHABLE")
                 : c.maxmix_weight ? "EDGE_SE2_MAXMIX"
                                   : (k2d ? "EDGE_SE2" : "EDGE_SE3:QUAT"));
    line << c.from << c.to;
    if (c.switch_id) line << *c.switch_id;
    if (c.maxmix_weight) line << *c.maxmix_weight;
    line << c.measurement.mean << c.measurement.information;
    out << line;
  }
}

}  // namespace

void WriteG2o(const AnyPoseGraph& graph, std::ostream& out) {
  std::visit([&out](const auto& g) { WriteGraph(g, out); }, graph);
}

void WriteG2oFile(const AnyPoseGraph& graph, const std::filesystem::path& path) {
  WriteFileAtomically(path, [&graph](std::ostream& out) { WriteG2o(graph, out); });
}

}  // namespace catgraph
