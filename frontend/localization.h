// Appearance-based localisation of a whole dataset with CAT-Graph: every
// frame's words, the filter run over the frames in order with the odometry
// interpolated at the frame times, and what came of it — the best hypothesis
// per frame, the visual loop closures, and the pose graph (odometry edges
// and visual closures) for the back end. Behind `catgraph localize`.
#ifndef CATGRAPH_FRONTEND_LOCALIZATION_H_
#define CATGRAPH_FRONTEND_LOCALIZATION_H_

#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "backend/graph/pose_graph.h"
#include "backend/io/dataset.h"
#include "frontend/cat_graph.h"
#include "frontend/fabmap.h"
#include "frontend/holistic.h"
#include "frontend/observation_model.h"
#include "frontend/vocabulary.h"

namespace catgraph {

inline constexpr double kNoError = std::numeric_limits<double>::quiet_NaN();

struct FrameLocalization {
  int frame = -1;
  int traversal = 1;
  LocationHypothesis best;
  int edge_from_frame = -1, edge_to_frame = -1;  // frames of the best edge's ends; -1: none
  double new_place_probability = 1.0;
  double log_evidence = 0.0;      // CatGraphStep::log_evidence
  double self_evidence = 0.0;     // CatGraphStep::self_evidence
  bool closure = false;
  int matched_frame = -1;         // frame of the matched node (closures)
  double error_m = kNoError;      // best hypothesis against ground truth
  bool inference_pending = false; // CAT-Graph+: passed local validation
};

// A loop closure of the front end: visual (CAT-Graph) or odometry-inferred
// (CAT-Graph+). Its id is its constraint id in the result's pose graph.
struct LoopClosure {
  int id = 0;
  ClosureKind kind = ClosureKind::kVisual;  // kVisual or kOdometryInferred
  int frame = -1;                 // the current frame
  int matched_frame = -1;         // the frame nearest to the matched location
  Pose2 T_frame_matched;          // matched frame's pose in the current frame's
  double hypothesis = 0.0;        // Eq 4 of the filter that made it
  double error_m = kNoError;      // position error of the matched location
  // Inferred: the visual closure it hangs from and the one that validated it.
  std::vector<int> parents;
  bool injected = false;          // forced by LocalizationOptions::imposed (a false match)
  bool vetoed = false;            // visual, at a frame of LocalizationOptions::vetoed_frames
};

// Inferences that passed local validation and were not emitted: they failed
// total-path validation at the next visual closure, or were dropped before
// one came (DiscardReason).
struct DiscardedInference {
  int frame = -1, matched_frame = -1;
  int reference_closure = -1;     // the visual closure they hung from
  int validating_closure = -1;    // the one whose d_tot check failed; -1 for the others
  double error_m = kNoError;
  DiscardReason reason = DiscardReason::kTotalPath;
};
// "total_path", "filter_lost", "sequence_break".
std::string_view ToString(DiscardReason reason);

// The uncertainty the result's pose graph gives its edges, for the back end.
// The spec (§2.9) gives every edge the filter's Q: a particle diffusion per
// frame, as loose as the step itself for odometry (0.05 m on 0.053 m steps)
// and five times tighter than a closure's real error in heading: solved
// with it, the map shrinks and true visual closures are rejected. These
// defaults model odometry as a random walk and closures by the front end's
// measured error (docs/mapping.md "Edge uncertainty").
struct PoseGraphUncertainty {
  // Odometry as a random walk: sigma = k sqrt(d) over d metres (at least
  // min_distance_m), translation in m/sqrt(m), heading in rad/sqrt(m).
  double odometry_m_per_sqrt_m = 0.05;
  double odometry_rad_per_sqrt_m = 0.01;
  double min_distance_m = 0.01;
  // A closure's sigma (x, y, theta): about the front end's measured
  // position error (mean 0.18 m, lateral offsets between traversals 0.15 m)
  // and the heading difference between traversals at one place.
  Eigen::Vector3d closure_sigma{0.25, 0.25, 0.05};
  // The n inferred closures one visual closure validates share one
  // closure's information (each gets 1/n of it): every one of them is its
  // parents' match carried along by odometry, so they share its error and
  // are not n independent measurements. Counted as independent, a false
  // pair of visual matches arrives with dozens of consistent children and
  // outweighs the odometry that contradicts it (docs/mapping.md).
  bool share_inferred_information = true;
};
// Throws std::invalid_argument naming the first field that is not > 0.
void Validate(const PoseGraphUncertainty& uncertainty);

struct LocalizationOptions {
  CatGraphOptions filter;
  PoseGraphUncertainty graph_uncertainty;
  // Closure decisions imposed on the filter by frame number
  // (CatGraphFilter::Commit; e.g. the false visual matches of
  // experiments/false_matches.h); empty: none, the filter decides. Frames
  // >= 0; a forced node must be older than the filter's exclusion windows
  // when its frame comes.
  std::map<int, ClosureOverride> imposed;
  // Frames whose visual closure CAT-Graph+ must not use (ClosureOverride::vetoed):
  // the frames of visual closures the back end rejected. The closures are
  // still made and reported, flagged `vetoed`.
  std::set<int> vetoed_frames;
  int threads = 0;                // feature extraction; 0: every core
  // Called from the calling thread: stage is "features" or "filter".
  std::function<void(const char* stage, std::size_t done, std::size_t total)> on_progress;
};
// The filter's and the graph's options, and threads >= 0; throws
// std::invalid_argument naming the first field out of range.
void Validate(const LocalizationOptions& options);

// The observation model a run used and what it was calibrated to.
struct ObservationSummary {
  std::string model;                           // ObservationModel::Name()
  double new_place_log_offset = 0.0;           // as the filter applied it
  std::optional<HolisticOptions> holistic;     // the holistic model's options ...
  std::optional<HolisticCalibration> calibration;  // ... and calibration
};

struct LocalizationResult {
  ObservationSummary observation;
  std::vector<FrameLocalization> frames;
  std::vector<LoopClosure> closures;  // in the order they were made
  std::vector<DiscardedInference> discarded_inferences;
  PoseGraph2 graph;               // vertex id = frame index; initial guess = odometry
  std::size_t words_per_frame_median = 0;
  // The options that made it, so that a re-run (the back end's feedback,
  // mapping/map_dataset.h) starts from them and cannot mix one run's result
  // with another's options.
  LocalizationOptions options;
};

// The discarded inferences that failed total-path validation (the others
// were dropped before a visual closure came).
std::size_t TotalPathDiscards(const LocalizationResult& r);

// The words of every frame of the dataset, in frame order, extracted on
// options.threads threads. Throws FileError for an image that cannot be read.
std::vector<WordSet> ExtractWords(const Dataset& dataset, const Vocabulary& vocabulary,
                                  const LocalizationOptions& options);

// The default vocabulary: trained on the dataset's first traversal (the map,
// never the traversals localised against it), on every `every`-th frame of
// it, or on about 200 frames spread over it when `every` is 0. Throws
// std::invalid_argument for every < 0, FileError for an unreadable image.
struct MapVocabulary {
  Vocabulary vocabulary;
  int frames = 0;     // trained on
  int traversal = 0;  // the first
};
MapVocabulary TrainMapVocabulary(const Dataset& dataset, const VocabularyOptions& options, int every = 0);

// The observation of every frame, in frame order, on options.threads
// threads: the words when `vocabulary` is given, the holistic template when
// `holistic` is. Throws FileError for an image that cannot be read.
std::vector<Observation> ExtractObservations(const Dataset& dataset, const Vocabulary* vocabulary,
                                             const HolisticModel* holistic, const LocalizationOptions& options);

// The holistic model calibrated on the dataset's first traversal
// (CalibrateHolistic: neighbours d_h apart, places beyond the exclusion
// window's distance), with the templates of every frame.
struct HolisticFrontEnd {
  std::unique_ptr<HolisticModel> model;
  std::vector<Observation> observations;
};
HolisticFrontEnd PrepareHolistic(const Dataset& dataset, const HolisticOptions& holistic,
                                 const LocalizationOptions& options);

// How a dataset's frames are observed, for a caller that builds the model
// from the dataset: the model, the default vocabulary (trained on the first
// traversal when no vocabulary is given) and each model's own options
// (docs/frontend.md "Observation models").
struct ObservationOptions {
  ObservationKind model = ObservationKind::kFabMap;
  // The default vocabulary's training; 500 words, the size the front end's
  // figures in docs/frontend.md were measured with.
  VocabularyOptions vocabulary = [] {
    VocabularyOptions o;
    o.words = 500;
    return o;
  }();
  int train_every = 0;  // TrainMapVocabulary's `every`; >= 0
  FabMapOptions fabmap;
  HolisticOptions holistic;
};
// Throws std::invalid_argument naming the first field out of range (its
// path: "vocabulary.words", "fabmap.p_observe_given_exists", ...).
void Validate(const ObservationOptions& options);

// One frame as a robot delivers it: {time_s, odometry} or with the rest.
struct FrameInput {
  FrameInput() = default;
  FrameInput(double time, const Pose2& odometry_pose, int traversal_number = 1,
             std::optional<Pose2> true_pose = std::nullopt)
      : time_s(time), odometry(odometry_pose), traversal(traversal_number), truth(true_pose) {}

  double time_s = 0.0;
  // The odometry pose at the frame time, in any frame fixed for the run:
  // the filter reads the motion since the previous frame from it.
  Pose2 odometry;
  int traversal = 1;            // reported (FrameLocalization::traversal), not used
  // The true pose when known: scores the hypotheses and closures (error_m)
  // against the true poses of the frames they match.
  std::optional<Pose2> truth;
};

// CAT-Graph and CAT-Graph+ frame by frame, building what Localize returns
// as the frames come: the incremental form behind Localize and the online
// mapping::Mapper. Frame k (the k-th AddFrame) is vertex k of the pose graph.
class Localizer {
 public:
  // `model` must outlive the localizer. options.imposed and
  // options.vetoed_frames apply by frame number. Throws
  // std::invalid_argument on options out of range.
  Localizer(const ObservationModel& model, LocalizationOptions options);
  Localizer(const Localizer&) = delete;
  Localizer& operator=(const Localizer&) = delete;

  // Adds the next frame and returns its localization. The closures it made
  // (a visual one, then the inferences it validated) are appended to
  // result().closures, the inferences it discarded or dropped to
  // result().discarded_inferences, its vertex and edges to result().graph.
  // Throws std::invalid_argument when a decision imposed on the frame
  // forces a node that is not older than the exclusion windows.
  FrameLocalization AddFrame(const FrameInput& frame, const Observation& z);

  const LocalizationResult& result() const { return result_; }
  // The result so far, moved out; the localizer is then spent.
  LocalizationResult TakeResult() && { return std::move(result_); }

 private:
  int FrameOf(int node) const { return filter_.graph().node(node).frame; }
  double LocationError(std::size_t frame, const LocationHypothesis& h) const;
  void AddClosure(const LoopClosure& c, double information_scale);
  int ReferenceClosure(const CatGraphStep& step) const;
  void Discard(const InferredClosure& inferred, int reference, int validating, DiscardReason reason);

  CatGraphFilter filter_;
  LocalizationResult result_;
  Eigen::Matrix3d closure_information_;
  std::vector<std::optional<Pose2>> truth_;    // per frame
  std::optional<Pose2> last_odometry_;
  std::map<int, int> visual_closure_of_frame_;  // frame -> closure id
};

// The filter over frames whose observations are given (one per frame), so
// that several runs over the same data extract the features once.
LocalizationResult Localize(const Dataset& dataset, const std::vector<Observation>& observations,
                            const ObservationModel& model, const LocalizationOptions& options);

// ExtractWords, then the filter with the vocabulary's Chow-Liu tree.
LocalizationResult Localize(const Dataset& dataset, const Vocabulary& vocabulary,
                            const LocalizationOptions& options);

}  // namespace catgraph

#endif  // CATGRAPH_FRONTEND_LOCALIZATION_H_
