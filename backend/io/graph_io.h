// Reading and writing pose-graph files.
//
// Readers: g2o 2D and 3D (VERTEX_SE2, EDGE_SE2, VERTEX_SE3:QUAT,
// EDGE_SE3:QUAT, FIX) with the robust tags of the Vertigo library
// (VERTEX_SWITCH, EDGE_SWITCH_PRIOR, EDGE_SE2_SWITCHABLE,
// EDGE_SE3_SWITCHABLE, EDGE_SE2_MAXMIX); TORO 2D (VERTEX2, EDGE2 with TORO's
// information order); and iSAM's EDGE2 / EDGE3 lines, whose matrices are
// square-root information. docs/file-formats.md gives every line layout.
//
// Every problem in a file is a FileError naming the file, the line and what
// was expected; the readers never crash on bad input and never return a
// partly read graph.
//
// Writer: g2o, including switches, fixed vertices and catgraph's closure
// metadata comments (kind and provenance), so write -> read returns the same
// graph. Output is written atomically.
#ifndef CATGRAPH_BACKEND_IO_GRAPH_IO_H_
#define CATGRAPH_BACKEND_IO_GRAPH_IO_H_

#include <cstddef>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "backend/graph/pose_graph.h"

namespace catgraph {

enum class GraphFormat {
  kAuto,  // decide from the content (and the .graph extension for TORO)
  kG2o,
  kToro,
  kIsam,
};

std::string_view ToString(GraphFormat format);
std::optional<GraphFormat> GraphFormatFromString(std::string_view text);

struct ReadGraphOptions {
  GraphFormat format = GraphFormat::kAuto;
  // Lines longer than this are rejected; no valid graph line comes close.
  std::size_t max_line_bytes = 64 * 1024;
  // Ids beyond this are rejected so a hostile file cannot declare a graph
  // that would exhaust memory when the back end allocates per pose id.
  std::int64_t max_id = std::int64_t{1} << 40;
};

struct GraphFile {
  AnyPoseGraph graph;
  GraphFormat format = GraphFormat::kG2o;  // the format it was read as
  // The lines of edges from a vertex to itself, which constrain nothing and
  // are left out of `graph`, as g2o leaves them out (published files have
  // them). The ids of the other edges do not change.
  std::vector<int> self_edge_lines;
};

// Throws FileError.
GraphFile ReadGraphFile(const std::filesystem::path& path, const ReadGraphOptions& options = {});
// `name` is used in error messages and, through its extension (".graph" means
// TORO), in auto-detection.
GraphFile ReadGraph(std::istream& in, const std::string& name,
                    const ReadGraphOptions& options = {});

// g2o text. Vertices are written only when every vertex has an initial pose,
// so an edges-only graph stays edges-only.
void WriteG2o(const AnyPoseGraph& graph, std::ostream& out);
// Atomic (temporary file + rename); throws FileError.
void WriteG2oFile(const AnyPoseGraph& graph, const std::filesystem::path& path);

}  // namespace catgraph

#endif  // CATGRAPH_BACKEND_IO_GRAPH_IO_H_
