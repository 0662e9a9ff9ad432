// The holistic observation model: its log-likelihood ratio against the
// integral it stands for, its templates and differences, the calibration on a
// sequence's own frames, and localisation on the real corridor.
#include "frontend/holistic.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <random>
#include <vector>

#include "tests/catch.h"
#include <opencv2/imgproc.hpp>

#include "backend/io/dataset.h"
#include "frontend/localization.h"
#include "simulation/vprbench_import.h"

namespace catgraph {
namespace {

// log (1/M) ∫_0^M exp(μ s - μ²/2) dμ by Simpson's rule.
double LogRatioByQuadrature(double s, double m) {
  const int n = 20000;
  const double h = m / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double mu = i * h;
    const double weight = i == 0 || i == n ? 1.0 : i % 2 == 1 ? 4.0 : 2.0;
    sum += weight * std::exp(mu * s - 0.5 * mu * mu);
  }
  return std::log(sum * h / 3.0 / m);
}

// A grey strip of smooth random texture (blobs of about 32 px), seeded: the
// world a camera moving sideways along it sees a window of.
cv::Mat Strip(int width, int height, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> unit(0.0f, 255.0f);
  cv::Mat coarse(std::max(2, height / 32), std::max(2, width / 32), CV_32F);
  for (int y = 0; y < coarse.rows; ++y) {
    for (int x = 0; x < coarse.cols; ++x) coarse.at<float>(y, x) = unit(rng);
  }
  cv::Mat strip;
  cv::resize(coarse, strip, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  return strip;
}

HolisticModel Model(double m = 3.0) { return HolisticModel(HolisticOptions{}, HolisticCalibration{m, 0, 0.0}); }

}  // namespace

TEST_CASE("the holistic log-likelihood ratio is the integral over a uniform shift", "[frontend][holistic]") {
  for (const double m : {0.5, 1.0, 2.6, 4.0}) {
    for (const double s : {-8.0, -3.0, -1.0, 0.0, 0.7, 1.4, 2.6, 4.0, 9.0}) {
      CHECK(HolisticLogLikelihoodRatio(s, m) == Approx(LogRatioByQuadrature(s, m)).margin(1e-6));
    }
  }
}

TEST_CASE("the holistic log-likelihood ratio rises with the score and falls only slowly below it",
          "[frontend][holistic]") {
  const double m = 2.6;
  double previous = -std::numeric_limits<double>::infinity();
  for (double s = -20.0; s <= 30.0; s += 0.25) {
    const double llr = HolisticLogLikelihoodRatio(s, m);
    REQUIRE(std::isfinite(llr));
    CHECK(llr > previous);
    previous = llr;
  }
  // A frame that looks like nothing costs about log(M |s|), not s²/2.
  CHECK(HolisticLogLikelihoodRatio(-10.0, m) > -std::log(m * 10.0) - 0.5);
  // The median place (s = 0) scores below new place (the mean over places).
  CHECK(HolisticLogLikelihoodRatio(0.0, m) < 0.0);
  CHECK(HolisticLogLikelihoodRatio(m, m) > 0.0);
}

TEST_CASE("holistic templates ignore exposure and keep the aspect ratio", "[frontend][holistic]") {
  const HolisticModel model = Model();
  const cv::Mat image = Strip(320, 120, 3);
  const cv::Mat brighter = image * 1.7 + 20.0;
  const cv::Mat a = model.Template(image), b = model.Template(brighter);
  CHECK(a.cols == 32);
  CHECK(a.rows == 12);
  CHECK(cv::norm(a, b, cv::NORM_INF) < 1e-4);
  cv::Scalar mean, deviation;
  cv::meanStdDev(a, mean, deviation);
  CHECK(mean[0] == Approx(0.0).margin(1e-5));
  CHECK(deviation[0] == Approx(1.0).margin(1e-4));
  CHECK(cv::countNonZero(model.Template(cv::Mat(40, 40, CV_8U, cv::Scalar(7)))) == 0);
  CHECK_THROWS_AS(model.Template(cv::Mat()), std::invalid_argument);
}

TEST_CASE("the holistic difference finds a sideways shift within its range", "[frontend][holistic]") {
  const HolisticModel model = Model();  // shifts up to 8 of 32 columns
  const cv::Mat strip = Strip(640, 96, 5);
  // Windows 60 px apart in the strip are 6 template columns apart.
  const cv::Mat a = model.Template(strip(cv::Rect(0, 0, 320, 96)));
  const cv::Mat shifted = model.Template(strip(cv::Rect(60, 0, 320, 96)));
  const cv::Mat elsewhere = model.Template(Strip(320, 96, 6));
  CHECK(model.Difference(a, a) == 0.0);
  CHECK(model.Difference(a, shifted) < 0.5 * model.Difference(a, elsewhere));
  CHECK_THROWS_AS(model.Difference(a, model.Template(Strip(320, 320, 1))), std::invalid_argument);
}

TEST_CASE("a holistic frame scores its own place highest and is silent without places to compare",
          "[frontend][holistic]") {
  const HolisticModel model = Model(2.0);
  std::vector<Observation> places;
  for (int i = 0; i < 40; ++i) places.push_back({{}, model.Template(Strip(256, 96, 100 + i))});
  std::vector<const Observation*> sample;
  for (const Observation& p : places) sample.push_back(&p);
  const Observation& z = places[17];
  const auto score = model.ScoreFrame(z, sample);
  double best = -1e9;
  int argmax = -1;
  for (int i = 0; i < 40; ++i) {
    const double llr = score->LogLikelihood(places[static_cast<std::size_t>(i)]);
    if (llr > best) best = llr, argmax = i;
  }
  CHECK(argmax == 17);
  CHECK(score->LogNewPlaceLikelihood() == 0.0);
  CHECK(score->LogUnseenPlaceLikelihood() == Approx(HolisticLogLikelihoodRatio(0.0, 2.0)));
  CHECK(score->SelfEvidence() == Approx(HolisticLogLikelihoodRatio(2.0, 2.0)));
  // Seven places are too few to standardise against: every place scores as new place.
  const std::vector<const Observation*> few(sample.begin(), sample.begin() + 7);
  CHECK(model.ScoreFrame(z, few)->LogLikelihood(places[17]) == 0.0);
}

TEST_CASE("the holistic calibration reads how alike neighbours look off the sequence itself",
          "[frontend][holistic]") {
  const HolisticModel model = Model();
  // A camera sliding along one textured strip: neighbours 1 m apart share
  // most of their view.
  const cv::Mat world = Strip(8000, 96, 11);
  std::vector<cv::Mat> sliding, unrelated;
  std::vector<double> path;
  for (int i = 0; i < 150; ++i) {
    path.push_back(0.25 * i);                             // 4 frames a metre ...
    sliding.push_back(model.Template(world(cv::Rect(10 * i, 0, 320, 96))));  // ... a template column a frame
    unrelated.push_back(model.Template(Strip(320, 96, 1000 + static_cast<std::uint64_t>(i))));
  }
  const HolisticCalibration c = CalibrateHolistic(model, sliding, path, 1.0, 5.0);
  CHECK(c.identical_score > 2.0);
  CHECK(c.frames > 100);
  CHECK(c.offset_m == 1.0);
  // Frames that have nothing in common: no score above chance, the floor.
  CHECK(CalibrateHolistic(model, unrelated, path, 1.0, 5.0).identical_score == 0.5);
  // Too short to have places beyond the exclusion distance.
  const std::vector<cv::Mat> few(sliding.begin(), sliding.begin() + 10);
  const std::vector<double> few_path(path.begin(), path.begin() + 10);
  CHECK_THROWS_AS(CalibrateHolistic(model, few, few_path, 1.0, 5.0), std::invalid_argument);
  CHECK_THROWS_AS(CalibrateHolistic(model, sliding, few_path, 1.0, 5.0), std::invalid_argument);
}

TEST_CASE("holistic options and calibrations out of range are refused", "[frontend][holistic]") {
  HolisticOptions bad;
  bad.width_px = 2;
  CHECK_THROWS_WITH(Validate(bad), Catch::Contains("width_px"));
  bad = {};
  bad.max_shift_fraction = 0.5;
  CHECK_THROWS_WITH(Validate(bad), Catch::Contains("max_shift_fraction"));
  bad = {};
  bad.reference_places = 7;
  CHECK_THROWS_WITH(Validate(bad), Catch::Contains("reference_places"));
  CHECK_THROWS_AS(HolisticModel({}, HolisticCalibration{0.0, 0, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS(HolisticModel({}, HolisticCalibration{std::nan(""), 0, 0.0}), std::invalid_argument);
}

// The real corridor (../shared), converted with its made-up odometry: the
// holistic model closes only at the true place (the set's own tolerance:
// ±2 frames, 1.0 m), and CAT-Graph+ infers where it does not close.
TEST_CASE("on the real corridor the holistic front end closes and infers only at the true place",
          "[frontend][holistic][shared]") {
  const auto source = std::filesystem::path(CATGRAPH_SHARED_DATASETS) / "images" / "corridor_vprbench";
  if (!std::filesystem::exists(source)) {
    WARN("skipped: the corridor set is not at " << source.string() << " (set -DCATGRAPH_SHARED_DATASETS=...)");
    return;
  }
  const auto dir = std::filesystem::temp_directory_path() / "catgraph-holistic-corridor";
  std::filesystem::remove_all(dir);
  ImportVprBench(source, dir, {});
  const Dataset d = ReadDataset(dir);
  LocalizationOptions options;
  options.threads = 1;
  const HolisticFrontEnd front = PrepareHolistic(d, HolisticOptions{}, options);
  // Neighbours 1 m apart on the reference traversal score well above chance.
  CHECK(front.model->calibration().identical_score > 1.5);
  const LocalizationResult r = Localize(d, front.observations, *front.model, options);
  int visual = 0, inferred = 0;
  for (const LoopClosure& c : r.closures) {
    CHECK(c.error_m <= 1.0);
    (c.kind == ClosureKind::kVisual ? visual : inferred) += 1;
  }
  // Measured: 27 visual and 81 inferred of the 111 query frames.
  CHECK(visual >= 20);
  CHECK(visual + inferred >= 90);
  std::filesystem::remove_all(dir);
}

}  // namespace catgraph
