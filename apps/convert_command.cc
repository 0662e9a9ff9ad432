// catgraph convert-vprbench SRC -o DIR [--spacing-m D] [--seed S]
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "backend/io/output_directory.h"
#include "simulation/vprbench_import.h"

namespace catgraph {

void AddConvertCommand(CLI::App& app, std::ostream& out) {
  struct Options {
    std::string source, output;
    VprBenchImportOptions import;
    bool quiet = false, overwrite = false;
  };
  auto o = std::make_shared<Options>();
  CLI::App* cmd = app.add_subcommand(
      "convert-vprbench",
      "Turn a VPR-Bench image set (ref/ and query/, index-aligned, e.g. "
      "../shared/datasets/images/corridor_vprbench) into a catgraph dataset with synthetic "
      "odometry along a made-up straight route; meta.json says what is synthetic.");
  cmd->add_option("source", o->source, "Folder with ref/ and query/")->required();
  cmd->add_option("-o,--output", o->output, "Dataset directory to write")->required();
  cmd->add_option("--spacing-m", o->import.spacing_m, "Made-up distance between frames (m)")->capture_default_str();
  cmd->add_option("--speed", o->import.speed_m_s, "Made-up driving speed (m/s)")->capture_default_str();
  cmd->add_option("--seed", o->import.seed, "Odometry noise seed")->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "No progress bar");
  AddOverwriteFlag(*cmd, o->overwrite);
  cmd->callback([o, &out] {
    auto bar = std::make_shared<ProgressBar>("images");
    if (!o->quiet) o->import.on_progress = [bar](std::size_t done, std::size_t total) { bar->Update(done, total); };
    OutputDirectory output(o->output, "convert-vprbench", o->overwrite, {o->source});
    const VprBenchImportSummary s = ImportVprBench(o->source, output.path(), o->import);
    output.Commit();
    out << "wrote " << o->output << ": " << s.reference_frames << " reference frames (traversal 1), "
        << s.query_frames << " query frames (traversal 2); odometry and metric ground truth are "
        << "synthetic (meta.json)\n";
  });
}

}  // namespace catgraph
