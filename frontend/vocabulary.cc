#include "frontend/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <numeric>
#include <optional>
#include <utility>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Core>
#include <opencv2/core/hal/hal.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <yaml-cpp/yaml.h>

#include "backend/graph/name_table.h"
#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"
#include "backend/io/yaml_text.h"

namespace catgraph {
namespace {

constexpr int kFormatVersion = 1;
constexpr std::uintmax_t kMaxFileBytes = 512u << 20;

constexpr NameTable<FeatureType, 4> kFeatureNames{{
    {FeatureType::kSift, "sift"},
    {FeatureType::kOrb, "orb"},
    {FeatureType::kAkaze, "akaze"},
    {FeatureType::kKaze, "kaze"},
}};

cv::Ptr<cv::Feature2D> MakeDetector(FeatureType type) {
  switch (type) {
    case FeatureType::kSift: return cv::SIFT::create();
    case FeatureType::kOrb: return cv::ORB::create();
    case FeatureType::kAkaze: return cv::AKAZE::create();
    case FeatureType::kKaze: return cv::KAZE::create();
  }
  return cv::SIFT::create();
}

}  // namespace

std::string_view ToString(FeatureType type) { return NameOf(kFeatureNames, type); }

FeatureType FeatureTypeFromString(std::string_view text) {
  if (const auto type = ValueOf(kFeatureNames, text)) return *type;
  throw std::invalid_argument("unknown feature '" + std::string(text) +
                              "'; expected one of sift, orb, akaze, kaze");
}

Vocabulary::Vocabulary(FeatureType feature, cv::Mat centres, ChowLiuTree tree)
    : feature_(feature), centres_(std::move(centres)), tree_(std::move(tree)) {
  if (centres_.type() != CV_32F || centres_.rows < 2) {
    throw std::invalid_argument("vocabulary: expected at least 2 CV_32F word centres");
  }
  if (tree_.vocabulary_size() != centres_.rows || tree_.p_z.size() != tree_.parent.size() ||
      tree_.p_z_given_parent_on.size() != tree_.parent.size() ||
      tree_.p_z_given_parent_off.size() != tree_.parent.size()) {
    throw std::invalid_argument("vocabulary: the Chow-Liu tree has " +
                                std::to_string(tree_.vocabulary_size()) + " words, the centres " +
                                std::to_string(centres_.rows));
  }
}



cv::Mat ComputeDescriptors(FeatureType feature, const cv::Mat& image) {
  cv::Mat grey = image;
  if (image.channels() == 3) cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  if (image.channels() == 4) cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  MakeDetector(feature)->detectAndCompute(grey, cv::noArray(), keypoints, descriptors);
  cv::Mat out;
  if (!descriptors.empty()) descriptors.convertTo(out, CV_32F);
  return out;
}

WordSet QuantizeDescriptors(const cv::Mat& centres, const cv::Mat& descriptors) {
  WordSet words;
  if (descriptors.empty()) return words;
  if (descriptors.type() != CV_32F || centres.type() != CV_32F) {
    throw std::invalid_argument("descriptors and word centres: expected CV_32F rows");
  }
  if (descriptors.cols != centres.cols) {
    throw std::invalid_argument("descriptors of " + std::to_string(descriptors.cols) +
                                " values; the vocabulary's words have " + std::to_string(centres.cols));
  }
  // ||x - c||^2 = ||x||^2 + ||c||^2 - 2 x.c ranks the centres for every
  // descriptor at once through one matrix product, several times faster
  // than a distance per pair (BFMatcher). Its rounding could swap two
  // centres whose distances nearly tie, so every centre within the
  // product's error bound of the best is measured again as BFMatcher
  // measures it (cv::hal::normL2Sqr_, the lowest index on a tie): the words
  // are exactly BFMatcher's.
  using RowMajor = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const cv::Mat c = centres.isContinuous() ? centres : centres.clone();
  const cv::Mat d = descriptors.isContinuous() ? descriptors : descriptors.clone();
  const Eigen::Map<const RowMajor> cm(c.ptr<float>(), c.rows, c.cols);
  const Eigen::Map<const RowMajor> dm(d.ptr<float>(), d.rows, d.cols);
  const Eigen::VectorXf centre_norms = cm.rowwise().squaredNorm();
  const float max_centre_norm = std::sqrt(centre_norms.maxCoeff());
  const RowMajor products = dm * cm.transpose();
  // A float dot product of n terms is off by at most n u ||x|| ||c|| (u the
  // unit round-off; Cauchy-Schwarz on the sum of |x_k c_k|), a squared norm
  // by n u ||c||^2, and BFMatcher's own distance by n u ||x - c||^2: the
  // window 8 n u (||x|| + max ||c||)^2 holds twice all of them together.
  const float unit = std::numeric_limits<float>::epsilon() / 2.0f;
  std::vector<int> candidates;
  Eigen::VectorXf rank(c.rows);
  for (int i = 0; i < d.rows; ++i) {
    rank.noalias() = centre_norms - 2.0f * products.row(i).transpose();
    const float least = rank.minCoeff();
    const float reach = dm.row(i).norm() + max_centre_norm;
    const float tolerance = 8.0f * static_cast<float>(d.cols) * unit * reach * reach;
    candidates.clear();
    for (Eigen::Index j = 0; j < rank.size(); ++j) {
      if (rank(j) <= least + tolerance) candidates.push_back(static_cast<int>(j));
    }
    int word = candidates.front();
    if (candidates.size() > 1) {
      float nearest = std::numeric_limits<float>::infinity();
      for (const int j : candidates) {
        const float distance = std::sqrt(cv::hal::normL2Sqr_(d.ptr<float>(i), c.ptr<float>(j), d.cols));
        if (distance < nearest) {
          nearest = distance;
          word = j;
        }
      }
    }
    words.push_back(word);
  }
  std::sort(words.begin(), words.end());
  words.erase(std::unique(words.begin(), words.end()), words.end());
  return words;
}

void Validate(const VocabularyOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("VocabularyOptions: " + what); };
  if (o.words < 2) fail("words must be >= 2");
  if (o.kmeans_iterations < 1) fail("kmeans_iterations must be >= 1");
  if (o.kmeans_attempts < 1) fail("kmeans_attempts must be >= 1");
  if (o.max_descriptors < static_cast<std::size_t>(o.words)) fail("max_descriptors must be >= words");
}

Vocabulary TrainVocabulary(const std::vector<cv::Mat>& images, const VocabularyOptions& options) {
  Validate(options);
  std::vector<cv::Mat> per_image;
  int total = 0;
  for (const cv::Mat& image : images) {
    per_image.push_back(ComputeDescriptors(options.feature, image));
    total += per_image.back().rows;
  }
  if (total < options.words) {
    throw std::invalid_argument("vocabulary: the training images have " + std::to_string(total) +
                                " descriptors, fewer than the " + std::to_string(options.words) +
                                " words asked for");
  }
  cv::Mat all;
  for (const cv::Mat& d : per_image) {
    if (!d.empty()) all.push_back(d);
  }
  // A seeded random subset when there are too many to cluster.
  if (static_cast<std::size_t>(all.rows) > options.max_descriptors) {
    std::vector<int> order(static_cast<std::size_t>(all.rows));
    std::iota(order.begin(), order.end(), 0);
    std::mt19937_64 rng(options.seed);
    std::shuffle(order.begin(), order.end(), rng);
    cv::Mat subset;
    for (std::size_t i = 0; i < options.max_descriptors; ++i) subset.push_back(all.row(order[i]));
    all = subset;
  }
  cv::theRNG().state = options.seed;
  cv::Mat labels, centres;
  cv::kmeans(all, options.words, labels,
             cv::TermCriteria(cv::TermCriteria::MAX_ITER + cv::TermCriteria::EPS, options.kmeans_iterations, 1e-4),
             options.kmeans_attempts, cv::KMEANS_PP_CENTERS, centres);
  std::vector<WordSet> observations;
  for (const cv::Mat& d : per_image) observations.push_back(QuantizeDescriptors(centres, d));
  return {options.feature, centres, LearnChowLiuTree(observations, options.words)};
}

void Vocabulary::Save(const std::filesystem::path& path) const {
  cv::FileStorage fs(".yml", cv::FileStorage::WRITE | cv::FileStorage::MEMORY);
  fs << "format_version" << kFormatVersion;
  fs << "feature" << std::string(ToString(feature_));
  fs << "words" << size();
  fs << "centres" << centres_;
  fs << "tree_parent" << tree_.parent;
  fs << "tree_p_z" << tree_.p_z;
  fs << "tree_p_z_given_parent_on" << tree_.p_z_given_parent_on;
  fs << "tree_p_z_given_parent_off" << tree_.p_z_given_parent_off;
  const std::string text = fs.releaseAndGetString();
  WriteFileAtomically(path, [&](std::ostream& out) { out << text; });
}

Vocabulary Vocabulary::Load(const std::filesystem::path& path) {
  const std::string name = path.string();
  std::string text = ReadWholeFile(path, kMaxFileBytes, "a vocabulary file (catgraph vocabulary train)");
  // The file is OpenCV's YAML, written by Save, but it is read with yaml-cpp:
  // OpenCV 4.6's parser loops for ever on some 45-byte inputs and allocates
  // whatever size a matrix header declares (both found by fuzzing,
  // docs/fuzzing.md). OpenCV's first line "%YAML:1.0" is not a YAML
  // directive; it is blanked, which keeps the line numbers.
  if (text.rfind("%YAML:", 0) == 0) text.erase(0, text.find('\n'));
  int line = 0;  // of the node being read, for errors
  auto at = [&](const YAML::Node& node) -> const YAML::Node& {
    if (node.IsDefined()) line = node.Mark().line + 1;
    return node;
  };
  try {
    const YAML::Node doc = LoadYamlWithoutAliases(text, name);
    if (!doc.IsMap()) throw FileError(name, 0, "expected a catgraph vocabulary (a YAML mapping)");
    const int version = doc["format_version"] ? at(doc["format_version"]).as<int>() : 0;
    if (version != kFormatVersion) {
      throw FileError(name, line, "format_version " + std::to_string(version) + "; expected " +
                                      std::to_string(kFormatVersion) + " (a catgraph vocabulary)");
    }
    const std::string feature = at(doc["feature"]).as<std::string>();
    const YAML::Node c = at(doc["centres"]);
    if (!c.IsMap() || !c["rows"] || !c["cols"] || !c["data"] || !c["data"].IsSequence()) {
      throw FileError(name, line, "centres: expected an !!opencv-matrix with rows, cols and data");
    }
    const long long rows = at(c["rows"]).as<long long>(), cols = at(c["cols"]).as<long long>();
    const YAML::Node data = at(c["data"]);
    const auto values = static_cast<long long>(data.size());
    if (rows < 0 || cols < 0 || rows > values || cols > values || rows * cols != values) {
      throw FileError(name, line, "centres: " + std::to_string(rows) + " rows x " + std::to_string(cols) +
                                      " columns declared, " + std::to_string(values) + " values given");
    }
    if (values > 0 && (!c["dt"] || at(c["dt"]).as<std::string>() != "f")) {
      throw FileError(name, line, "centres: expected dt: f (32-bit floats)");
    }
    cv::Mat centres(static_cast<int>(rows), static_cast<int>(cols), CV_32F);
    float* out = values > 0 ? centres.ptr<float>() : nullptr;
    for (const YAML::Node& v : data) *out++ = static_cast<float>(at(v).as<double>());  // as OpenCV reads them
    auto sequence = [&]<typename T>(const char* key, T) {
      const YAML::Node node = at(doc[key]);
      return node.IsSequence() ? node.as<std::vector<T>>() : std::vector<T>{};
    };
    ChowLiuTree tree;
    tree.parent = sequence("tree_parent", int{});
    tree.p_z = sequence("tree_p_z", double{});
    tree.p_z_given_parent_on = sequence("tree_p_z_given_parent_on", double{});
    tree.p_z_given_parent_off = sequence("tree_p_z_given_parent_off", double{});
    for (std::size_t q = 0; q < tree.parent.size(); ++q) {
      const int p = tree.parent[q];
      if (p < -1 || p >= static_cast<int>(tree.parent.size()) || p == static_cast<int>(q)) {
        throw FileError(name, 0, "tree_parent[" + std::to_string(q) + "] = " + std::to_string(p) +
                                     "; expected -1 or another word's id");
      }
    }
    for (const auto* probabilities : {&tree.p_z, &tree.p_z_given_parent_on, &tree.p_z_given_parent_off}) {
      for (const double p : *probabilities) {
        if (!(p > 0.0 && p < 1.0)) throw FileError(name, 0, "a tree probability outside (0, 1)");
      }
    }
    if (!centres.empty() && !cv::checkRange(centres)) throw FileError(name, 0, "centres hold NaN or infinity");
    return {FeatureTypeFromString(feature), centres, std::move(tree)};
  } catch (const YAML::Exception& e) {
    throw FileError(name, e.mark.line >= 0 ? e.mark.line + 1 : line,
                    "expected a catgraph vocabulary (OpenCV YAML): " + e.msg);
  } catch (const cv::Exception& e) {
    throw FileError(name, 0, "expected a catgraph vocabulary: " + e.msg);
  } catch (const std::invalid_argument& e) {
    throw FileError(name, 0, e.what());
  }
}

}  // namespace catgraph
