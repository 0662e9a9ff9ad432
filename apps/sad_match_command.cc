// catgraph sad-match DATASET -o OUT/ [--tolerance M] [--normalize N] [--every N] [--shift P]
// The CAT-Graph+ paper's baseline (its §5.2, Fig. 9): SAD template matching.
#include <cmath>
#include <fstream>
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/plot/figure.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/output_directory.h"
#include "frontend/sad_matcher.h"

namespace catgraph {
namespace {

struct SadCommandOptions {
  std::string dataset, output, normalization = "none", localization;
  double tolerance_m = 1.0;
  SadOptions sad;
  bool overwrite = false;
};

std::string Fixed(double value, const char* format) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

void RunSadMatch(SadCommandOptions& o, std::ostream& out) {
  if (!(o.tolerance_m > 0.0)) throw std::invalid_argument("--tolerance: expected > 0");
  o.sad.normalization = SadNormalizationFromString(o.normalization);
  std::vector<std::filesystem::path> inputs = {o.dataset};
  if (!o.localization.empty()) inputs.emplace_back(o.localization);
  OutputDirectory output(o.output, "sad-match", o.overwrite, inputs);
  const Dataset d = ReadDataset(o.dataset);
  if (!d.HasGroundTruth()) throw FileError(o.dataset, 0, "sad-match needs ground truth (groundtruth.csv)");
  const std::vector<SadMatch> matches = MatchDataset(d, o.sad);
  const double best = BestThreshold(matches, o.tolerance_m);

  const std::filesystem::path& dir = output.path();
  WriteFileAtomically(dir / "matches.csv", [&](std::ostream& f) {
    f << "query_frame,template_frame,difference,shift_px,error_m,changed,accepted\n";
    for (const auto& m : matches) {
      f << m.query_frame << ',' << m.template_frame << ',' << Fixed(m.comparison.difference, "%.6f") << ','
        << m.comparison.shift_px << ',' << Fixed(m.error_m, "%.4f") << ','
        << (d.frames[static_cast<std::size_t>(m.query_frame)].changed ? 1 : 0) << ','
        << (m.comparison.difference <= best ? 1 : 0) << '\n';
    }
  });
  WriteFileAtomically(dir / "threshold_sweep.csv", [&](std::ostream& f) {
    f << "threshold,accepted,false\n";
    for (const auto& p : SweepThreshold(matches, o.tolerance_m)) {
      f << Fixed(p.threshold, "%.6f") << ',' << p.accepted << ',' << p.false_matches << '\n';
    }
  });

  // The paper's Fig. 9: matched template against query frame; the matches
  // accepted at the best threshold, and the truth (the nearest template).
  plot::Series all{"best template", {}, {}, plot::SeriesStyle::kMarkers, {0.6, 0.6, 0.6, 0.7}, 1.5};
  plot::Series accepted{"SAD match accepted at the best threshold", {}, {}, plot::SeriesStyle::kMarkers,
                        {0.0, 0.0, 0.0, 0.8}, 2.5};
  plot::Series changed{"query frames that see a changed region", {}, {}, plot::SeriesStyle::kSegments,
                       plot::kChangedRegionColor, 4.0};
  int n_changed = 0, accepted_changed = 0, n_accepted = 0;
  for (const auto& m : matches) {
    const bool in_changed = d.frames[static_cast<std::size_t>(m.query_frame)].changed;
    const bool ok = m.comparison.difference <= best;
    all.x.push_back(m.query_frame);
    all.y.push_back(m.template_frame);
    if (ok) {
      accepted.x.push_back(m.query_frame);
      accepted.y.push_back(m.template_frame);
    }
    if (in_changed) {
      changed.x.insert(changed.x.end(), {m.query_frame - 1.0, m.query_frame + 1.0});
      changed.y.insert(changed.y.end(), {-20.0, -20.0});
    }
    n_changed += in_changed;
    accepted_changed += in_changed && ok;
    n_accepted += ok;
  }
  // Beside it, from a `catgraph localize` output: the frames CAT-Graph's
  // visual closures and CAT-Graph+'s inferred closures matched.
  plot::Series visual{"CAT-Graph visual closure", {}, {}, plot::SeriesStyle::kMarkers, plot::kVisualClosureColor, 1.5};
  plot::Series inferred{"CAT-Graph+ inferred closure", {}, {}, plot::SeriesStyle::kMarkers, plot::kInferredClosureColor,
                        1.5};
  if (!o.localization.empty()) {
    const std::filesystem::path file = std::filesystem::path(o.localization) / "closures.json";
    std::ifstream in(file);
    if (!in) throw FileError(file.string(), 0, "cannot open (expected a catgraph localize output directory)");
    nlohmann::json closures;
    try {
      closures = nlohmann::json::parse(in);
      for (const auto& c : closures) {
        plot::Series& s = c.at("kind").get<std::string>() == "inferred" ? inferred : visual;
        s.x.push_back(c.at("frame").get<double>());
        s.y.push_back(c.at("matched_frame").get<double>());
      }
    } catch (const nlohmann::json::exception& e) {
      throw FileError(file.string(), 0, std::string("expected closures.json of catgraph localize: ") + e.what());
    }
  }
  plot::Axes axes;
  axes.title = "SAD template matching (16 x 8, +-" + std::to_string(o.sad.max_shift_px) + " px), threshold " +
               Fixed(best, "%.4f");
  axes.x_label = "query frame";
  axes.y_label = "matched template frame";
  axes.series = {changed, all};
  if (!visual.x.empty()) axes.series.push_back(visual);
  if (!inferred.x.empty()) axes.series.push_back(inferred);
  axes.series.push_back(accepted);
  plot::Figure figure;
  figure.axes = {axes};
  plot::SaveFigure(figure, dir / "sad.png");
  plot::SaveFigure(figure, dir / "sad.svg");
  output.Commit();

  const double n = static_cast<double>(std::max<std::size_t>(1, matches.size()));
  out << "wrote " << o.output << ": " << matches.size() << " queries against the first traversal's templates\n"
      << "best threshold " << Fixed(best, "%.5f") << " (no match farther than " << Fixed(o.tolerance_m, "%.2f")
      << " m): " << n_accepted << " accepted (recall " << Fixed(100.0 * n_accepted / n, "%.1f") << " %)";
  if (n_changed > 0) {
    out << "; inside changed regions " << accepted_changed << " of " << n_changed << " ("
        << Fixed(100.0 * accepted_changed / n_changed, "%.1f") << " %)";
  }
  out << '\n';
}

}  // namespace

void AddSadMatchCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<SadCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "sad-match",
      "The CAT-Graph+ paper's baseline: sum-of-absolute-differences template matching of 16 x 8 grey images "
      "with sideways shifts, its threshold swept to the largest with no false match (matches.csv, "
      "threshold_sweep.csv, sad.png/svg).");
  cmd->add_option("dataset", o->dataset, "Dataset directory (with ground truth)")->required();
  cmd->add_option("-o,--output", o->output, "Output directory")->required();
  cmd->add_option("--tolerance", o->tolerance_m, "A match farther than this from the truth is false (m)")
      ->capture_default_str();
  cmd->add_option("--normalize", o->normalization, "none, local (RatSLAM) or patch (SeqSLAM)")->capture_default_str();
  cmd->add_option("--localization", o->localization,
                  "A catgraph localize output directory: its closures are drawn beside the matches")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--every", o->sad.every, "Every N-th frame is a template / a query")->capture_default_str();
  cmd->add_option("--shift", o->sad.max_shift_px, "Sideways shifts tried each way (px)")->capture_default_str();
  AddOverwriteFlag(*cmd, o->overwrite);
  cmd->callback([o, &out] { RunSadMatch(*o, out); });
}

}  // namespace catgraph
