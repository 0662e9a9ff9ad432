// catgraph simulate --scenario NAME|FILE -o DIR [--seed S] [--frames N]
// catgraph simulate --list | --print-scenario NAME
#include <algorithm>
#include <cstdio>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "backend/io/output_directory.h"
#include "simulation/office_simulator.h"
#include "simulation/scenario.h"

namespace catgraph {
namespace {

struct SimulateCommandOptions {
  std::string scenario, output, print;
  std::uint64_t seed = 0;
  std::size_t frames = 0;
  int threads = 0;
  bool list = false, quiet = false, overwrite = false;
};

void RunSimulate(const SimulateCommandOptions& o, const CLI::App& command, std::ostream& out) {
  if (o.list) {
    for (const auto& name : BuiltInScenarioNames()) out << name << '\n';
    return;
  }
  if (!o.print.empty()) {
    out << BuiltInScenarioText(o.print);
    return;
  }
  if (o.scenario.empty() || o.output.empty()) {
    throw std::invalid_argument("simulate needs --scenario and -o (or --list, --print-scenario)");
  }
  const Scenario scenario = LoadScenario(o.scenario);
  std::vector<std::filesystem::path> inputs;  // a scenario file, not a built-in name
  const std::vector<std::string> built_in = BuiltInScenarioNames();
  if (std::find(built_in.begin(), built_in.end(), o.scenario) == built_in.end()) inputs.emplace_back(o.scenario);
  OutputDirectory output(o.output, "simulate", o.overwrite, inputs);
  SimulationOptions options;
  if (command.count("--seed") > 0) options.seed = o.seed;
  options.max_frames = o.frames;
  options.threads = o.threads;
  auto bar = std::make_shared<ProgressBar>("frames");
  if (!o.quiet) options.on_progress = [bar](std::size_t done, std::size_t total) { bar->Update(done, total); };
  const SimulationSummary s = SimulateDataset(scenario, output.path(), options);
  output.Commit();
  out << "wrote " << o.output << ": scenario " << scenario.name << ", seed "
      << options.seed.value_or(scenario.seed) << ", " << s.frames << " frames (";
  for (std::size_t i = 0; i < s.frames_per_traversal.size(); ++i) {
    out << (i ? ", " : "") << "traversal " << scenario.traversals[i].id << ": "
        << s.frames_per_traversal[i];
  }
  char line[128];
  std::snprintf(line, sizeof line, "), %.1f s, %zu frames see a changed region\n", s.duration_s,
                s.changed_frames);
  out << line;
  for (std::size_t i = 0; i < s.distance_m.size(); ++i) {
    std::snprintf(line, sizeof line, "traversal %d: %.1f m driven\n", scenario.traversals[i].id,
                  s.distance_m[i]);
    out << line;
  }
}

}  // namespace

void AddSimulateCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<SimulateCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate",
      "Simulate a dataset (camera images, wheel odometry, ground truth) in the office world. "
      "Built-in scenarios: office-static, office-change, office-split, office-lighting; or a "
      "scenario file (docs/simulation.md). The same seed gives the same files.");
  cmd->add_option("--scenario", o->scenario, "Built-in scenario name or scenario file (YAML)");
  cmd->add_option("-o,--output", o->output, "Dataset directory to write (docs/dataset-format.md)");
  cmd->add_option("--seed", o->seed, "Noise seed (default: the scenario's)");
  cmd->add_option("--frames", o->frames, "Stop after this many frames (0: all)")->capture_default_str();
  cmd->add_option("--threads", o->threads, "Rendering threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_flag("--list", o->list, "List the built-in scenarios");
  cmd->add_option("--print-scenario", o->print, "Print a built-in scenario's YAML (to copy and edit)");
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  AddOverwriteFlag(*cmd, o->overwrite);
  cmd->callback([o, cmd, &out] { RunSimulate(*o, *cmd, out); });
}

}  // namespace catgraph
