#include "experiments/evidence.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace catgraph {
namespace {

void MaxInto(double& best, double value) { best = std::isnan(best) ? value : std::max(best, value); }

}  // namespace

void Validate(const EvidenceOptions& o) {
  if (!(o.true_radius_m > 0.0 && o.true_radius_m <= o.near_min_m && o.near_min_m < o.near_max_m &&
        o.max_heading_rad >= 0.0)) {
    throw std::invalid_argument(
        "EvidenceOptions: expected 0 < true_radius_m <= near_min_m < near_max_m and max_heading_rad >= 0");
  }
}

std::vector<FrameEvidence> MeasureEvidence(const ObservationModel& model, const std::vector<WordSet>& words,
                                           const std::vector<Pose2>& truth, const std::vector<bool>& changed,
                                           const std::vector<int>& map_frames, const std::vector<int>& query_frames,
                                           const EvidenceOptions& o) {
  std::vector<Observation> observations;
  observations.reserve(words.size());
  for (const WordSet& w : words) observations.push_back({w, {}});
  return MeasureEvidence(model, observations, truth, changed, map_frames, query_frames, o);
}

std::vector<FrameEvidence> MeasureEvidence(const ObservationModel& model, const std::vector<Observation>& words,
                                           const std::vector<Pose2>& truth, const std::vector<bool>& changed,
                                           const std::vector<int>& map_frames, const std::vector<int>& query_frames,
                                           const EvidenceOptions& o) {
  if (words.size() != truth.size() || (!changed.empty() && changed.size() != words.size())) {
    throw std::invalid_argument("MeasureEvidence: words, truth and changed must have one entry per frame");
  }
  Validate(o);
  const auto check = [&](int frame) {
    if (frame < 0 || static_cast<std::size_t>(frame) >= words.size()) {
      throw std::invalid_argument("MeasureEvidence: frame " + std::to_string(frame) + " out of range");
    }
    return static_cast<std::size_t>(frame);
  };
  for (const int m : map_frames) check(m);
  // The places a model that standardises against the map is shown: the map
  // frames, evenly spread.
  std::vector<const Observation*> places;
  for (const std::size_t i : EvenlySpread(map_frames.size(), model.PlacesWanted())) {
    places.push_back(&words[static_cast<std::size_t>(map_frames[i])]);
  }
  std::vector<FrameEvidence> result;
  result.reserve(query_frames.size());
  for (const int q : query_frames) {
    const std::size_t k = check(q);
    const std::unique_ptr<FrameScore> likelihood = model.ScoreFrame(words[k], places);
    const double mean_field = likelihood->LogNewPlaceLikelihood();
    FrameEvidence e;
    e.frame = q;
    e.words = words[k].words.size();
    e.changed = !changed.empty() && changed[k];
    e.self = likelihood->SelfEvidence();
    for (const int m : map_frames) {
      const auto j = static_cast<std::size_t>(m);
      if (std::abs(WrapAngle(truth[j].theta() - truth[k].theta())) > o.max_heading_rad) continue;
      const double distance = (truth[j].translation() - truth[k].translation()).norm();
      const bool near = distance >= o.near_min_m && distance < o.near_max_m;
      if (distance >= o.true_radius_m && !near && distance < o.near_max_m) continue;  // between the bands
      const double nats = likelihood->LogLikelihood(words[j]) - mean_field;
      MaxInto(distance < o.true_radius_m ? e.true_place : near ? e.near : e.far, nats);
    }
    result.push_back(e);
  }
  return result;
}

OffsetSeparation SeparationAt(const std::vector<FrameEvidence>& evidence, double constant, double relative) {
  OffsetSeparation s{constant, relative, 0, 0.0, 0.0};
  std::size_t true_over = 0, near_over = 0;
  for (const FrameEvidence& e : evidence) {
    if (std::isnan(e.true_place)) continue;
    ++s.frames;
    const double offset = constant + relative * e.self;
    true_over += e.true_place > offset ? 1 : 0;
    near_over += !std::isnan(e.near) && e.near > offset ? 1 : 0;
  }
  if (s.frames > 0) {
    s.true_over = static_cast<double>(true_over) / static_cast<double>(s.frames);
    s.near_over = static_cast<double>(near_over) / static_cast<double>(s.frames);
  }
  return s;
}

}  // namespace catgraph
