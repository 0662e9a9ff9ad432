// The visual vocabulary on simulated office frames: training, quantisation,
// the file round trip, and FAB-MAP recognising places across traversals.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <vector>

#include <opencv2/features2d.hpp>

#include "tests/catch.h"

#include "backend/io/file_error.h"
#include "frontend/vocabulary.h"
#include "simulation/office_simulator.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

struct OfficeFrames {
  std::vector<PlannedFrame> frames;
  std::vector<cv::Mat> images;
};

// Every `step`-th frame of office-static, rendered.
const OfficeFrames& Office(std::size_t step) {
  static std::map<std::size_t, OfficeFrames> cache;
  auto [it, inserted] = cache.try_emplace(step);
  if (inserted) {
    const Scenario scenario = LoadScenario("office-static");
    const OfficeWorld world = MakeWorld(scenario);
    const auto all = PlanFrames(DriveScenario(scenario, 1), scenario.camera.frame_rate_hz, 0);
    for (std::size_t i = 0; i < all.size(); i += step) {
      it->second.frames.push_back(all[i]);
      it->second.images.push_back(world.Render(all[i].T_world_camera, all[i].traversal, FrameNoiseSeed(1, i)));
    }
  }
  return it->second;
}

std::vector<cv::Mat> TraversalImages(const OfficeFrames& office, int traversal) {
  std::vector<cv::Mat> images;
  for (std::size_t i = 0; i < office.frames.size(); ++i) {
    if (office.frames[i].traversal == traversal) images.push_back(office.images[i]);
  }
  return images;
}

TEST_CASE("a descriptor equal to a word centre quantises to that word", "[frontend][vocabulary]") {
  cv::Mat centres(5, 3, CV_32F);
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 3; ++c) centres.at<float>(r, c) = static_cast<float>(10 * r + c);
  }
  CHECK(QuantizeDescriptors(centres, centres.rowRange(3, 5)) == WordSet{3, 4});
  cv::Mat near = centres.row(1) + 0.4f;
  near.push_back(cv::Mat(centres.row(1) - 0.2f));
  CHECK(QuantizeDescriptors(centres, near) == WordSet{1});
  CHECK_THROWS_AS(QuantizeDescriptors(centres, cv::Mat::zeros(1, 4, CV_32F)), std::invalid_argument);
}

// The words BFMatcher gives: each descriptor's nearest centre, the lowest
// index on a tie.
WordSet BruteForceWords(const cv::Mat& centres, const cv::Mat& descriptors) {
  std::vector<cv::DMatch> matches;
  cv::BFMatcher(cv::NORM_L2).match(descriptors, centres, matches);
  WordSet words;
  for (const cv::DMatch& m : matches) words.push_back(m.trainIdx);
  std::sort(words.begin(), words.end());
  words.erase(std::unique(words.begin(), words.end()), words.end());
  return words;
}

TEST_CASE("quantisation gives BFMatcher's words, near ties included", "[frontend][vocabulary]") {
  // SIFT descriptors of office frames against centres that are descriptors
  // of other frames: distances of real magnitude, many near ties.
  const auto& office = Office(40);
  cv::Mat pool;
  for (const cv::Mat& image : office.images) pool.push_back(ComputeDescriptors(FeatureType::kSift, image));
  REQUIRE(pool.rows > 600);
  const cv::Mat centres = pool.rowRange(0, 300).clone();
  int frames = 0;
  for (int start = 300; start + 40 <= pool.rows; start += 40, ++frames) {
    const cv::Mat descriptors = pool.rowRange(start, start + 40);
    CHECK(QuantizeDescriptors(centres, descriptors) == BruteForceWords(centres, descriptors));
  }
  CHECK(frames > 5);

  // Exact ties (a centre listed twice) go to the lower index, as BFMatcher's.
  cv::Mat doubled = centres.rowRange(0, 10).clone();
  doubled.push_back(centres.row(3));
  CHECK(QuantizeDescriptors(doubled, centres.row(3)) == WordSet{3});
  CHECK(BruteForceWords(doubled, centres.row(3)) == WordSet{3});
  // Two centres a rounding apart, in the order that makes the product's
  // ranking and the exact distance disagree for some descriptors.
  cv::Mat close = centres.rowRange(0, 2).clone();
  close.row(1) = close.row(0) + 1e-3f;
  cv::Mat between = 0.5 * (close.row(0) + close.row(1));
  for (int k = 0; k < 20; ++k) {
    between.at<float>(0, k) += (k % 2 ? 1e-4f : -1e-4f);
    CHECK(QuantizeDescriptors(close, between) == BruteForceWords(close, between));
  }

  cv::Mat strided = cv::Mat::zeros(3, 2 * centres.cols, CV_32F);
  centres.rowRange(0, 3).copyTo(strided.colRange(0, centres.cols));
  CHECK(QuantizeDescriptors(centres, strided.colRange(0, centres.cols)) == WordSet{0, 1, 2});
  CHECK_THROWS_AS(QuantizeDescriptors(centres, cv::Mat::zeros(1, centres.cols, CV_64F)), std::invalid_argument);
}

TEST_CASE("a vocabulary trains deterministically and survives its file", "[frontend][vocabulary]") {
  const auto images = TraversalImages(Office(40), 1);
  VocabularyOptions options;
  options.words = 64;
  options.seed = 5;
  const Vocabulary a = TrainVocabulary(images, options);
  const Vocabulary b = TrainVocabulary(images, options);
  REQUIRE(a.size() == 64);
  CHECK(a.centres().cols == 128);  // SIFT
  CHECK(cv::norm(a.centres(), b.centres(), cv::NORM_INF) == 0.0);
  CHECK(a.tree().parent == b.tree().parent);
  CHECK(std::count(a.tree().parent.begin(), a.tree().parent.end(), -1) == 1);

  const auto dir = testing::TempDir("vocabulary");
  a.Save(dir / "vocab.yml");
  const Vocabulary loaded = Vocabulary::Load(dir / "vocab.yml");
  CHECK(loaded.feature() == FeatureType::kSift);
  CHECK(cv::norm(a.centres(), loaded.centres(), cv::NORM_INF) < 1e-3);
  // Read with yaml-cpp, the same numbers OpenCV's own reader gets.
  cv::FileStorage fs((dir / "vocab.yml").string(), cv::FileStorage::READ);
  cv::Mat opencv_centres;
  fs["centres"] >> opencv_centres;
  CHECK(cv::norm(opencv_centres, loaded.centres(), cv::NORM_INF) == 0.0);
  CHECK(loaded.tree().parent == a.tree().parent);
  for (std::size_t q = 0; q < 64; ++q) CHECK(loaded.tree().p_z[q] == Approx(a.tree().p_z[q]));
  CHECK(loaded.Words(images[3]) == a.Words(images[3]));
  CHECK(a.Words(images[3]).size() >= 20);
  std::filesystem::remove_all(dir);
}

TEST_CASE("a broken vocabulary file is an error naming it", "[frontend][vocabulary][bad-input]") {
  const auto dir = testing::TempDir("vocabulary_bad");
  std::ofstream(dir / "garbage.yml") << "%YAML:1.0\n---\nformat_version: 1\nfeature: sift\ncentres: [1, 2\n";
  CHECK_THROWS_AS(Vocabulary::Load(dir / "garbage.yml"), FileError);
  std::ofstream(dir / "version.yml") << "%YAML:1.0\n---\nformat_version: 7\n";
  try {
    Vocabulary::Load(dir / "version.yml");
    FAIL("no error");
  } catch (const FileError& e) {
    CHECK_THAT(e.what(), Catch::Contains("version.yml:3: format_version 7; expected 1"));
  }
  CHECK_THROWS_AS(Vocabulary::Load(dir / "missing.yml"), FileError);
  std::filesystem::remove_all(dir);
}

TEST_CASE("FAB-MAP with a trained vocabulary recognises office places across traversals",
          "[frontend][vocabulary][fabmap][slow]") {
  const OfficeFrames& office = Office(8);
  VocabularyOptions options;
  options.words = 300;
  const Vocabulary vocabulary = TrainVocabulary(TraversalImages(office, 1), options);
  const FabMapModel model(vocabulary.tree(), FabMapOptions{});
  // Map: traversal-1 frames about 3 m apart; queries: the traversal-2 frame
  // nearest to each map frame.
  std::vector<std::size_t> map;
  for (std::size_t i = 0; i < office.frames.size(); ++i) {
    if (office.frames[i].traversal != 1) continue;
    if (map.empty() || (office.frames[i].T_world_camera.translation() -
                        office.frames[map.back()].T_world_camera.translation()).norm() > 3.0) {
      map.push_back(i);
    }
  }
  std::vector<WordSet> map_words;
  for (const std::size_t i : map) map_words.push_back(vocabulary.Words(office.images[i]));
  int correct = 0, queries = 0;
  for (std::size_t m = 0; m < map.size(); ++m) {
    const Pose2& place = office.frames[map[m]].T_world_camera;
    std::size_t query = 0;
    double best = 1e9;
    for (std::size_t i = 0; i < office.frames.size(); ++i) {
      if (office.frames[i].traversal != 2) continue;
      const Pose2& p = office.frames[i].T_world_camera;
      if (std::abs(WrapAngle(p.theta() - place.theta())) > 0.3) continue;
      const double d = (p.translation() - place.translation()).norm();
      if (d < best) best = d, query = i;
    }
    if (best > 0.5) continue;
    const FrameLikelihood frame = model.ForFrame(vocabulary.Words(office.images[query]));
    std::size_t argmax = 0;
    for (std::size_t k = 1; k < map.size(); ++k) {
      if (frame.LogLikelihood(map_words[k]) > frame.LogLikelihood(map_words[argmax])) argmax = k;
    }
    ++queries;
    correct += argmax == m;
  }
  INFO(correct << " of " << queries << " places recognised");
  REQUIRE(queries >= 20);
  CHECK(correct >= 0.8 * queries);
}

}  // namespace
}  // namespace catgraph
