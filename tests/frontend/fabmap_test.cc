// FAB-MAP's Chow-Liu tree and observation likelihoods against values worked
// out by hand from the formulas of docs/catgraph-spec.md §2.4.
#include <cmath>
#include <random>
#include <vector>

#include "tests/catch.h"

#include "frontend/fabmap.h"

namespace catgraph {
namespace {

// Four images over two words: {0,1}, {0,1}, {0}, {}.
const std::vector<WordSet> kTraining = {{0, 1}, {0, 1}, {0}, {}};

TEST_CASE("mutual information of two binary words from counts", "[frontend][fabmap]") {
  // p11 = 1/2, p10 = 1/4, p01 = 0, p00 = 1/4; p(a) = 3/4, p(b) = 1/2.
  const double expected = 0.5 * std::log(0.5 / 0.375) + 0.25 * std::log(0.25 / 0.375) +
                          0.25 * std::log(0.25 / 0.125);
  CHECK(MutualInformation(4, 3, 2, 2) == Approx(expected));
  CHECK(MutualInformation(4, 2, 2, 1) == Approx(0.0).margin(1e-15));  // independent
  CHECK(MutualInformation(10, 5, 5, 5) == Approx(std::log(2.0)));    // identical words
}

TEST_CASE("the Chow-Liu tree's probabilities are openFABMAP's smoothed frequencies",
          "[frontend][fabmap]") {
  const ChowLiuTree tree = LearnChowLiuTree(kTraining, 2);
  CHECK(tree.parent == std::vector<int>{-1, 0});
  CHECK(tree.p_z[0] == Approx(0.98 * 0.75 + 0.01));
  CHECK(tree.p_z[1] == Approx(0.98 * 0.5 + 0.01));
  CHECK(tree.p_z_given_parent_on[1] == Approx(0.98 * 2.0 / 3.0 + 0.01));
  CHECK(tree.p_z_given_parent_off[1] == Approx(0.01));  // word 1 never without word 0
  CHECK_THROWS_AS(LearnChowLiuTree({{0, 5}}, 2), std::invalid_argument);
}

TEST_CASE("the tree joins the words that carry most information about each other",
          "[frontend][fabmap]") {
  // Words 1 and 2 always together, word 3 always with word 0, else random.
  std::mt19937_64 rng(3);
  std::vector<WordSet> training;
  for (int i = 0; i < 400; ++i) {
    WordSet w;
    const bool a = rng() % 2, b = rng() % 2;
    if (a) w.insert(w.end(), {0});
    if (b) w.insert(w.end(), {1, 2});
    if (a) w.push_back(3);
    training.push_back(w);
  }
  const ChowLiuTree tree = LearnChowLiuTree(training, 4);
  CHECK(tree.parent[3] == 0);
  CHECK((tree.parent[2] == 1 || tree.parent[1] == 2));
}

TEST_CASE("log p(z | L) matches the hand computation on two words", "[frontend][fabmap]") {
  const FabMapModel model(LearnChowLiuTree(kTraining, 2), FabMapOptions{});
  // z = {0, 1}, L = {0}; p(z=1|e=1) = 0.39, p(z=1|e=0) = 0.
  // Word 0 (root, no parent): L has it, so p(e=1|L) = 1; its term is
  //   β/(α+β) with α = P·0.61·(1-P), β = (1-P)·0.39·P, i.e. 0.39.
  const double word0 = std::log(0.39);
  // Word 1: L lacks it, so p(e=1|L) = 0.61·0.5 / (0.61·0.5 + 1·0.5).
  const double p_e = 0.61 * 0.5 / (0.61 * 0.5 + 0.5);
  const double c = 0.98 * 2.0 / 3.0 + 0.01;  // p(z1=1 | z0=1)
  const double alpha = 0.5 * 0.61 * (1.0 - c), beta = 0.5 * 0.39 * c;
  const double word1 = std::log(p_e * beta / (alpha + beta));  // e = 0 cannot emit z = 1
  CHECK(model.LogLikelihoodDirect({0, 1}, {0}) == Approx(word0 + word1));
  CHECK(model.ForFrame({0, 1}).LogLikelihood({0}) == Approx(word0 + word1));
}

TEST_CASE("naive Bayes ignores the tree: p(z|L) = sum_s p(e=s|L) p(z|e=s)", "[frontend][fabmap]") {
  FabMapOptions options;
  options.naive_bayes = true;
  const FabMapModel model(LearnChowLiuTree(kTraining, 2), options);
  // z = {1}, L = {1}: word 0 absent in both, word 1 present in both.
  const double p0 = 0.745;  // p(z0 = 1)
  const double p_e0 = 0.61 * p0 / (0.61 * p0 + 1.0 * (1.0 - p0));
  const double word0 = std::log(p_e0 * 0.61 + (1.0 - p_e0) * 1.0);
  const double word1 = std::log(1.0 * 0.39);  // L has word 1: it exists for sure
  CHECK(model.LogLikelihoodDirect({1}, {1}) == Approx(word0 + word1));
}

TEST_CASE("the mean-field new place uses the training marginals as generators", "[frontend][fabmap]") {
  FabMapOptions options;
  options.naive_bayes = true;
  const FabMapModel model(LearnChowLiuTree(kTraining, 2), options);
  const double p0 = 0.745, p1 = 0.5;
  // z = {0}: word 0 seen, word 1 not.
  const double expected = std::log(p0 * 0.39 + (1 - p0) * 0.0) + std::log(p1 * 0.61 + (1 - p1) * 1.0);
  CHECK(model.ForFrame({0}).LogNewPlaceLikelihood() == Approx(expected));
}

TEST_CASE("the sampled new place is the log-mean-exp of the likelihoods against the samples",
          "[frontend][fabmap]") {
  const std::vector<WordSet> samples = {{0}, {1}, {0, 1}};
  FabMapOptions options;
  options.new_place = NewPlaceModel::kSampled;
  const FabMapModel model(LearnChowLiuTree(kTraining, 2), options, samples);
  const WordSet z = {1};
  double mean = 0.0;
  for (const WordSet& s : samples) mean += std::exp(model.LogLikelihoodDirect(z, s)) / 3.0;
  CHECK(model.ForFrame(z).LogNewPlaceLikelihood() == Approx(std::log(mean)));
  CHECK_THROWS_AS(FabMapModel(LearnChowLiuTree(kTraining, 2), options), std::invalid_argument);  // no samples
}

TEST_CASE("the per-frame tables give the direct likelihood for any node", "[frontend][fabmap]") {
  std::mt19937_64 rng(7);
  const int v = 40;
  auto random_words = [&](double p) {
    WordSet w;
    for (int q = 0; q < v; ++q) {
      if (std::uniform_real_distribution<double>(0, 1)(rng) < p) w.push_back(q);
    }
    return w;
  };
  std::vector<WordSet> training;
  for (int i = 0; i < 200; ++i) training.push_back(random_words(0.2));
  for (const bool naive : {false, true}) {
    FabMapOptions options;
    options.naive_bayes = naive;
    options.p_observe_given_absent = naive ? 0.0 : 0.01;
    const FabMapModel model(LearnChowLiuTree(training, v), options);
    for (int trial = 0; trial < 20; ++trial) {
      const WordSet z = random_words(0.2), location = random_words(0.2);
      const FrameLikelihood frame = model.ForFrame(z);
      CHECK(frame.LogLikelihood(location) == Approx(model.LogLikelihoodDirect(z, location)).epsilon(1e-12));
      // The place that saw exactly these words explains them best.
      CHECK(frame.LogLikelihood(z) > frame.LogLikelihood(location));
    }
  }
}

TEST_CASE("FAB-MAP options out of range are refused", "[frontend][fabmap]") {
  const ChowLiuTree tree = LearnChowLiuTree(kTraining, 2);
  CHECK_THROWS_AS(FabMapModel(tree, FabMapOptions{0.0, 0.0, false}), std::invalid_argument);
  CHECK_THROWS_AS(FabMapModel(tree, FabMapOptions{0.39, 1.0, false}), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph
