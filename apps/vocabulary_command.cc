// catgraph vocabulary train DATASET... -o vocab.yml [--words K] [--feature F]
//                                      [--traversal T] [--every N] [--seed S]
#include <cstdio>
#include <memory>
#include <string>
#include <vector>


#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "backend/io/dataset.h"
#include "backend/io/output_directory.h"
#include "frontend/vocabulary.h"

namespace catgraph {
namespace {

struct VocabularyCommandOptions {
  std::vector<std::string> datasets;
  std::string output, feature = "sift";
  int traversal = 0;
  std::size_t every = 4;
  VocabularyOptions vocabulary;
  bool quiet = false;
};

void RunTrain(const VocabularyCommandOptions& o, std::ostream& out) {
  if (o.every < 1) throw std::invalid_argument("--every: expected >= 1");
  VocabularyOptions options = o.vocabulary;
  options.feature = FeatureTypeFromString(o.feature);
  std::vector<std::filesystem::path> paths;
  for (const auto& name : o.datasets) {
    const Dataset d = ReadDataset(name);
    RefuseOutputClashes({o.output}, DatasetFiles(d));
    for (std::size_t i = 0; i < d.frames.size(); i += o.every) {
      if (o.traversal == 0 || d.frames[i].traversal == o.traversal) paths.push_back(d.ImagePath(i));
    }
  }
  if (paths.empty()) throw std::invalid_argument("no training images (check --traversal)");
  ProgressBar bar("images read");
  std::vector<cv::Mat> images;
  for (const auto& path : paths) {
    images.push_back(ReadImage(path));
    if (!o.quiet) bar.Update(images.size(), paths.size());
  }
  const Vocabulary vocabulary = TrainVocabulary(images, options);
  vocabulary.Save(o.output);
  out << "wrote " << o.output << ": " << vocabulary.size() << " " << o.feature << " words from "
      << images.size() << " images, with their Chow-Liu tree\n";
}

}  // namespace

void AddVocabularyCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<VocabularyCommandOptions>();
  CLI::App* cmd = app.add_subcommand("vocabulary", "Visual vocabularies for the front end");
  cmd->require_subcommand(1);
  CLI::App* train = cmd->add_subcommand(
      "train",
      "Train a visual vocabulary (k-means over local features) and its Chow-Liu tree on the "
      "images of one or more datasets. Train on data that is not the traversal you will "
      "localise (--traversal 1, or another dataset).");
  train->add_option("datasets", o->datasets, "Dataset directories")->required();
  train->add_option("-o,--output", o->output, "Vocabulary file to write (.yml)")->required();
  train->add_option("--words", o->vocabulary.words, "Number of words (k)")->capture_default_str();
  train->add_option("--feature", o->feature, "sift, orb, akaze or kaze")->capture_default_str();
  train->add_option("--traversal", o->traversal, "Only this traversal's frames (0: all)")->capture_default_str();
  train->add_option("--every", o->every, "Every N-th frame")->capture_default_str();
  train->add_option("--seed", o->vocabulary.seed, "k-means seed")->capture_default_str();
  train->add_option("--iterations", o->vocabulary.kmeans_iterations, "k-means iterations")->capture_default_str();
  train->add_flag("--quiet", o->quiet, "No progress bar");
  train->callback([o, &out] { RunTrain(*o, out); });
}

}  // namespace catgraph
