// catgraph export GRAPH [--format tum|json|dot|svg|png|g2o] -o FILE
#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/plot/graph_figure.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_export.h"
#include "backend/io/graph_io.h"
#include "backend/io/output_directory.h"
#include "backend/io/trajectory_io.h"

namespace catgraph {
namespace {

struct ExportOptions {
  std::string input, output, format, title;
  std::string input_format = "auto";
};

void RunExport(const ExportOptions& o, std::ostream& out) {
  RefuseOutputClashes({o.output}, {o.input});
  std::string format = o.format;
  if (format.empty()) {
    format = plot::LowerCaseExtension(o.output);
    if (format != "tum" && format != "json" && format != "dot" && format != "svg" &&
        format != "png" && format != "g2o") {
      throw std::invalid_argument("cannot tell the export format from '" + o.output +
                                  "'; give --format tum|json|dot|svg|png|g2o");
    }
  }
  const GraphFile file = ReadCommandGraph(o.input, o.input_format);
  const AnyPoseGraph& graph = file.graph;
  try {
    if (format == "tum") WriteTumFile(TrajectoryOf(graph), o.output);
    if (format == "json") WriteGraphJsonFile(graph, o.output);
    if (format == "dot") WriteGraphDotFile(graph, o.output);
    if (format == "g2o") WriteG2oFile(graph, o.output);
    if (format == "svg" || format == "png") {
      if (plot::LowerCaseExtension(o.output) != format) {
        throw std::invalid_argument("--format " + format + " needs an output file ending in ." +
                                    format);
      }
      plot::SaveFigure(plot::GraphFigure(graph, o.title.empty() ? o.input : o.title), o.output);
    }
  } catch (const std::invalid_argument& e) {
    // A graph without poses: name the file the user gave.
    throw FileError(o.input, 0, std::string(e.what()));
  }
  WriteSelfEdgeNote(out, o.input, file);
  out << "wrote " << o.output << " (" << format << ")\n";
}

}  // namespace

void AddExportCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<ExportOptions>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Write a pose graph for other tools: the trajectory as TUM (evo), the whole graph as "
      "JSON or GraphViz, or a picture (SVG, PNG) with accepted and rejected closures.");
  cmd->add_option("graph", o->input, "Pose-graph file (g2o, TORO, iSAM)")->required();
  cmd->add_option("-o,--output", o->output, "Output file")->required();
  cmd->add_option("--format", o->format, "Output format; default: from the output's extension")
      ->check(CLI::IsMember({"tum", "json", "dot", "svg", "png", "g2o"}));
  cmd->add_option("--input-format", o->input_format,
                  "Input format; auto decides from the tags (and .graph for TORO)")
      ->check(CLI::IsMember({"auto", "g2o", "toro", "isam"}))
      ->capture_default_str();
  cmd->add_option("--title", o->title, "Picture title (default: the input path)");
  cmd->callback([o, &out] { RunExport(*o, out); });
}

}  // namespace catgraph
