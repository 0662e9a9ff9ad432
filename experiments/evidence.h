// How well an observation model tells a revisited place from its
// neighbours, frame by frame, against ground truth: the measurement behind the new-place offsets
// (docs/frontend.md "A relative new-place offset"), `catgraph evidence`.
//
// For a query frame z (a later traversal) and a map frame L (the first), the
// evidence is log p(z | L) - log p(z | new place) in the model's nats, the quantity the
// new-place offset is compared with. Per query frame:
//   self      the evidence of z against a node that saw exactly z's words:
//             how much better than the mean field any place can explain it;
//   true      the best evidence of the map frames at the query's place;
//   near      the best of the map frames a few metres away along the route
//             (the look-alikes a forward camera meets in a corridor);
//   far       the best of the rest.
// Map frames facing more than `max_heading_rad` away from the query are left
// out: a forward camera sees something else there.
#ifndef CATGRAPH_EXPERIMENTS_EVIDENCE_H_
#define CATGRAPH_EXPERIMENTS_EVIDENCE_H_

#include <cstddef>
#include <limits>
#include <numbers>
#include <vector>

#include "backend/graph/pose2.h"
#include "frontend/fabmap.h"

namespace catgraph {

struct EvidenceOptions {
  double true_radius_m = 0.5;                      // "true": map frames nearer than this; > 0
  double near_min_m = 2.0, near_max_m = 10.0;      // "near": in [min, max); true_radius <= min < max
  double max_heading_rad = std::numbers::pi / 4;   // map frames facing farther away are left out; >= 0
};

// Throws std::invalid_argument unless 0 < true_radius_m <= near_min_m <
// near_max_m and max_heading_rad >= 0.
void Validate(const EvidenceOptions& options);

struct FrameEvidence {
  int frame = -1;
  std::size_t words = 0;
  bool changed = false;   // the query sees a changed region (simulated data)
  // Nats over the mean field; NaN where no map frame qualifies.
  double self = 0.0;
  double true_place = std::numeric_limits<double>::quiet_NaN();
  double near = std::numeric_limits<double>::quiet_NaN();
  double far = std::numeric_limits<double>::quiet_NaN();
};

// `observations` and `truth` per frame (same length); `map_frames` and
// `query_frames` index them. `changed` (per frame, may be empty) is copied
// into the result. A model that standardises against the map
// (ObservationModel::PlacesWanted) is shown the map frames, evenly spread.
// Throws std::invalid_argument on mismatched sizes, an index out of range or
// options out of range.
std::vector<FrameEvidence> MeasureEvidence(const ObservationModel& model, const std::vector<Observation>& observations,
                                           const std::vector<Pose2>& truth, const std::vector<bool>& changed,
                                           const std::vector<int>& map_frames, const std::vector<int>& query_frames,
                                           const EvidenceOptions& options = {});
// The same for frames observed by their words alone.
std::vector<FrameEvidence> MeasureEvidence(const ObservationModel& model, const std::vector<WordSet>& words,
                                           const std::vector<Pose2>& truth, const std::vector<bool>& changed,
                                           const std::vector<int>& map_frames, const std::vector<int>& query_frames,
                                           const EvidenceOptions& options = {});

// Of the query frames with a true place: the fraction whose true place, and
// the fraction whose best near place, scores over the offset
// `constant + relative * self` — how often a place would enter the map
// rightly and wrongly at that offset, frame by frame.
struct OffsetSeparation {
  double constant = 0.0, relative = 0.0;
  std::size_t frames = 0;
  double true_over = 0.0, near_over = 0.0;
};
OffsetSeparation SeparationAt(const std::vector<FrameEvidence>& evidence, double constant, double relative);

}  // namespace catgraph

#endif  // CATGRAPH_EXPERIMENTS_EVIDENCE_H_
