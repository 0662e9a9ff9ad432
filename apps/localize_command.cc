// catgraph localize DATASET [--vocabulary V] -o OUT/ [--particles N] [--seed S]
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "frontend/localization.h"

namespace catgraph {
namespace {

struct LocalizeCommandOptions {
  std::string dataset, vocabulary, output;
  int words = 500, train_every = 8, threads = 0;
  LocalizationOptions localization;
  bool quiet = false;
};

// The default vocabulary: trained on the dataset's first traversal (the map),
// never on the traversals that are localised against it.
Vocabulary VocabularyFor(const Dataset& d, const LocalizeCommandOptions& o, std::ostream& out) {
  if (!o.vocabulary.empty()) return Vocabulary::Load(o.vocabulary);
  const int first = d.Traversals().front();
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < d.frames.size(); i += static_cast<std::size_t>(o.train_every)) {
    if (d.frames[i].traversal != first) continue;
    images.push_back(cv::imread(d.ImagePath(i).string(), cv::IMREAD_COLOR));
    if (images.back().empty()) throw FileError(d.ImagePath(i).string(), 0, "cannot decode the image");
  }
  VocabularyOptions options;
  options.words = o.words;
  Vocabulary v = TrainVocabulary(images, options);
  out << "trained a " << v.size() << "-word SIFT vocabulary on " << images.size()
      << " frames of traversal " << first << "\n";
  return v;
}

std::string Number(double value, const char* format = "%.4f") {
  if (std::isnan(value)) return "";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

void RunLocalize(LocalizeCommandOptions& o, std::ostream& out) {
  if (o.train_every < 1) throw std::invalid_argument("--train-every: expected >= 1");
  const Dataset d = ReadDataset(o.dataset);
  const Vocabulary vocabulary = VocabularyFor(d, o, out);
  auto features = std::make_shared<ProgressBar>("frames: features");
  auto filter = std::make_shared<ProgressBar>("frames: filter");
  if (!o.quiet) {
    o.localization.on_progress = [features, filter](const char* stage, std::size_t done, std::size_t total) {
      (std::string(stage) == "features" ? features : filter)->Update(done, total);
    };
  }
  o.localization.threads = o.threads;
  const LocalizationResult r = Localize(d, vocabulary, o.localization);

  const std::filesystem::path dir(o.output);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw FileError(dir.string(), 0, "cannot create the output directory: " + ec.message());
  WriteFileAtomically(dir / "hypotheses.csv", [&](std::ostream& f) {
    f << "frame,traversal,edge_from_frame,edge_to_frame,alpha,direction,hypothesis,new_place,closure,"
         "matched_frame,error_m\n";
    for (const auto& h : r.frames) {
      f << h.frame << ',' << h.traversal << ',' << h.edge_from_frame << ',' << h.edge_to_frame << ','
        << Number(h.best.alpha) << ',' << h.best.direction << ',' << Number(h.best.value) << ','
        << Number(h.new_place_probability) << ',' << (h.closure ? 1 : 0) << ',' << h.matched_frame << ','
        << Number(h.error_m) << '\n';
    }
  });
  nlohmann::ordered_json closures = nlohmann::ordered_json::array();
  for (const auto& c : r.closures) {
    nlohmann::ordered_json j{{"id", c.id},
                             {"frame", c.frame},
                             {"matched_frame", c.matched_frame},
                             {"kind", "visual"},
                             {"hypothesis", c.hypothesis},
                             {"relative_pose", {c.T_frame_matched.x(), c.T_frame_matched.y(), c.T_frame_matched.theta()}}};
    j["error_m"] = std::isnan(c.error_m) ? nlohmann::ordered_json() : nlohmann::ordered_json(c.error_m);
    closures.push_back(j);
  }
  WriteFileAtomically(dir / "closures.json", [&](std::ostream& f) { f << closures.dump(1) << '\n'; });
  WriteG2oFile(AnyPoseGraph(r.graph), dir / "graph.g2o");

  double sum = 0.0, worst = 0.0;
  int with_error = 0;
  for (const auto& c : r.closures) {
    if (std::isnan(c.error_m)) continue;
    sum += c.error_m;
    worst = std::max(worst, c.error_m);
    ++with_error;
  }
  out << "wrote " << o.output << ": " << r.frames.size() << " frames, " << r.closures.size()
      << " visual closures (median " << r.words_per_frame_median << " words per frame)";
  if (with_error > 0) {
    out << "; closure error mean " << Number(sum / with_error, "%.3f") << " m, max " << Number(worst, "%.3f")
        << " m";
  }
  out << '\n';
}

}  // namespace

void AddLocalizeCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<LocalizeCommandOptions>();
  CatGraphOptions& f = o->localization.filter;
  CLI::App* cmd = app.add_subcommand(
      "localize",
      "Appearance-based localisation with CAT-Graph: per-frame location hypotheses, visual loop "
      "closures and the pose graph. In progress (issue #6): on corridor data it still makes "
      "false closures; see docs/frontend.md.");
  cmd->alias("localise");
  cmd->add_option("dataset", o->dataset, "Dataset directory")->required();
  cmd->add_option("-o,--output", o->output, "Output directory")->required();
  cmd->add_option("--vocabulary", o->vocabulary,
                  "Vocabulary file (catgraph vocabulary train); default: train one on the first traversal");
  cmd->add_option("--words", o->words, "Words of the default vocabulary")->capture_default_str();
  cmd->add_option("--train-every", o->train_every, "Default vocabulary: every N-th frame of the first traversal")
      ->capture_default_str();
  cmd->add_option("--particles", f.num_particles, "n_p")->capture_default_str();
  cmd->add_option("--closure-threshold", f.closure_threshold, "T_h")->capture_default_str();
  cmd->add_option("--hypothesis-radius", f.hypothesis_radius_m, "d_h (m)")->capture_default_str();
  cmd->add_option("--new-place-prior", f.new_place_prior, "p_new")->capture_default_str();
  cmd->add_option("--exclusion-s", f.exclusion_window_s, "Self-match exclusion window (s)")->capture_default_str();
  cmd->add_option("--exclusion-m", f.exclusion_window_m, "Self-match exclusion window (m of path)")->capture_default_str();
  cmd->add_option("--seed", f.seed, "Filter seed")->capture_default_str();
  cmd->add_option("--threads", o->threads, "Feature-extraction threads (0: every core)")->capture_default_str();
  cmd->add_flag("--quiet", o->quiet, "No progress bars");
  cmd->callback([o, &out] { RunLocalize(*o, out); });
}

}  // namespace catgraph
