// The observation model of CAT-Graph (docs/catgraph-spec.md §2.4, §2.7): how
// likely the current frame is at a place whose node saw another frame, and
// how likely it is at a place never seen (new place). The visual filter
// interpolates the node likelihoods along an edge (Eq 2), weighs new place
// against them (Eq 6), and takes the self-evidence as the most any place can
// score. Two models implement it:
//
//   FabMapModel (fabmap.h)      bag of words with a Chow-Liu tree, in nats of
//                               FAB-MAP's own probability model;
//   HolisticModel (holistic.h)  the whole image, tiny and normalised, compared
//                               with sideways shifts (the SeqSLAM family), its
//                               differences turned into a log-likelihood ratio
//                               calibrated on the sequence's own first traversal.
//
// A frame is prepared once (ScoreFrame) and then scored against any number of
// nodes. Models whose scale is relative to the map are given a sample of the
// places the frame may be at (the eligible nodes).
//
// Thread-compatible; a model is immutable after construction.
#ifndef CATGRAPH_FRONTEND_OBSERVATION_MODEL_H_
#define CATGRAPH_FRONTEND_OBSERVATION_MODEL_H_

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

namespace catgraph {

// Sorted, unique word ids present in one image.
using WordSet = std::vector<int>;

// What a frame (and the node made of it) carries for the observation models;
// each model reads its own part and ignores the others.
struct Observation {
  WordSet words;     // FAB-MAP's bag of words
  cv::Mat holistic;  // the holistic template (HolisticModel::Template), CV_32F; empty if unused
};

// One frame's likelihood against any node.
class FrameScore {
 public:
  virtual ~FrameScore() = default;
  // log p(z | L) for the place whose node observed `node`.
  virtual double LogLikelihood(const Observation& node) const = 0;
  // log p(z | new place) (Eq 6's observation term).
  virtual double LogNewPlaceLikelihood() const = 0;
  // log p(z | a place the camera does not see), for particles facing against
  // the nodes (CatGraphOptions::forward_camera): what an unremarkable place
  // scores. FAB-MAP's is its mean field, as new place.
  virtual double LogUnseenPlaceLikelihood() const { return LogNewPlaceLikelihood(); }
  // How much better than new place the best-matching place can explain the
  // frame, in nats (>= 0): the scale the filter's relative thresholds refer to.
  virtual double SelfEvidence() const = 0;
};

class ObservationModel {
 public:
  virtual ~ObservationModel() = default;
  // "fabmap" or "holistic".
  virtual std::string_view Name() const = 0;
  // Prepares frame `z`, which must outlive the score. `places` samples the
  // observations of the places the frame may be at (at most PlacesWanted(),
  // in any order; may be empty).
  virtual std::unique_ptr<FrameScore> ScoreFrame(const Observation& z,
                                                 const std::vector<const Observation*>& places) const = 0;
  // How many places ScoreFrame wants to see; 0: it does not use them.
  virtual int PlacesWanted() const { return 0; }
  // Added to log p(z | new place) unless the filter's options set one
  // (CatGraphOptions::new_place_log_offset): how much better than new place a
  // place must score to be taken for it, in this model's nats.
  virtual double NewPlaceLogOffset() const = 0;
};

// Up to `wanted` indices of [0, count), evenly spread from 0: the places a
// model that standardises against the map is shown.
std::vector<std::size_t> EvenlySpread(std::size_t count, int wanted);

// Which observation model a run uses.
enum class ObservationKind { kFabMap, kHolistic };
std::string_view ToString(ObservationKind kind);
std::optional<ObservationKind> ObservationKindFromString(std::string_view text);  // "fabmap", "holistic"
std::vector<std::string> ObservationKindNames();

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_OBSERVATION_MODEL_H_
