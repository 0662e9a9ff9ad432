// catgraph generate-graph -o OUT [--truth TRUTH] [--poses N] [--seed S] ...
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "apps/commands.h"
#include "backend/io/graph_io.h"
#include "backend/io/output_directory.h"
#include "simulation/manhattan_world.h"

namespace catgraph {
namespace {

struct GenerateGraphOptions {
  ManhattanWorldOptions world;
  std::string output;
  std::string truth;
};

void RunGenerateGraph(const GenerateGraphOptions& options, std::ostream& out) {
  if (const double edges = ExpectedManhattanEdges(options.world); edges > kMaxManhattanEdges) {
    throw CLI::ValidationError("--poses", std::to_string(options.world.num_poses) + " poses on a " +
                                              std::to_string(options.world.grid_cells) +
                                              "-step square would make about " +
                                              std::to_string(static_cast<long long>(edges)) +
                                              " edges, more than " +
                                              std::to_string(static_cast<long long>(kMaxManhattanEdges)) +
                                              ": widen the square (--grid-cells)");
  }
  RefuseOutputClashes({options.output, options.truth}, {});
  const SimulatedPoseGraph2 simulated = SimulateManhattanWorld(options.world);
  WriteG2oFile(simulated.graph, options.output);
  out << "wrote " << options.output << ": " << simulated.graph.vertices.size() << " poses, "
      << simulated.graph.constraints.size() << " edges (seed " << options.world.seed << ")\n";
  if (!options.truth.empty()) {
    WriteG2oFile(simulated.truth, options.truth);
    out << "wrote " << options.truth << ": ground truth (true poses, exact measurements)\n";
  }
}

}  // namespace

void AddGenerateGraphCommand(CLI::App& app, std::ostream& out) {
  auto options = std::make_shared<GenerateGraphOptions>();
  ManhattanWorldOptions& w = options->world;
  CLI::App* cmd = app.add_subcommand(
      "generate-graph",
      "Simulate a 2D Manhattan-world pose graph with exact ground truth (g2o). The same seed "
      "gives the same file.");
  cmd->add_option("-o,--output", options->output, "Output g2o file (noisy graph)")->required();
  cmd->add_option("--truth", options->truth, "Also write the ground-truth graph here");
  cmd->add_option("--poses", w.num_poses, "Number of poses")
      ->check(CLI::Range(2, kMaxManhattanPoses))
      ->capture_default_str();
  cmd->add_option("--seed", w.seed, "Random seed")->capture_default_str();
  cmd->add_option("--grid-cells", w.grid_cells, "Side of the square the walk stays in, in steps")
      ->capture_default_str();
  cmd->add_option("--step", w.grid_step_m, "Grid step in metres")->capture_default_str();
  cmd->add_option("--turn-probability", w.turn_probability, "Chance of a turn at each step")
      ->capture_default_str();
  cmd->add_option("--closure-probability", w.closure_probability,
                  "Chance that a revisit yields a loop closure")
      ->capture_default_str();
  cmd->add_option("--odometry-sigma-m", w.odometry_sigma_m, "Odometry translation noise (m)")
      ->capture_default_str();
  cmd->add_option("--odometry-sigma-rad", w.odometry_sigma_rad, "Odometry heading noise (rad)")
      ->capture_default_str();
  cmd->callback([options, &out] { RunGenerateGraph(*options, out); });
}

}  // namespace catgraph
