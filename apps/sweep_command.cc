// catgraph sweep --config FILE [-o CSV] [--jobs N] [--shard i/n] [--plot PREFIX]
// catgraph sweep merge CSV... -o OUT [--plot PREFIX]
// catgraph sweep plot CSV --prefix PREFIX
#include <unistd.h>

#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "experiments/sweep.h"
#include "backend/io/output_directory.h"

namespace catgraph {
namespace {

std::atomic<bool> g_stop{false};

extern "C" void OnInterrupt(int) {
  g_stop.store(true);
  std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C ends at once
}

struct SweepCommandOptions {
  std::string config, output, shard = "0/1", plot;
  int jobs = 0;
  bool quiet = false;
  std::vector<std::string> merge_inputs;
  std::string merge_output, merge_plot;
  std::string plot_csv, plot_prefix;
};

void PrintWritten(const std::vector<std::filesystem::path>& files, std::ostream& out) {
  for (const auto& f : files) out << "wrote " << f.string() << '\n';
}

void RunSweepCommand(const SweepCommandOptions& o, std::ostream& out) {
  SweepConfig config = ReadSweepConfigFile(o.config);
  if (!o.output.empty()) config.output = o.output;
  if (config.output.empty()) {
    throw std::invalid_argument("no output CSV: give -o or 'output' in " + o.config);
  }
  std::vector<std::filesystem::path> inputs = {o.config};
  for (const SweepDataset& d : config.datasets) {
    inputs.push_back(d.graph);
    inputs.push_back(d.truth);
  }
  RefuseOutputClashes({config.output}, inputs);
  SweepOptions options;
  options.shard = ParseShard(o.shard);
  options.jobs = o.jobs;
  auto bar = std::make_shared<ProgressBar>("runs");
  if (!o.quiet) {
    options.on_progress = [bar](const SweepProgress& p) { bar->Update(p.done, p.total, p.elapsed_s); };
  }
  g_stop.store(false);
  options.stop = &g_stop;
  const auto previous = std::signal(SIGINT, OnInterrupt);
  SweepSummary s;
  try {
    s = RunSweep(config, options);
  } catch (...) {
    std::signal(SIGINT, previous);
    throw;
  }
  std::signal(SIGINT, previous);
  out << "sweep " << o.config << " (shard " << o.shard << "): " << s.planned << " runs, "
      << s.resumed << " already in " << config.output.string() << ", " << s.finished
      << " run now" << (s.failed ? " (" + std::to_string(s.failed) + " solver failures)" : "")
      << '\n';
  if (s.stopped) {
    out << "interrupted: every finished run is in " << config.output.string()
        << "; rerun the same command to resume\n";
    throw std::runtime_error("sweep interrupted");
  }
  if (!o.plot.empty()) PrintWritten(PlotSweep(config.output, o.plot), out);
}

}  // namespace

void AddSweepCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<SweepCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sweep",
      "Run a false-positive experiment grid (datasets x policies x outlier counts x seeds x "
      "methods) on every core, appending each finished run to a CSV; rerun to resume.");
  cmd->add_option("--config", o->config, "Sweep configuration (JSON, or YAML: .yaml/.yml)");
  cmd->add_option("-o,--output", o->output, "CSV of finished runs (default: 'output' of the config)");
  cmd->add_option("--jobs", o->jobs, "Parallel runs; 0 = every core")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_option("--shard", o->shard,
                  "Run only slice i of n (0 <= i < n): run k belongs to shard k mod n")
      ->capture_default_str();
  cmd->add_option("--plot", o->plot,
                  "When done, write PREFIX-<dataset>.png/.svg/.md from the CSV");
  cmd->add_flag("--quiet", o->quiet, "No progress bar");

  CLI::App* merge = cmd->add_subcommand("merge", "Merge shard CSVs into one (one row per run)");
  merge->add_option("inputs", o->merge_inputs, "Shard CSVs")->required();
  merge->add_option("-o,--output", o->merge_output, "Merged CSV")->required();
  merge->add_option("--plot", o->merge_plot, "Also write PREFIX-<dataset>.png/.svg/.md");
  merge->callback([o, &out] {
    std::vector<std::filesystem::path> inputs(o->merge_inputs.begin(), o->merge_inputs.end());
    RefuseOutputClashes({o->merge_output}, inputs);
    MergeSweepCsv(inputs, o->merge_output);
    out << "wrote " << o->merge_output << '\n';
    if (!o->merge_plot.empty()) PrintWritten(PlotSweep(o->merge_output, o->merge_plot), out);
  });

  CLI::App* plot = cmd->add_subcommand("plot", "Plot and tabulate a sweep CSV");
  plot->add_option("csv", o->plot_csv, "Sweep CSV")->required();
  plot->add_option("--prefix", o->plot_prefix, "Writes PREFIX-<dataset>.png/.svg/.md")->required();
  plot->callback([o, &out] { PrintWritten(PlotSweep(o->plot_csv, o->plot_prefix), out); });

  cmd->callback([o, cmd, &out] {
    if (!cmd->get_subcommands().empty()) return;  // merge or plot ran
    if (o->config.empty()) throw CLI::RequiredError("--config");
    RunSweepCommand(*o, out);
  });
}

}  // namespace catgraph
