// MeasureEvidence and SeparationAt on a corridor whose answers are known.
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "tests/catch.h"

#include "experiments/evidence.h"

namespace catgraph {
namespace {

// A straight 30 m corridor, one frame every 0.1 m, driven twice east and
// once west; each 0.5 m has its own 4 words, seen with 80 % chance each: no
// place looks like another.
struct Corridor {
  static constexpr double kLength = 30.0, kStep = 0.1;
  std::vector<WordSet> words;
  std::vector<Pose2> truth;
  std::vector<int> first, second, reverse;
  // FAB-MAP trained on the first pass.
  FabMapModel Model() const {
    std::vector<WordSet> training;
    for (const int f : first) training.push_back(words[static_cast<std::size_t>(f)]);
    return FabMapModel(LearnChowLiuTree(training, 4 * static_cast<int>(kLength / 0.5)), FabMapOptions{});
  }
};

Corridor MakeCorridor() {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto observe = [&](double x) {
    WordSet w;
    const int bin = static_cast<int>(x / 0.5);
    for (int k = 0; k < 4; ++k) {
      if (unit(rng) < 0.8) w.push_back(4 * bin + k);
    }
    return w;
  };
  Corridor c;
  const int frames = static_cast<int>(Corridor::kLength / Corridor::kStep);
  for (int pass = 0; pass < 3; ++pass) {
    for (int k = 0; k < frames; ++k) {
      const double x = pass == 2 ? Corridor::kLength - 0.05 - k * Corridor::kStep : 0.05 + k * Corridor::kStep;
      (pass == 0 ? c.first : pass == 1 ? c.second : c.reverse).push_back(static_cast<int>(c.words.size()));
      c.words.push_back(observe(x));
      c.truth.emplace_back(x, pass == 1 ? 0.15 : 0.0, pass == 2 ? std::numbers::pi : 0.0);
    }
  }
  return c;
}

TEST_CASE("evidence: the true place explains a revisit, the places metres away do not", "[experiments][evidence]") {
  const Corridor c = MakeCorridor();
  const FabMapModel model = c.Model();
  const std::vector<FrameEvidence> e = MeasureEvidence(model, c.words, c.truth, {}, c.first, c.second);
  REQUIRE(e.size() == c.second.size());
  int with_words = 0, true_beats_near = 0;
  for (std::size_t i = 0; i < e.size(); ++i) {
    CAPTURE(e[i].frame);
    CHECK(e[i].frame == c.second[i]);
    CHECK(e[i].words == c.words[static_cast<std::size_t>(e[i].frame)].size());
    CHECK_FALSE(e[i].changed);
    REQUIRE_FALSE(std::isnan(e[i].true_place));  // map frames every 0.1 m: one is within 0.5 m
    REQUIRE_FALSE(std::isnan(e[i].near));         // the corridor is 30 m: some place is 2-10 m away
    if (e[i].words == 0) continue;
    ++with_words;
    // A frame explained by a node with exactly its words beats the mean field.
    CHECK(e[i].self > 0.0);
    true_beats_near += e[i].true_place > e[i].near ? 1 : 0;
  }
  CHECK(true_beats_near >= 0.95 * with_words);
  CHECK_FALSE(std::isnan(e.front().far));  // at 0.05 m, the map runs on to 29.95 m

  // Driven the other way, a forward camera sees other things: no map frame
  // qualifies within 45 degrees of its heading.
  for (const FrameEvidence& r : MeasureEvidence(model, c.words, c.truth, {}, c.first, c.reverse)) {
    CHECK(std::isnan(r.true_place));
    CHECK(std::isnan(r.near));
    CHECK(std::isnan(r.far));
  }
}

TEST_CASE("evidence: the separation counts frames over constant + relative x self", "[experiments][evidence]") {
  std::vector<FrameEvidence> e(4);
  // self, true, near: offsets 10 + 0.1 self = 20, 15, 12, -
  e[0].self = 100, e[0].true_place = 30, e[0].near = 25;  // both over 20
  e[1].self = 50, e[1].true_place = 16, e[1].near = 14;   // true over 15, near not
  e[2].self = 20, e[2].true_place = 11;                   // neither (near NaN)
  e[3].self = 80;                                         // no true place: not counted
  const OffsetSeparation s = SeparationAt(e, 10.0, 0.1);
  CHECK(s.frames == 3);
  CHECK(s.true_over == Approx(2.0 / 3.0));
  CHECK(s.near_over == Approx(1.0 / 3.0));
  CHECK(SeparationAt({}, 0.0, 0.0).frames == 0);
}

TEST_CASE("evidence: mismatched inputs and bad options are refused", "[experiments][evidence]") {
  const Corridor c = MakeCorridor();
  const FabMapModel model = c.Model();
  std::vector<Pose2> short_truth(c.truth.begin(), c.truth.end() - 1);
  CHECK_THROWS_AS(MeasureEvidence(model, c.words, short_truth, {}, c.first, c.second), std::invalid_argument);
  CHECK_THROWS_AS(MeasureEvidence(model, c.words, c.truth, {true}, c.first, c.second), std::invalid_argument);
  CHECK_THROWS_WITH(MeasureEvidence(model, c.words, c.truth, {}, c.first, {static_cast<int>(c.words.size())}),
                    Catch::Contains("out of range"));
  EvidenceOptions bad;
  bad.near_min_m = 0.2;  // inside the true radius
  CHECK_THROWS_AS(MeasureEvidence(model, c.words, c.truth, {}, c.first, c.second, bad), std::invalid_argument);
}

}  // namespace
}  // namespace catgraph
