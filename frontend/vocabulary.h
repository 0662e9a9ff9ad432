// The visual vocabulary: local features (SIFT by default; ORB, AKAZE, KAZE
// selectable), clustered by k-means into words, each image reduced to the set
// of words present in it (FAB-MAP's binary observation), and the Chow-Liu tree
// of those words learned from the same training images.
//
// One file holds all of it (OpenCV YAML, `format_version` 1): the feature
// type, the word centres and the tree, so that a vocabulary trained once is
// all a localisation run needs. Binary descriptors (ORB, AKAZE) are clustered
// as vectors of byte values under the L2 norm — the usual approximation when
// k-means is used for them.
//
// Deterministic for a seed (OpenCV's k-means++ seeded from it). Thread-
// compatible: a Vocabulary is immutable after construction; Words() may be
// called from several threads.
#ifndef CATGRAPH_FRONTEND_VOCABULARY_H_
#define CATGRAPH_FRONTEND_VOCABULARY_H_

#include <cstdint>
#include <filesystem>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "backend/io/image_file.h"  // ReadImage, for the images a vocabulary is trained on
#include "frontend/fabmap.h"

namespace catgraph {

enum class FeatureType { kSift, kOrb, kAkaze, kKaze };

std::string_view ToString(FeatureType type);
// Throws std::invalid_argument listing the names.
FeatureType FeatureTypeFromString(std::string_view text);

struct VocabularyOptions {
  FeatureType feature = FeatureType::kSift;
  int words = 1000;                        // k of k-means; >= 2
  int kmeans_iterations = 30;              // >= 1
  int kmeans_attempts = 1;                 // restarts, best compactness kept; >= 1
  std::size_t max_descriptors = 200000;    // a random subset beyond this is clustered; >= words
  std::uint64_t seed = 1;
};
// Throws std::invalid_argument naming the first field out of range.
void Validate(const VocabularyOptions& options);

// Descriptors of an image (colour or grey; detected on grey), one CV_32F row
// each (binary descriptors as byte values).
cv::Mat ComputeDescriptors(FeatureType feature, const cv::Mat& image);

// The words present among `descriptors`: each descriptor's nearest centre
// (L2), sorted and unique. Throws std::invalid_argument on a size mismatch.
WordSet QuantizeDescriptors(const cv::Mat& centres, const cv::Mat& descriptors);

class Vocabulary {
 public:
  // `centres`: one CV_32F row per word. Throws std::invalid_argument when
  // the tree's size disagrees with the centres.
  Vocabulary(FeatureType feature, cv::Mat centres, ChowLiuTree tree);

  FeatureType feature() const { return feature_; }
  int size() const { return centres_.rows; }
  const cv::Mat& centres() const { return centres_; }
  const ChowLiuTree& tree() const { return tree_; }

  cv::Mat Descriptors(const cv::Mat& image) const { return ComputeDescriptors(feature_, image); }
  WordSet Quantize(const cv::Mat& descriptors) const { return QuantizeDescriptors(centres_, descriptors); }
  WordSet Words(const cv::Mat& image) const { return Quantize(Descriptors(image)); }

  // Writes the file atomically; throws FileError.
  void Save(const std::filesystem::path& path) const;
  // Throws FileError naming the file and what was expected.
  static Vocabulary Load(const std::filesystem::path& path);

 private:
  FeatureType feature_;
  cv::Mat centres_;
  ChowLiuTree tree_;
};

// Clusters the descriptors of `images` into options.words words and learns
// the Chow-Liu tree of the images' word sets. Throws std::invalid_argument
// when the images have fewer descriptors than words.
Vocabulary TrainVocabulary(const std::vector<cv::Mat>& images, const VocabularyOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_VOCABULARY_H_
