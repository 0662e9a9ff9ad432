// The SAD template matcher (docs/catgraph-spec.md §8) against values worked
// out by hand.
#include <cmath>
#include <vector>

#include "tests/catch.h"

#include <opencv2/core.hpp>

#include "frontend/sad_matcher.h"

namespace catgraph {
namespace {

cv::Mat Ramp(int width, int height, int offset) {
  cv::Mat m(height, width, CV_32F);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) m.at<float>(y, x) = static_cast<float>(((x + offset) % width) * 0.05 + y * 0.01);
  }
  return m;
}

TEST_CASE("SAD: identical templates differ by 0, a constant offset by that constant", "[frontend][sad]") {
  const cv::Mat a = Ramp(16, 8, 0);
  CHECK(CompareTemplates(a, a, 2).difference == Approx(0.0).margin(1e-12));
  CHECK(CompareTemplates(a, a, 2).shift_px == 0);
  const cv::Mat b = a + 0.1;
  CHECK(CompareTemplates(b, a, 0).difference == Approx(0.1));
}

TEST_CASE("SAD: a sideways shift is found and only the overlap counts", "[frontend][sad]") {
  // The query is the reference moved one column left: query column c shows
  // reference column c + 1, which the matcher finds at shift +1 with no
  // difference over the 15 overlapping columns.
  cv::Mat reference(8, 16, CV_32F), query(8, 16, CV_32F, cv::Scalar(0.9f));
  cv::randu(reference, 0.0, 1.0);
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x + 1 < 16; ++x) query.at<float>(y, x) = reference.at<float>(y, x + 1);
  }
  const SadComparison c = CompareTemplates(query, reference, 2);
  CHECK(c.shift_px == 1);
  CHECK(c.difference == Approx(0.0).margin(1e-7));
  CHECK(CompareTemplates(query, reference, 0).difference > 0.1);  // without shifts it does not match
  CHECK_THROWS_AS(CompareTemplates(query, cv::Mat(8, 15, CV_32F), 2), std::invalid_argument);
}

TEST_CASE("SAD templates: area-averaged grey in [0, 1], normalised flat patches are 0.5", "[frontend][sad]") {
  cv::Mat image(80, 160, CV_8UC3, cv::Scalar(51, 51, 51));
  image(cv::Rect(0, 0, 80, 80)).setTo(cv::Scalar(255, 255, 255));
  SadOptions o;
  const cv::Mat t = SadTemplate(image, o);
  REQUIRE(t.size() == cv::Size(16, 8));
  CHECK(t.at<float>(3, 2) == Approx(1.0));
  CHECK(t.at<float>(3, 12) == Approx(0.2));
  o.normalization = SadNormalization::kPatch;
  const cv::Mat n = SadTemplate(image, o);
  CHECK(n.at<float>(0, 0) == Approx(0.5));    // a flat 4 x 4 patch
  CHECK(n.at<float>(0, 12) == Approx(0.5));
  CHECK_THROWS_AS(SadNormalizationFromString("zscore"), std::invalid_argument);
}

TEST_CASE("SAD: the best threshold is the largest that accepts no false match", "[frontend][sad]") {
  std::vector<SadMatch> m(4);
  m[0].comparison.difference = 0.10, m[0].error_m = 0.2;
  m[1].comparison.difference = 0.20, m[1].error_m = 0.5;
  m[2].comparison.difference = 0.30, m[2].error_m = 5.0;  // false
  m[3].comparison.difference = 0.40, m[3].error_m = 0.1;
  const double best = BestThreshold(m, 1.0);
  CHECK(best < 0.30);
  CHECK(best > 0.2999);
  m[2].error_m = 0.3;  // nothing false: every match is accepted
  CHECK(BestThreshold(m, 1.0) == 0.40);
  const auto sweep = SweepThreshold(m, 1.0, 4);
  REQUIRE(sweep.size() == 4);
  CHECK(sweep.back().accepted == 4);
  CHECK(sweep.front().accepted == 1);
}

}  // namespace
}  // namespace catgraph
