// False visual matches at the source, for the experiment of the CAT-Graph+
// paper's discussion: perceptual aliasing makes the visual filter take a
// stretch of the current path for a wrong but similarly shaped stretch of
// the old trajectory. Each false match is a pair of false visual closures,
// at the two ends of the stretch and consistent with each other, so that
// CAT-Graph+ validates the odometry-inferred closures between them (and
// names both as their parents). `catgraph map --inject-false-visual N`;
// docs/mapping.md.
//
// The plan is made from the dataset's odometry and ground truth before the
// filter runs (ground truth makes sure every match is false), and imposed
// on it by frame (ImposedDecisions, LocalizationOptions::imposed).
#ifndef CATGRAPH_EXPERIMENTS_FALSE_MATCHES_H_
#define CATGRAPH_EXPERIMENTS_FALSE_MATCHES_H_

#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include "backend/io/dataset.h"
#include "frontend/cat_graph.h"

namespace catgraph {

// Frames `first_frame` ... `last_frame` of the current path are taken for
// the old stretch from `matched_first_frame` to `matched_last_frame`: false
// visual closures at both ends; the filter's own closures in between are
// withheld (the aliasing lasts the stretch).
struct FalseVisualMatch {
  int first_frame = -1, last_frame = -1;
  int matched_first_frame = -1, matched_last_frame = -1;
};

struct FalseMatchOptions {
  int count = 0;                    // false matches (pairs of false visual closures); >= 0
  std::uint64_t seed = 1;
  double stretch_m = 2.0;           // path length of each stretch; > 0
  // Every frame of a stretch is at least this far from the old place it is
  // taken for (ground truth): a false match, not a loose true one; > 0.
  double min_error_m = 2.0;
  double max_error_m = std::numeric_limits<double>::infinity();  // ... and at most this; >= min_error_m
  // The two stretches have the same shape: by odometry, every frame's
  // position relative to the stretch's start agrees with its counterpart's
  // to this (m) and its heading to shape_tolerance_rad; > 0.
  double shape_tolerance_m = 0.2;
  double shape_tolerance_rad = 0.1;
  // Path between two stretches (m), where the filter's own closures count
  // again; >= 0.
  double separation_m = 2.0;
};

// `options.count` false matches drawn at random (by `options.seed`) among
// the stretches that qualify: the old stretch is older than the filter's
// exclusion windows and inside its odometric gate all along (so the filters
// can follow it), of the same shape, and at least min_error_m from the
// truth at every frame. Sorted by frame. Throws std::invalid_argument for a
// dataset without ground truth or odometry, options out of range, or when
// fewer than `count` qualify (saying how many).
std::vector<FalseVisualMatch> PlanFalseVisualMatches(const Dataset& dataset, const CatGraphOptions& filter,
                                                     const FalseMatchOptions& options);

// The plan as decisions imposed on the filter by frame: at the first and
// last frame of each stretch the old frame is forced, every frame between
// them withholds the filter's own closure. Throws std::invalid_argument for
// a match that does not map frames first < last onto older frames, or for
// matches that overlap.
std::map<int, ClosureOverride> ImposedDecisions(const std::vector<FalseVisualMatch>& plan);

}  // namespace catgraph

#endif  // CATGRAPH_EXPERIMENTS_FALSE_MATCHES_H_
