// catgraph info FILE [--format F] [--json]
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "backend/graph_summary.h"
#include "backend/io/graph_io.h"

namespace catgraph {
namespace {

struct InfoOptions {
  std::string file;
  std::string format = "auto";
  bool json = false;
};

std::string FormatKindCounts(const GraphSummary& s) {
  std::string text;
  for (const auto& [kind, count] : s.edges_by_kind) {
    if (!text.empty()) text += ", ";
    text += std::string(ToString(kind)) + " " + std::to_string(count);
  }
  return text.empty() ? "none" : text;
}

void RunInfo(const InfoOptions& options, std::ostream& out) {
  const GraphFile file = ReadCommandGraph(options.file, options.format);
  const GraphSummary s = Summarize(file.graph);
  const std::string sqrt_warning =
      "the information matrices look like square-root information (" +
      s.square_root_information_example +
      "); g2o expects information. Published robust-back-end numbers use such files as "
      "they are; state it whenever you rescale them.";
  if (options.json) {
    nlohmann::json j;
    j["file"] = options.file;
    j["format"] = ToString(file.format);
    j["dimension"] = s.dimension;
    j["vertices"] = s.vertices;
    j["vertices_without_pose"] = s.vertices_without_pose;
    j["fixed_vertices"] = s.fixed_vertices;
    j["edges"] = s.edges;
    j["odometry_edges"] = s.odometry_edges;
    j["loop_closures"] = s.loop_closures;
    j["switchable_edges"] = s.switchable_edges;
    j["maxmix_edges"] = s.maxmix_edges;
    j["switches"] = s.switches;
    j["edges_by_kind"] = nlohmann::json::object();
    for (const auto& [kind, count] : s.edges_by_kind) j["edges_by_kind"][ToString(kind)] = count;
    j["indefinite_information_edges"] = s.indefinite_information_edges;
    j["connected"] = s.connected;
    j["connected_components"] = s.connected_components;
    j["square_root_information_suspected"] = s.looks_like_square_root_information;
    j["self_edges_skipped"] = file.self_edge_lines.size();
    j["warnings"] = nlohmann::json::array();
    if (s.looks_like_square_root_information) j["warnings"].push_back(sqrt_warning);
    out << j.dump(2) << '\n';
    return;
  }
  out << "file:          " << options.file << " (" << ToString(file.format) << ", "
      << s.dimension << "D)\n"
      << "vertices:      " << s.vertices << " (" << s.vertices_without_pose
      << " without initial pose, " << s.fixed_vertices << " fixed)\n"
      << "edges:         " << s.edges << " (" << s.odometry_edges << " odometry, "
      << s.loop_closures << " loop closures; " << s.switchable_edges << " switchable, "
      << s.maxmix_edges << " max-mixture)\n"
      << "switches:      " << s.switches << '\n'
      << "closure kinds: " << FormatKindCounts(s) << '\n'
      << "connected:     " << (s.connected ? "yes" : "no") << " (" << s.connected_components
      << (s.connected_components == 1 ? " component)\n" : " components)\n");
  WriteSelfEdgeNote(out, options.file, file);
  if (s.vertices_without_pose > 0) {
    out << "note: " << s.vertices_without_pose
        << " vertices have no initial pose; the optimiser initialises them\n";
  }
  if (s.indefinite_information_edges > 0) {
    out << "warning: " << s.indefinite_information_edges
        << " edges have an indefinite information matrix (positive-definite translation and "
           "rotation blocks, indefinite coupling)\n";
  }
  if (s.looks_like_square_root_information) out << "warning: " << sqrt_warning << '\n';
}

}  // namespace

void AddInfoCommand(CLI::App& app, std::ostream& out) {
  auto options = std::make_shared<InfoOptions>();
  CLI::App* cmd = app.add_subcommand(
      "info", "Summarise a pose-graph file: dimension, vertex and edge counts by kind, "
              "odometry vs loop closures, switches, connectivity, information-matrix warnings.");
  cmd->add_option("file", options->file, "Pose-graph file (g2o 2D/3D, TORO .graph, iSAM)")
      ->required();
  AddGraphFormatOption(*cmd, options->format);
  cmd->add_flag("--json", options->json,
                "Print one JSON object (keys: dimension, vertices, edges, odometry_edges, "
                "loop_closures, switches, connected, ...)");
  cmd->callback([options, &out] { RunInfo(*options, out); });
}

}  // namespace catgraph
