// catgraph localize DATASET [--vocabulary V] -o OUT/ [--particles N] [--seed S]
#include <algorithm>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "mapping/map_dataset.h"
#include "apps/progress_bar.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "frontend/localization.h"

namespace catgraph {

using mapping::MappingResult;
using mapping::SolveWithFeedback;
using mapping::TruthAtFrames;
using mapping::kDefaultFeedbackReruns;
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

struct InferenceSweepOptions {
  LocalizeCommandOptions base;
  std::vector<double> d_tot = {0.5, 1.0, 2.5, 5.0, 7.5, 10.0, 12.5};
  std::vector<double> d_loc = {0.5, 1.0, 2.5, 5.0, 7.5, 10.0};
  double false_threshold_m = 1.0;
  // Each cell mapped as `catgraph map` does with its defaults (switchable,
  // cascade, the back end's verdict fed back), not the front end alone.
  bool back_end = false;
};

// The CAT-Graph+ paper's Table III: CAT-Graph+ over every (d_tot, d_loc),
// the features extracted once.
void RunInferenceSweep(InferenceSweepOptions& o, std::ostream& out) {
  if (!(o.false_threshold_m > 0.0)) throw std::invalid_argument("--false-threshold: expected > 0");
  ValidateOptions(o.base);
  OutputDirectory output = OpenOutputDirectory(o.base, "inference-sweep");
  const Dataset d = ReadDataset(o.base.dataset);
  if (!d.HasGroundTruth()) throw FileError(o.base.dataset, 0, "the sweep needs ground truth (groundtruth.csv)");
  const FrontEndInputs inputs = PrepareFrontEnd(d, o.base, out);
  LocalizationOptions options = o.base.pipeline.front_end;
  const std::vector<Observation>& words = inputs.observations;
  const ObservationModel& model = *inputs.model;
  const PoseGraphOptimizerOptions& optimizer = o.base.pipeline.back_end;
  const HierarchyOptions& hierarchy = o.base.pipeline.hierarchy;
  const Trajectory2 truth = TruthAtFrames(d);
  std::ostringstream csv, table, accepted_table;
  csv << "d_tot_m,d_loc_m,inferred,false,largest_error_m,mean_false_error_m,mean_error_m,discarded,false_accepted,"
         "reruns,dropped\n";
  auto header = [&o](std::ostringstream& t) {
    t << "| d_tot \\ d_loc |";
    for (const double l : o.d_loc) t << ' ' << Number(l, "%.1f") << " |";
    t << "\n|---|";
    for (std::size_t i = 0; i < o.d_loc.size(); ++i) t << "---|";
    t << '\n';
  };
  table << "False inferences (error > " << Number(o.false_threshold_m, "%.2f")
        << " m): count / largest error / mean error of the false ones / mean error of all inferences (m)"
        << (o.back_end ? ", in the front end's last run after the back end's feedback" : "") << ".\n\n";
  header(table);
  accepted_table << "\nFalse inferences the back end accepted (switchable, cascade), of those above.\n\n";
  header(accepted_table);
  ProgressBar bar("runs");
  std::size_t done = 0;
  for (const double t : o.d_tot) {
    table << "| " << Number(t, "%.1f") << " m |";
    accepted_table << "| " << Number(t, "%.1f") << " m |";
    for (const double l : o.d_loc) {
      options.filter.inference.enabled = true;
      options.filter.inference.total_validation_m = t;
      options.filter.inference.local_validation_m = l;
      LocalizationResult r = Localize(d, words, model, options);
      std::optional<MappingResult> mapped;
      if (o.back_end) {
        mapped = SolveWithFeedback(d, words, model, std::move(r), optimizer, hierarchy, truth, kDefaultFeedbackReruns);
        r = std::move(mapped->front);
      }
      int inferred = 0, wrong = 0;
      double largest = 0.0, sum_false = 0.0, sum = 0.0;
      for (const auto& c : r.closures) {
        if (c.kind != ClosureKind::kOdometryInferred) continue;
        ++inferred;
        sum += c.error_m;
        largest = std::max(largest, c.error_m);
        if (c.error_m > o.false_threshold_m) ++wrong, sum_false += c.error_m;
      }
      const double mean_false = wrong > 0 ? sum_false / wrong : 0.0, mean = inferred > 0 ? sum / inferred : 0.0;
      csv << t << ',' << l << ',' << inferred << ',' << wrong << ',' << Number(largest) << ',' << Number(mean_false)
          << ',' << Number(mean) << ',' << TotalPathDiscards(r) << ',';
      if (mapped) {
        const std::vector<double>& kept = mapped->outcome.by_kind.at(ClosureKind::kOdometryInferred).accepted_errors;
        const auto false_accepted =
            std::count_if(kept.begin(), kept.end(), [&o](double e) { return e > o.false_threshold_m; });
        csv << false_accepted << ',' << mapped->reruns;
        accepted_table << ' ' << false_accepted << " |";
      } else {
        csv << ',';
      }
      csv << ',' << r.discarded_inferences.size() - TotalPathDiscards(r) << '\n';
      table << ' ' << (wrong == 0 ? std::string("0") : std::to_string(wrong) + " / " + Number(largest, "%.2f") +
                                                          " / " + Number(mean_false, "%.2f") + " / " + Number(mean, "%.2f"))
            << " |";
      if (!o.base.quiet) bar.Update(++done, o.d_tot.size() * o.d_loc.size());
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
  auto o = std::make_shared<InferenceSweepOptions>();
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
  cmd->add_option("--d-tot", o->d_tot, "d_tot values (m)")->delimiter(',')->capture_default_str();
  cmd->add_option("--d-loc", o->d_loc, "d_loc values (m)")->delimiter(',')->capture_default_str();
  cmd->add_option("--false-threshold", o->false_threshold_m, "An inference farther than this from the truth is false (m)")
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
  cmd->callback([o, &out] { RunInferenceSweep(*o, out); });
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
