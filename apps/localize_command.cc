// catgraph localize DATASET [--vocabulary V] -o OUT/ [--particles N] [--seed S]
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "apps/progress_bar.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "experiments/inference_sweep.h"
#include "frontend/localization.h"

namespace catgraph {
namespace {

void RunLocalize(LocalizeCommandOptions& o, std::ostream& out) {
  ValidateOptions(o);
  OutputDirectory output = OpenOutputDirectory(o, "localize");
  const Dataset d = ReadDataset(o.dataset);
  const LocalizationResult r = RunLocalization(d, o, out);
  WriteLocalization(output.path(), d, r, o.pipeline.front_end.filter.closure_threshold);
  WriteOptions(output.path(), o);
  output.Commit();
  out << "wrote " << o.output << ": ";
  PrintLocalizationSummary(d, r, o.pipeline.front_end.filter.inference.enabled, out);
}

struct InferenceSweepCommandOptions {
  LocalizeCommandOptions base;
  InferenceSweepOptions sweep;
  // Each cell mapped as `catgraph map` does (the back end and hierarchy of
  // the options, the back end's verdict fed back), not the front end alone.
  bool back_end = false;
};

// The CAT-Graph+ paper's Table III: CAT-Graph+ over every (d_tot, d_loc),
// the features extracted once.
void RunInferenceSweepCommand(InferenceSweepCommandOptions& o, std::ostream& out) {
  if (!(o.sweep.false_threshold_m > 0.0)) throw std::invalid_argument("--false-threshold: expected > 0");
  ValidateOptions(o.base);
  OutputDirectory output = OpenOutputDirectory(o.base, "inference-sweep");
  const Dataset d = ReadDataset(o.base.dataset);
  if (!d.HasGroundTruth()) throw FileError(o.base.dataset, 0, "the sweep needs ground truth (groundtruth.csv)");
  const FrontEndInputs inputs = PrepareFrontEnd(d, o.base, out);
  o.sweep.front_end = o.base.pipeline.front_end;
  if (o.back_end) o.sweep.back_end = {o.base.pipeline.back_end, o.base.pipeline.hierarchy};
  ProgressBar bar("runs");
  const std::vector<InferenceSweepCell> cells =
      RunInferenceSweep(d, inputs.observations, *inputs.model, o.sweep, [&](std::size_t done, std::size_t total) {
        if (!o.base.quiet) bar.Update(done, total);
      });

  std::ostringstream csv, table, accepted_table;
  csv << "d_tot_m,d_loc_m,inferred,false,largest_error_m,mean_false_error_m,mean_error_m,discarded,false_accepted,"
         "reruns,dropped\n";
  auto header = [&o](std::ostringstream& t) {
    t << "| d_tot \\ d_loc |";
    for (const double l : o.sweep.d_loc_m) t << ' ' << Number(l, "%.1f") << " |";
    t << "\n|---|";
    for (std::size_t i = 0; i < o.sweep.d_loc_m.size(); ++i) t << "---|";
    t << '\n';
  };
  table << "False inferences (error > " << Number(o.sweep.false_threshold_m, "%.2f")
        << " m): count / largest error / mean error of the false ones / mean error of all inferences (m)"
        << (o.back_end ? ", in the front end's last run after the back end's feedback" : "") << ".\n\n";
  header(table);
  accepted_table << "\nFalse inferences the back end accepted (switchable, cascade), of those above.\n\n";
  header(accepted_table);
  std::size_t k = 0;
  for (const double t : o.sweep.d_tot_m) {
    table << "| " << Number(t, "%.1f") << " m |";
    accepted_table << "| " << Number(t, "%.1f") << " m |";
    for (std::size_t l = 0; l < o.sweep.d_loc_m.size(); ++l, ++k) {
      const InferenceSweepCell& c = cells[k];
      csv << c.d_tot_m << ',' << c.d_loc_m << ',' << c.inferred << ',' << c.wrong << ',' << Number(c.largest_error_m)
          << ',' << Number(c.mean_false_error_m) << ',' << Number(c.mean_error_m) << ',' << c.discarded << ',';
      if (c.false_accepted) {
        csv << *c.false_accepted << ',' << c.reruns;
        accepted_table << ' ' << *c.false_accepted << " |";
      } else {
        csv << ',';
      }
      csv << ',' << c.dropped << '\n';
      table << ' '
            << (c.wrong == 0 ? std::string("0")
                             : std::to_string(c.wrong) + " / " + Number(c.largest_error_m, "%.2f") + " / " +
                                   Number(c.mean_false_error_m, "%.2f") + " / " + Number(c.mean_error_m, "%.2f"))
            << " |";
    }
    table << '\n';
    accepted_table << '\n';
  }
  if (o.back_end) table << accepted_table.str();
  WriteFileAtomically(output.path() / "sweep.csv", [&](std::ostream& f) { f << csv.str(); });
  WriteFileAtomically(output.path() / "table.md", [&](std::ostream& f) { f << table.str(); });
  output.Commit();
  out << table.str();
}

}  // namespace

void AddInferenceSweepCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<InferenceSweepCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "inference-sweep",
      "CAT-Graph+ over a grid of total-path (d_tot) and local (d_loc) validation tolerances, the features "
      "extracted once: false inferences per cell, as the CAT-Graph+ paper's Table III (sweep.csv, table.md).");
  cmd->add_option("dataset", o->base.dataset, "Dataset directory (with ground truth)")->required();
  cmd->add_option("-o,--output", o->base.output, "Output directory")->required();
  // Every filter option of localize, but the two tolerances swept.
  AddLocalizationOptions(*cmd, o->base, {"--observation", "--vocabulary", "--particles", "--seed"});
  for (const char* swept : {"--d-tot", "--d-loc", "--no-odometric-inference"}) {
    const CLI::Option* option = cmd->get_option(swept);
    std::erase_if(o->base.option_fields, [option](const auto& field) { return field.first == option; });
    cmd->remove_option(cmd->get_option(swept));
  }
  cmd->add_option("--d-tot", o->sweep.d_tot_m, "d_tot values (m)")->delimiter(',')->capture_default_str();
  cmd->add_option("--d-loc", o->sweep.d_loc_m, "d_loc values (m)")->delimiter(',')->capture_default_str();
  cmd->add_option("--false-threshold", o->sweep.false_threshold_m,
                  "An inference farther than this from the truth is false (m)")
      ->capture_default_str();
  cmd->add_flag("--back-end", o->back_end,
                "Map each cell as catgraph map does (the back end and hierarchy of the options, the rejected "
                "visual closures vetoed and CAT-Graph+ re-run); also counts the false inferences the back end "
                "accepted");
  cmd->add_option("--threads", o->base.pipeline.front_end.threads, "Feature-extraction threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_flag("--quiet", o->base.quiet, "No progress bar");
  AddOverwriteFlag(*cmd, o->base.overwrite);
  cmd->callback([o, &out] { RunInferenceSweepCommand(*o, out); });
}

void AddLocalizeCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<LocalizeCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "localize",
      "Appearance-based localisation with CAT-Graph: per-frame location hypotheses, visual loop "
      "closures and the pose graph (hypotheses.csv, closures.json, graph.g2o). Defaults and the "
      "choices beyond the paper: docs/frontend.md.");
  cmd->alias("localise");
  cmd->add_option("dataset", o->dataset, "Dataset directory")->required();
  cmd->add_option("-o,--output", o->output, "Output directory")->required();
  AddLocalizationOptions(*cmd, *o);
  cmd->add_option("--threads", o->pipeline.front_end.threads, "Feature-extraction threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "No progress bars");
  AddOverwriteFlag(*cmd, o->overwrite);
  cmd->callback([o, &out] { RunLocalize(*o, out); });
}

}  // namespace catgraph
