#include "frontend/holistic.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "frontend/sad_matcher.h"

namespace catgraph {
namespace {

// Φ(a) - Φ(b) for a >= b, from the tails that keep it accurate.
double NormalMass(double a, double b) {
  const double r = 1.0 / std::numbers::sqrt2;
  if (b >= 0.0) return 0.5 * (std::erfc(b * r) - std::erfc(a * r));
  if (a <= 0.0) return 0.5 * (std::erfc(-a * r) - std::erfc(-b * r));
  return 1.0 - 0.5 * std::erfc(a * r) - 0.5 * std::erfc(-b * r);
}

struct MeanAndDeviation {
  double mean = 0.0, deviation = 0.0;
};

MeanAndDeviation Moments(const std::vector<double>& values) {
  MeanAndDeviation m;
  if (values.empty()) return m;
  for (const double v : values) m.mean += v;
  m.mean /= static_cast<double>(values.size());
  double ss = 0.0;
  for (const double v : values) ss += (v - m.mean) * (v - m.mean);
  m.deviation = std::sqrt(ss / static_cast<double>(values.size()));
  return m;
}

// Fewer places than this give no usable standardisation: the frame scores
// every place alike (LLR 0, as new place).
constexpr int kMinPlaces = 8;

class HolisticFrameScore : public FrameScore {
 public:
  HolisticFrameScore(const HolisticModel& model, const cv::Mat& frame, MeanAndDeviation reference)
      : model_(model), frame_(frame), reference_(reference) {}

  double LogLikelihood(const Observation& node) const override {
    if (!(reference_.deviation > 0.0) || node.holistic.empty()) return 0.0;
    const double s = (reference_.mean - model_.Difference(frame_, node.holistic)) / reference_.deviation;
    return HolisticLogLikelihoodRatio(s, model_.calibration().identical_score);
  }
  double LogNewPlaceLikelihood() const override { return 0.0; }
  // The median place: s = 0. New place is the mean over places, LLR 0, which
  // one unremarkable place scores less than.
  double LogUnseenPlaceLikelihood() const override {
    return reference_.deviation > 0.0 ? HolisticLogLikelihoodRatio(0.0, model_.calibration().identical_score) : 0.0;
  }
  double SelfEvidence() const override {
    const double m = model_.calibration().identical_score;
    return HolisticLogLikelihoodRatio(m, m);
  }

 private:
  const HolisticModel& model_;
  cv::Mat frame_;
  MeanAndDeviation reference_;
};

}  // namespace

void Validate(const HolisticOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("HolisticOptions: " + what); };
  if (o.width_px < 4 || o.width_px > 1024) fail("width_px must be in [4, 1024]");
  if (!(o.max_shift_fraction >= 0.0 && o.max_shift_fraction < 0.5)) fail("max_shift_fraction must be in [0, 0.5)");
  if (o.reference_places < kMinPlaces || o.reference_places > 100000) {
    fail("reference_places must be in [8, 100000]");
  }
}

double HolisticLogLikelihoodRatio(double score, double identical_score) {
  const double m = identical_score;
  // Beyond these the ratio is flat or linear to well under a nat per unit of
  // s, and erfc would underflow.
  const double s = std::clamp(score, -30.0, m + 30.0);
  return 0.5 * s * s + std::log(std::sqrt(2.0 * std::numbers::pi) / m) + std::log(NormalMass(m - s, -s));
}

HolisticModel::HolisticModel(HolisticOptions options, HolisticCalibration calibration)
    : options_(options), calibration_(calibration) {
  Validate(options_);
  if (!(calibration_.identical_score > 0.0 && std::isfinite(calibration_.identical_score))) {
    throw std::invalid_argument("HolisticModel: the calibration's identical_score must be finite and > 0, not " +
                                std::to_string(calibration_.identical_score));
  }
}

cv::Mat HolisticModel::Template(const cv::Mat& image) const {
  if (image.empty()) throw std::invalid_argument("HolisticModel::Template: empty image");
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  } else {
    grey = image;
  }
  const int width = options_.width_px;
  const int height = std::max(4, static_cast<int>(std::lround(width * static_cast<double>(grey.rows) / grey.cols)));
  cv::Mat small, t;
  cv::resize(grey, small, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  small.convertTo(t, CV_32F);
  cv::Scalar mean, deviation;
  cv::meanStdDev(t, mean, deviation);
  if (deviation[0] < 1e-6) return cv::Mat::zeros(t.size(), CV_32F);
  t = (t - mean[0]) / deviation[0];
  return t;
}

double HolisticModel::Difference(const cv::Mat& a, const cv::Mat& b) const {
  return CompareTemplates(a, b, static_cast<int>(options_.max_shift_fraction * a.cols)).difference;
}

std::unique_ptr<FrameScore> HolisticModel::ScoreFrame(const Observation& z,
                                                      const std::vector<const Observation*>& places) const {
  MeanAndDeviation reference;
  if (!z.holistic.empty() && static_cast<int>(places.size()) >= kMinPlaces) {
    std::vector<double> differences;
    differences.reserve(places.size());
    for (const Observation* p : places) {
      if (!p->holistic.empty()) differences.push_back(Difference(z.holistic, p->holistic));
    }
    if (static_cast<int>(differences.size()) >= kMinPlaces) reference = Moments(differences);
  }
  return std::make_unique<HolisticFrameScore>(*this, z.holistic, reference);
}

HolisticCalibration CalibrateHolistic(const HolisticModel& model, const std::vector<cv::Mat>& templates,
                                      const std::vector<double>& path_length_m, double offset_m, double exclusion_m,
                                      int max_frames) {
  if (templates.size() != path_length_m.size()) {
    throw std::invalid_argument("CalibrateHolistic: " + std::to_string(templates.size()) + " templates for " +
                                std::to_string(path_length_m.size()) + " path lengths");
  }
  if (!(offset_m > 0.0 && exclusion_m > offset_m && max_frames >= 1)) {
    throw std::invalid_argument("CalibrateHolistic: need 0 < offset_m < exclusion_m and max_frames >= 1");
  }
  const auto n = static_cast<int>(templates.size());
  const int places_wanted = model.options().reference_places;
  std::vector<double> scores, differences;
  std::vector<int> places;
  const int stride = std::max(1, n / max_frames);
  for (int i = 0; i < n; i += stride) {
    // The neighbour: the frame nearest to offset_m behind i.
    const double target = path_length_m[static_cast<std::size_t>(i)] - offset_m;
    if (target < path_length_m.front()) continue;
    const auto it = std::lower_bound(path_length_m.begin(), path_length_m.begin() + i, target);
    int j = static_cast<int>(it - path_length_m.begin());
    if (j > 0 && std::abs(path_length_m[static_cast<std::size_t>(j - 1)] - target) <
                     std::abs(path_length_m[static_cast<std::size_t>(j)] - target)) {
      --j;
    }
    if (j >= i) continue;
    places.clear();
    for (int k = 0; k < n; ++k) {
      if (std::abs(path_length_m[static_cast<std::size_t>(k)] - path_length_m[static_cast<std::size_t>(i)]) >
          exclusion_m) {
        places.push_back(k);
      }
    }
    if (static_cast<int>(places.size()) < kMinPlaces) continue;
    // Evenly spread over the far frames, as the filter samples its places.
    differences.clear();
    for (const std::size_t k : EvenlySpread(places.size(), places_wanted)) {
      differences.push_back(model.Difference(templates[static_cast<std::size_t>(i)],
                                             templates[static_cast<std::size_t>(places[k])]));
    }
    const MeanAndDeviation m = Moments(differences);
    if (!(m.deviation > 0.0)) continue;
    scores.push_back((m.mean - model.Difference(templates[static_cast<std::size_t>(i)],
                                                templates[static_cast<std::size_t>(j)])) /
                     m.deviation);
  }
  if (scores.empty()) {
    throw std::invalid_argument("CalibrateHolistic: no frame with a neighbour " + std::to_string(offset_m) +
                                " m behind and places more than " + std::to_string(exclusion_m) +
                                " m away (a traversal too short to calibrate on)");
  }
  std::nth_element(scores.begin(), scores.begin() + static_cast<long>(scores.size() / 2), scores.end());
  HolisticCalibration c;
  // A median at or below 0 says the images do not tell places apart at all;
  // the smallest M that still ranks places keeps the model nearly silent.
  c.identical_score = std::max(0.5, scores[scores.size() / 2]);
  c.frames = static_cast<int>(scores.size());
  c.offset_m = offset_m;
  return c;
}

}  // namespace catgraph
