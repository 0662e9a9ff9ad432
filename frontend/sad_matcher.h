// The baseline of the CAT-Graph+ paper (§5.2; docs/catgraph-spec.md §8): a
// RatSLAM / SeqSLAM-style template matcher. Every frame becomes a tiny grey
// template (16 × 8 by area averaging); a query is compared with every
// reference template by the mean absolute difference over the overlapping
// columns, the query shifted sideways by up to ±2 pixels (about ±12° at this
// size); the smallest difference wins. A match is accepted when its
// difference is at most a threshold, which is swept: its best value is the
// largest with no false match.
//
// Thread-compatible; pure functions of their inputs.
#ifndef CATGRAPH_FRONTEND_SAD_MATCHER_H_
#define CATGRAPH_FRONTEND_SAD_MATCHER_H_

#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

#include "backend/io/dataset.h"

namespace catgraph {

enum class SadNormalization {
  kNone,
  kLocal,  // RatSLAM: z-score over a (2r+1)² neighbourhood, mapped to [0, 1] as (z+3)/6
  kPatch,  // SeqSLAM: z-score per non-overlapping patch, mapped the same way
};
std::string_view ToString(SadNormalization n);
// Throws std::invalid_argument listing the names.
SadNormalization SadNormalizationFromString(std::string_view text);

struct SadOptions {
  int width_px = 16, height_px = 8;  // template size; >= 2
  int max_shift_px = 2;              // sideways shifts tried each way; >= 0, < width
  int every = 2;                     // every N-th frame is a template / a query; >= 1
  SadNormalization normalization = SadNormalization::kNone;
  int local_radius_px = 1;           // kLocal; >= 1
  int patch_px = 4;                  // kPatch; >= 2
};
// Throws std::invalid_argument naming the first field out of range.
void Validate(const SadOptions& options);

// The template of one image (colour or grey): grey, area-resized, values in
// [0, 1] (or normalised), CV_32F.
cv::Mat SadTemplate(const cv::Mat& image, const SadOptions& options);

struct SadComparison {
  double difference = 0.0;  // mean absolute difference over the overlap
  int shift_px = 0;         // of the query against the template
};
// The best shift of `query` against `reference` (same size).
SadComparison CompareTemplates(const cv::Mat& query, const cv::Mat& reference, int max_shift_px);

struct SadMatch {
  int query_frame = -1;      // row of frames.csv
  int template_frame = -1;   // the best reference
  SadComparison comparison;
  double error_m = -1.0;     // template's true position against the query's; < 0: no ground truth
};

// Templates: every `every`-th frame of the first traversal; queries: every
// `every`-th frame of the others. Throws FileError for an unreadable image.
std::vector<SadMatch> MatchDataset(const Dataset& dataset, const SadOptions& options);

struct SadThresholdPoint {
  double threshold = 0.0;
  int accepted = 0, false_matches = 0;
};
// Accepted / false counts for `count` thresholds spread over the range of the
// matches' differences; false = error above `tolerance_m`.
std::vector<SadThresholdPoint> SweepThreshold(const std::vector<SadMatch>& matches, double tolerance_m,
                                              int count = 200);
// The largest threshold with no false match: just below the smallest
// difference of a false match, or the largest difference when none is false.
double BestThreshold(const std::vector<SadMatch>& matches, double tolerance_m);

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_SAD_MATCHER_H_
