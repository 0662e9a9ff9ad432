#include "frontend/sad_matcher.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "frontend/vocabulary.h"

namespace catgraph {
namespace {

// z-score of `v` against mean and standard deviation, mapped to [0, 1] as
// (z + 3) / 6 and clipped; flat neighbourhoods give 0.5.
float MapZ(double v, double mean, double sd) {
  if (sd < 1e-6) return 0.5f;
  return static_cast<float>(std::clamp(((v - mean) / sd + 3.0) / 6.0, 0.0, 1.0));
}

void RegionMoments(const cv::Mat& m, const cv::Rect& r, double& mean, double& sd) {
  cv::Scalar mu, sigma;
  cv::meanStdDev(m(r), mu, sigma);
  mean = mu[0];
  sd = sigma[0];
}

}  // namespace

std::string_view ToString(SadNormalization n) {
  switch (n) {
    case SadNormalization::kNone: return "none";
    case SadNormalization::kLocal: return "local";
    case SadNormalization::kPatch: return "patch";
  }
  return "none";
}

SadNormalization SadNormalizationFromString(std::string_view text) {
  for (const auto n : {SadNormalization::kNone, SadNormalization::kLocal, SadNormalization::kPatch}) {
    if (text == ToString(n)) return n;
  }
  throw std::invalid_argument("normalisation '" + std::string(text) + "': expected none, local or patch");
}

void Validate(const SadOptions& o) {
  auto fail = [](const std::string& what) { throw std::invalid_argument("SadOptions: " + what); };
  if (o.width_px < 2 || o.height_px < 2) fail("template size must be >= 2 x 2");
  if (o.max_shift_px < 0 || o.max_shift_px >= o.width_px) fail("max_shift_px must be in [0, width)");
  if (o.every < 1) fail("every must be >= 1");
  if (o.local_radius_px < 1) fail("local_radius_px must be >= 1");
  if (o.patch_px < 2) fail("patch_px must be >= 2");
}

cv::Mat SadTemplate(const cv::Mat& image, const SadOptions& o) {
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else {
    grey = image;
  }
  cv::Mat small;
  cv::resize(grey, small, cv::Size(o.width_px, o.height_px), 0, 0, cv::INTER_AREA);
  cv::Mat t;
  small.convertTo(t, CV_32F, 1.0 / 255.0);
  if (o.normalization == SadNormalization::kNone) return t;
  cv::Mat out(t.size(), CV_32F);
  double mean = 0.0, sd = 0.0;
  if (o.normalization == SadNormalization::kLocal) {
    const int r = o.local_radius_px;
    for (int y = 0; y < t.rows; ++y) {
      for (int x = 0; x < t.cols; ++x) {
        const int x0 = std::max(0, x - r), y0 = std::max(0, y - r);
        const cv::Rect window(x0, y0, std::min(t.cols, x + r + 1) - x0, std::min(t.rows, y + r + 1) - y0);
        RegionMoments(t, window, mean, sd);
        out.at<float>(y, x) = MapZ(t.at<float>(y, x), mean, sd);
      }
    }
    return out;
  }
  for (int y0 = 0; y0 < t.rows; y0 += o.patch_px) {
    for (int x0 = 0; x0 < t.cols; x0 += o.patch_px) {
      const cv::Rect patch(x0, y0, std::min(o.patch_px, t.cols - x0), std::min(o.patch_px, t.rows - y0));
      RegionMoments(t, patch, mean, sd);
      for (int y = patch.y; y < patch.y + patch.height; ++y) {
        for (int x = patch.x; x < patch.x + patch.width; ++x) out.at<float>(y, x) = MapZ(t.at<float>(y, x), mean, sd);
      }
    }
  }
  return out;
}

SadComparison CompareTemplates(const cv::Mat& query, const cv::Mat& reference, int max_shift_px) {
  if (query.size() != reference.size() || query.type() != CV_32F || reference.type() != CV_32F) {
    throw std::invalid_argument("CompareTemplates: templates of different size or type");
  }
  SadComparison best{std::numeric_limits<double>::infinity(), 0};
  const int w = query.cols;
  for (int s = -max_shift_px; s <= max_shift_px; ++s) {
    // Query column c against reference column c + s, where both exist; the
    // mean over the overlap, so that large shifts are not favoured.
    const int c0 = std::max(0, -s), c1 = std::min(w, w - s);
    if (c1 <= c0) continue;
    double sum = 0.0;
    for (int y = 0; y < query.rows; ++y) {
      const float* q = query.ptr<float>(y);
      const float* r = reference.ptr<float>(y);
      for (int c = c0; c < c1; ++c) sum += std::abs(q[c] - r[c + s]);
    }
    const double mean = sum / (static_cast<double>(c1 - c0) * query.rows);
    if (mean < best.difference) best = {mean, s};
  }
  return best;
}

std::vector<SadMatch> MatchDataset(const Dataset& d, const SadOptions& o) {
  Validate(o);
  if (d.frames.empty()) return {};
  const int first = d.Traversals().front();
  auto load = [&](std::size_t i) { return SadTemplate(ReadImage(d.ImagePath(i)), o); };
  std::vector<std::size_t> template_frames, query_frames;
  std::vector<cv::Mat> templates;
  int seen_first = 0, seen_other = 0;
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    if (d.frames[i].traversal == first) {
      if (seen_first++ % o.every == 0) template_frames.push_back(i), templates.push_back(load(i));
    } else if (seen_other++ % o.every == 0) {
      query_frames.push_back(i);
    }
  }
  std::vector<SadMatch> matches;
  if (templates.empty()) return matches;
  for (const std::size_t q : query_frames) {
    const cv::Mat query = load(q);
    SadMatch m;
    m.query_frame = static_cast<int>(q);
    m.comparison.difference = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < templates.size(); ++t) {
      const SadComparison c = CompareTemplates(query, templates[t], o.max_shift_px);
      if (c.difference < m.comparison.difference) {
        m.comparison = c;
        m.template_frame = static_cast<int>(template_frames[t]);
      }
    }
    if (d.HasGroundTruth()) {
      const auto at = [&](int frame) {
        return InterpolatePose(d.ground_truth, d.frames[static_cast<std::size_t>(frame)].timestamp_s).translation();
      };
      m.error_m = (at(m.query_frame) - at(m.template_frame)).norm();
    }
    matches.push_back(m);
  }
  return matches;
}

std::vector<SadThresholdPoint> SweepThreshold(const std::vector<SadMatch>& matches, double tolerance_m, int count) {
  std::vector<SadThresholdPoint> points;
  if (matches.empty() || count < 2) return points;
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (const auto& m : matches) {
    lo = std::min(lo, m.comparison.difference);
    hi = std::max(hi, m.comparison.difference);
  }
  for (int i = 0; i < count; ++i) {
    SadThresholdPoint p;
    p.threshold = lo + (hi - lo) * i / (count - 1);
    for (const auto& m : matches) {
      if (!(m.comparison.difference <= p.threshold)) continue;
      ++p.accepted;
      p.false_matches += m.error_m > tolerance_m ? 1 : 0;
    }
    points.push_back(p);
  }
  return points;
}

double BestThreshold(const std::vector<SadMatch>& matches, double tolerance_m) {
  double smallest_false = std::numeric_limits<double>::infinity(), largest = 0.0;
  for (const auto& m : matches) {
    largest = std::max(largest, m.comparison.difference);
    if (m.error_m > tolerance_m) smallest_false = std::min(smallest_false, m.comparison.difference);
  }
  // Accepted: difference <= threshold.
  if (std::isinf(smallest_false)) return largest;
  return std::nextafter(smallest_false, 0.0);
}

}  // namespace catgraph
