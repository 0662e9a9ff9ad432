// A holistic observation model (the SeqSLAM / RatSLAM family, the paper's §6):
// the whole image, shrunk to a tiny grey template and standardised (zero
// mean, unit deviation, so that a global change of exposure or gain does
// not count), compared with a node's template by the mean absolute difference
// over the overlapping columns at the best of a few sideways shifts (a camera
// turned a little between traversals).
//
// A difference D means nothing on its own: it depends on the camera, the
// scene and the frame. So each frame's differences are standardised against
// those to a sample of the places it may be at (SeqSLAM's local contrast
// enhancement): s = (mean D - D) / sd D, about N(0, 1) for a place that is not
// the frame's. At the frame's true place s is larger by an unknown amount μ,
// somewhere between 0 (the place looks like any other) and M, what the first
// traversal's own neighbours score against each other (a revisit can look no
// more alike than that). With μ uniform on [0, M] the log-likelihood ratio of
// "this place" against "some other place" (new place) is
//
//   LLR(s) = log (1/M) ∫_0^M exp(μ s - μ²/2) dμ
//          = s²/2 + log(√(2π) / M) + log(Φ(M - s) - Φ(-s)),
//
// increasing in s, about M s - M²/2 - log(s - M) for large s and only
// -log(M |s|) for very negative s: a frame that looks like nothing (a person
// in front of the camera) does not wipe out the particles at the right
// place. M comes from the data (CalibrateHolistic), so the model has no
// constant in nats; new place is the reference, LLR = 0, and needs no offset.
//
// Thread-compatible; HolisticModel is immutable after construction.
#ifndef CATGRAPH_FRONTEND_HOLISTIC_H_
#define CATGRAPH_FRONTEND_HOLISTIC_H_

#include <memory>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "frontend/observation_model.h"

namespace catgraph {

struct HolisticOptions {
  // Template width; the height follows the image's aspect ratio (at least
  // 4 px). 32: single-frame recognition peaks between 16 and 64 on the real
  // and rendered sets (docs/frontend.md "Observation models").
  int width_px = 32;
  // Sideways shifts tried each way, as a fraction of the width; [0, 0.5).
  double max_shift_fraction = 0.25;
  // Places a frame's differences are standardised against; >= 8.
  int reference_places = 64;
};
// Throws std::invalid_argument naming the first field out of range.
void Validate(const HolisticOptions& options);

// What the calibration read off the first traversal.
struct HolisticCalibration {
  // M: the median standardised score of a frame against the frame about
  // `offset_m` behind it on the same traversal; > 0.
  double identical_score = 3.0;
  int frames = 0;          // frames it was measured on (0: not measured, the value is a default)
  double offset_m = 0.0;   // the distance along the path it was measured at
};

// LLR(s) above, for M > 0.
double HolisticLogLikelihoodRatio(double score, double identical_score);

class HolisticModel : public ObservationModel {
 public:
  // Throws std::invalid_argument on options out of range or M <= 0.
  HolisticModel(HolisticOptions options, HolisticCalibration calibration);

  const HolisticOptions& options() const { return options_; }
  const HolisticCalibration& calibration() const { return calibration_; }

  // The template of an image (colour or grey, any size): CV_32F,
  // width_px wide, standardised (a flat image gives zeros).
  cv::Mat Template(const cv::Mat& image) const;
  // The mean absolute difference of two templates of one size at the best
  // sideways shift (the template matcher's CompareTemplates); throws
  // std::invalid_argument for templates of different sizes.
  double Difference(const cv::Mat& a, const cv::Mat& b) const;

  std::string_view Name() const override { return "holistic"; }
  std::unique_ptr<FrameScore> ScoreFrame(const Observation& z,
                                         const std::vector<const Observation*>& places) const override;
  int PlacesWanted() const override { return options_.reference_places; }
  double NewPlaceLogOffset() const override { return 0.0; }

 private:
  HolisticOptions options_;
  HolisticCalibration calibration_;
};

// M from a traversal's templates in order of travel (`path_length_m`, the
// odometry distance of each, non-decreasing): for up to `max_frames` frames
// spread over it, the standardised score of the frame `offset_m` behind it
// against up to reference_places frames more than `exclusion_m` away along
// the path; the median. offset_m is the distance within which the filter
// calls two places one (d_h). Throws std::invalid_argument on mismatched
// sizes or when no frame has both a neighbour and enough places to compare
// with (a traversal shorter than exclusion_m).
HolisticCalibration CalibrateHolistic(const HolisticModel& model, const std::vector<cv::Mat>& templates,
                                      const std::vector<double>& path_length_m, double offset_m,
                                      double exclusion_m, int max_frames = 200);

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_HOLISTIC_H_
