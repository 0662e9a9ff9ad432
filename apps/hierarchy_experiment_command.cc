// catgraph hierarchy-experiment DATASET -o OUT/ [--inject-false-visual N]
//     [--seeds 1,2,3,4,5] [--hierarchies cascade,coupled,flat] [--method M]
//     [--false-stretch M] [--false-min-error M] [--false-max-error M]
//     [--feedback-reruns N] [localize options]
//
// What the closure hierarchy buys against false visual matches at the
// source: for each seed, the front end without and with N injected false
// matches (catgraph map --inject-false-visual), each solved under every
// policy. One row per seed and policy in hierarchy-experiment.csv, and the
// table in hierarchy-experiment.md with the command that regenerates it.
// The features are extracted once. docs/mapping.md.
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "experiments/hierarchy_experiment.h"

namespace catgraph {
namespace {

struct ExperimentOptions {
  LocalizeCommandOptions front;
  std::string method = "switchable";
  HierarchyExperimentOptions experiment;  // front_end and back_end from `front`
};

using Row = HierarchyExperimentRow;

std::string Command(const ExperimentOptions& o) {
  std::ostringstream c;
  c << "catgraph hierarchy-experiment " << o.front.dataset << " -o " << o.front.output << " --inject-false-visual "
    << o.experiment.injection.count << " --seeds ";
  for (std::size_t i = 0; i < o.experiment.seeds.size(); ++i) c << (i ? "," : "") << o.experiment.seeds[i];
  c << " --hierarchies ";
  for (std::size_t i = 0; i < o.experiment.hierarchies.size(); ++i) c << (i ? "," : "") << o.experiment.hierarchies[i];
  c << " --method " << o.method << " --false-stretch " << o.experiment.injection.stretch_m << " --false-min-error "
    << o.experiment.injection.min_error_m;
  if (std::isfinite(o.experiment.injection.max_error_m)) {
    c << " --false-max-error " << o.experiment.injection.max_error_m;
  }
  c << " --feedback-reruns " << o.experiment.feedback_reruns;
  return c.str();
}

void WriteTables(const ExperimentOptions& o, const std::vector<Row>& rows, const std::filesystem::path& dir) {
  const FalseMatchOptions& injection = o.experiment.injection;
  WriteFileAtomically(dir / "hierarchy-experiment.csv", [&](std::ostream& f) {
    f << "seed,hierarchy,false_closures,false_closures_rejected,children,children_accepted,children_of_rejected,"
         "children_of_rejected_accepted,children_turned_off,accepted_children_error_max_m,ate_without_m,"
         "ate_with_m,ate_oracle_m,ate_ratio,solves,reruns\n";
    for (const Row& r : rows) {
      const mapping::InjectionOutcome& i = r.injection;
      f << r.seed << ',' << r.hierarchy << ',' << i.parents << ',' << i.parents_rejected << ',' << i.children << ','
        << i.children_accepted << ',' << i.children_of_rejected << ',' << i.children_of_rejected_accepted << ','
        << i.children_turned_off << ','
        << (i.accepted_child_errors.empty() ? std::string() : Number(StatisticsOf(i.accepted_child_errors).max))
        << ',' << Number(r.ate_without_m) << ',' << Number(r.ate_with_m) << ',' << Number(r.ate_oracle_m) << ','
        << Number(r.ate_with_m / r.ate_without_m) << ',' << r.solves << ',' << r.reruns << '\n';
    }
  });
  WriteFileAtomically(dir / "hierarchy-experiment.md", [&](std::ostream& f) {
    f << "# False visual matches at the source: what the closure hierarchy buys\n\n"
      << "Regenerate with\n\n    " << Command(o) << "\n\n"
      << injection.count << " false matches per run on `" << o.front.dataset << "`, each a pair of false visual "
      << "closures around a " << injection.stretch_m << " m stretch at least " << injection.min_error_m
      << " m from the truth; CAT-Graph+ infers the closures between them (their *children*). "
      << "\"Children of rejected\" have a false parent the back end rejected; \"survive\" is how many of those "
      << "it still accepted (both from the first solve). Under cascade and coupled the back end's verdict is then "
      << "fed back: CAT-Graph+ is re-run with the rejected visual closures vetoed and the map solved again "
      << "(\"re-runs\"; flat is solved once). ATE is the RMSE after alignment of the final map, without and with "
      << "the injection, same seed and policy; \"oracle\" is the run with injection, its front end re-run with the "
      << "false closures vetoed from the start: what perfect rejection and feedback could do.\n\n"
      << "| seed | hierarchy | false closures rejected | children (accepted) | children of rejected | survive | "
         "turned off by the hierarchy | accepted children's max error (m) | re-runs | ATE without (m) | "
         "ATE with (m) | ratio | ATE oracle (m) |\n"
      << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows) {
      const mapping::InjectionOutcome& i = r.injection;
      f << "| " << r.seed << " | " << r.hierarchy << " | " << i.parents_rejected << " / " << i.parents << " | "
        << i.children << " (" << i.children_accepted << ") | " << i.children_of_rejected << " | "
        << i.children_of_rejected_accepted << " | " << i.children_turned_off << " | "
        << (i.accepted_child_errors.empty() ? "–" : Number(StatisticsOf(i.accepted_child_errors).max, "%.2f"))
        << " | " << r.reruns << " | " << Number(r.ate_without_m, "%.3f") << " | " << Number(r.ate_with_m, "%.3f") << " | "
        << Number(r.ate_with_m / r.ate_without_m, "%.2f") << " | " << Number(r.ate_oracle_m, "%.3f") << " |\n";
    }
    f << "\n| hierarchy | seeds with every child of a rejected false parent off | seeds with ATE within 10 % | "
         "children that survive a rejected parent, in all |\n|---|---|---|---|\n";
    for (const std::string& h : o.experiment.hierarchies) {
      int all_off = 0, within = 0, seeds = 0, survivors = 0;
      for (const Row& r : rows) {
        if (r.hierarchy != h) continue;
        ++seeds;
        all_off += r.injection.children_of_rejected_accepted == 0 ? 1 : 0;
        within += r.ate_with_m <= 1.1 * r.ate_without_m ? 1 : 0;
        survivors += r.injection.children_of_rejected_accepted;
      }
      f << "| " << h << " | " << all_off << " of " << seeds << " | " << within << " of " << seeds << " | "
        << survivors << " |\n";
    }
  });
}

void RunExperiment(ExperimentOptions& o, std::ostream& out) {
  ValidateOptions(o.front);
  o.experiment.back_end = o.front.pipeline.back_end;
  o.experiment.back_end.method = *RobustMethodFromString(o.method);
  Validate(o.experiment.back_end);
  for (const std::string& h : o.experiment.hierarchies) mapping::HierarchyOptionsFor(h, o.experiment.back_end);
  OutputDirectory output = OpenOutputDirectory(o.front, "hierarchy-experiment");
  const Dataset d = ReadDataset(o.front.dataset);
  if (!d.HasGroundTruth()) throw std::invalid_argument(o.front.dataset + ": the experiment needs ground truth");

  o.front.quiet = true;  // no progress bars: dozens of filter runs
  const FrontEndInputs inputs = PrepareFrontEnd(d, o.front, out);
  o.experiment.front_end = o.front.pipeline.front_end;
  const std::vector<Row> rows =
      RunHierarchyExperiment(d, inputs.observations, *inputs.model, o.experiment, [&out](const Row& row) {
        const mapping::InjectionOutcome& i = row.injection;
        out << "seed " << row.seed << ", " << row.hierarchy << ": " << i.parents_rejected << " of " << i.parents
            << " false closures rejected, " << i.children_of_rejected_accepted << " of " << i.children_of_rejected
            << " children of rejected ones survive; ATE " << Number(row.ate_without_m, "%.3f") << " -> "
            << Number(row.ate_with_m, "%.3f") << " m (oracle " << Number(row.ate_oracle_m, "%.3f") << " m)\n";
      });
  WriteTables(o, rows, output.path());
  output.Commit();
  out << "wrote " << (std::filesystem::path(o.front.output) / "hierarchy-experiment.md").string() << " and .csv\n";
}

}  // namespace

void AddHierarchyExperimentCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<ExperimentOptions>();
  CLI::App* cmd = app.add_subcommand(
      "hierarchy-experiment",
      "False visual matches at the source, seeds x hierarchy policies: what the closure hierarchy buys "
      "(hierarchy-experiment.md/.csv). docs/mapping.md.");
  cmd->add_option("dataset", o->front.dataset, "Dataset directory (with ground truth)")->required();
  cmd->add_option("-o,--output", o->front.output, "Output directory")->required();
  cmd->add_option("--inject-false-visual", o->experiment.injection.count, "False matches per run")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--seeds", o->experiment.seeds, "Seeds (filter and injection)")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--hierarchies", o->experiment.hierarchies, "Policies")
      ->delimiter(',')
      ->check(CLI::IsMember({"cascade", "coupled", "flat"}))
      ->capture_default_str();
  cmd->add_option("--method", o->method, "Robust method for loop closures (as catgraph optimize)")
      ->check(CLI::IsMember(RobustMethodNames()))
      ->capture_default_str();
  AddFalseMatchOptions(*cmd, o->experiment.injection);
  AddLocalizationOptions(*cmd, o->front);
  cmd->remove_option(cmd->get_option("--seed"));  // --seeds
  cmd->add_option("--feedback-reruns", o->experiment.feedback_reruns,
                  "cascade and coupled: front-end re-runs with the rejected visual closures vetoed (as catgraph map)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--threads", o->front.pipeline.front_end.threads, "Feature-extraction threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  AddOverwriteFlag(*cmd, o->front.overwrite);
  cmd->callback([o, &out] { RunExperiment(*o, out); });
}

}  // namespace catgraph
