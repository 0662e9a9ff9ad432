#include "frontend/localization.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr NameTable<DiscardReason, 3> kDiscardReasonNames = {{
    {DiscardReason::kTotalPath, "total_path"},
    {DiscardReason::kFilterLost, "filter_lost"},
    {DiscardReason::kSequenceBreak, "sequence_break"},
}};

}  // namespace

std::vector<WordSet> ExtractWords(const Dataset& d, const Vocabulary& vocabulary,
                                  const LocalizationOptions& options) {
  std::vector<Observation> observations = ExtractObservations(d, &vocabulary, nullptr, options);
  std::vector<WordSet> words;
  words.reserve(observations.size());
  for (Observation& o : observations) words.push_back(std::move(o.words));
  return words;
}

std::vector<Observation> ExtractObservations(const Dataset& d, const Vocabulary* vocabulary,
                                             const HolisticModel* holistic, const LocalizationOptions& options) {
  std::vector<Observation> observations(d.frames.size());
  std::atomic<std::size_t> next{0}, done{0};
  std::exception_ptr error;
  std::mutex mutex;
  auto work = [&](bool report) {
    for (std::size_t i = next++; i < d.frames.size(); i = next++) {
      try {
        const cv::Mat image = ReadImage(d.ImagePath(i));
        if (vocabulary != nullptr) observations[i].words = vocabulary->Words(image);
        if (holistic != nullptr) observations[i].holistic = holistic->Template(image);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
      }
      ++done;
      if (report && options.on_progress) options.on_progress("features", done.load(), d.frames.size());
    }
  };
  const int n = options.threads > 0 ? options.threads : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  std::vector<std::jthread> pool;  // joined on the way out should starting one fail
  for (int i = 1; i < n; ++i) pool.emplace_back(work, false);
  work(true);  // the calling thread works too, and reports
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  if (options.on_progress) options.on_progress("features", d.frames.size(), d.frames.size());
  return observations;
}

MapVocabulary TrainMapVocabulary(const Dataset& d, const VocabularyOptions& options, int every) {
  if (every < 0) throw std::invalid_argument("TrainMapVocabulary: every must be >= 0, not " + std::to_string(every));
  const int first = d.Traversals().front();
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < d.frames.size(); ++i) {
    if (d.frames[i].traversal == first) frames.push_back(i);
  }
  // Automatic: about 200 images, every frame of a short traversal.
  const std::size_t step = every > 0 ? static_cast<std::size_t>(every) : std::max<std::size_t>(1, frames.size() / 200);
  std::vector<cv::Mat> images;
  for (std::size_t k = 0; k < frames.size(); k += step) images.push_back(ReadImage(d.ImagePath(frames[k])));
  MapVocabulary out{TrainVocabulary(images, options), static_cast<int>(images.size()), first};
  return out;
}

HolisticFrontEnd PrepareHolistic(const Dataset& d, const HolisticOptions& holistic,
                                 const LocalizationOptions& options) {
  HolisticFrontEnd out;
  const HolisticModel uncalibrated(holistic, {});
  out.observations = ExtractObservations(d, nullptr, &uncalibrated, options);
  // The first traversal in order of travel, with its odometry distance.
  const int first = d.Traversals().front();
  const std::vector<Pose2> odometry = PosesAtFrames(d, d.odometry);
  std::vector<cv::Mat> templates;
  std::vector<double> path_length_m;
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    if (d.frames[k].traversal != first) continue;
    path_length_m.push_back(path_length_m.empty() ? 0.0
                                                  : path_length_m.back() +
                                                        (odometry[k].translation() - odometry[k - 1].translation()).norm());
    templates.push_back(out.observations[k].holistic);
  }
  const HolisticCalibration calibration =
      CalibrateHolistic(uncalibrated, templates, path_length_m, options.filter.hypothesis_radius_m,
                        std::max(options.filter.exclusion_window_m, 2.0 * options.filter.hypothesis_radius_m));
  out.model = std::make_unique<HolisticModel>(holistic, calibration);
  return out;
}

LocalizationResult Localize(const Dataset& d, const Vocabulary& vocabulary,
                            const LocalizationOptions& options) {
  const FabMapModel model(vocabulary.tree(), FabMapOptions{});
  return Localize(d, ExtractObservations(d, &vocabulary, nullptr, options), model, options);
}

namespace {

Eigen::Matrix3d InformationOf(const Eigen::Vector3d& sigma) {
  return sigma.cwiseProduct(sigma).cwiseInverse().asDiagonal();
}

const LocalizationOptions& Validated(const LocalizationOptions& options) {
  Validate(options);
  return options;
}

}  // namespace

void Validate(const PoseGraphUncertainty& u) {
  auto require = [](bool ok, const char* field) {
    if (!ok) throw std::invalid_argument(std::string("PoseGraphUncertainty: ") + field + " must be finite and > 0");
  };
  require(std::isfinite(u.odometry_m_per_sqrt_m) && u.odometry_m_per_sqrt_m > 0.0, "odometry_m_per_sqrt_m");
  require(std::isfinite(u.odometry_rad_per_sqrt_m) && u.odometry_rad_per_sqrt_m > 0.0, "odometry_rad_per_sqrt_m");
  require(std::isfinite(u.min_distance_m) && u.min_distance_m > 0.0, "min_distance_m");
  require(IsValidSigma(u.closure_sigma), "closure_sigma");
}

std::size_t TotalPathDiscards(const LocalizationResult& r) {
  return static_cast<std::size_t>(
      std::count_if(r.discarded_inferences.begin(), r.discarded_inferences.end(),
                    [](const DiscardedInference& x) { return x.reason == DiscardReason::kTotalPath; }));
}

void Validate(const ObservationOptions& options) {
  // A part's own Validate, its message naming the field by its path here.
  auto part = [](const char* name, const char* type, auto validate) {
    try {
      validate();
    } catch (const std::invalid_argument& e) {
      std::string what = e.what();
      const std::string prefix = std::string(type) + ": ";
      if (what.starts_with(prefix)) what = what.substr(prefix.size());
      throw std::invalid_argument("ObservationOptions: " + std::string(name) + "." + what);
    }
  };
  part("vocabulary", "VocabularyOptions", [&] { Validate(options.vocabulary); });
  part("fabmap", "FabMapOptions", [&] { Validate(options.fabmap); });
  part("holistic", "HolisticOptions", [&] { Validate(options.holistic); });
  if (options.train_every < 0) throw std::invalid_argument("ObservationOptions: train_every must be >= 0");
}

void Validate(const LocalizationOptions& options) {
  Validate(options.filter);
  Validate(options.graph_uncertainty);
  if (options.threads < 0) throw std::invalid_argument("LocalizationOptions: threads must be >= 0");
  if (!options.imposed.empty() && options.imposed.begin()->first < 0) {
    throw std::invalid_argument("LocalizationOptions: imposed decisions need frames >= 0");
  }
}

Localizer::Localizer(const ObservationModel& model, LocalizationOptions options)
    : filter_(model, Validated(options).filter),
      closure_information_(InformationOf(options.graph_uncertainty.closure_sigma)) {
  result_.options = std::move(options);
  result_.observation.model = model.Name();
  result_.observation.new_place_log_offset =
      result_.options.filter.new_place.log_offset.value_or(model.NewPlaceLogOffset());
  if (const auto* holistic = dynamic_cast<const HolisticModel*>(&model)) {
    result_.observation.holistic = holistic->options();
    result_.observation.calibration = holistic->calibration();
  }
}

double Localizer::LocationError(std::size_t frame, const LocationHypothesis& h) const {
  if (h.edge < 0 || !truth_[frame]) return kNoError;
  const GraphEdge& e = filter_.graph().edge(h.edge);
  const std::optional<Pose2>& a = truth_[static_cast<std::size_t>(FrameOf(e.from))];
  const std::optional<Pose2>& b = truth_[static_cast<std::size_t>(FrameOf(e.to))];
  if (!a || !b) return kNoError;
  return (truth_[frame]->translation() - InterpolateTranslation(*a, *b, h.alpha)).norm();
}

void Localizer::AddClosure(const LoopClosure& c, double information_scale) {
  result_.closures.push_back(c);
  Provenance provenance;
  for (const int parent : c.parents) provenance.parents.push_back(ClosureId(parent));
  result_.graph.constraints.push_back({ClosureId(c.id), PoseId(c.frame), PoseId(c.matched_frame),
                                       {c.T_frame_matched, information_scale * closure_information_}, c.kind,
                                       provenance, {}, {}, {}});
}

// The id of the visual closure a step's inferences hung from (-1: none).
int Localizer::ReferenceClosure(const CatGraphStep& step) const {
  const int reference = step.inference.reference_node;
  const auto found = visual_closure_of_frame_.find(reference >= 0 ? FrameOf(reference) : -1);
  return found == visual_closure_of_frame_.end() ? -1 : found->second;
}

void Localizer::Discard(const InferredClosure& inferred, int reference, int validating, DiscardReason reason) {
  const int at = FrameOf(inferred.node);
  result_.discarded_inferences.push_back({at, FrameOf(inferred.matched_node), reference, validating,
                                          LocationError(static_cast<std::size_t>(at), inferred.location), reason});
}

FrameLocalization Localizer::AddFrame(const FrameInput& in, const Observation& z) {
  const PoseGraphUncertainty& uncertainty = result_.options.graph_uncertainty;
  const std::size_t k = result_.frames.size();
  const auto imposed = result_.options.imposed.find(static_cast<int>(k));
  ClosureOverride decision = imposed == result_.options.imposed.end() ? ClosureOverride{} : imposed->second;
  decision.vetoed = decision.vetoed || result_.options.vetoed_frames.count(static_cast<int>(k)) > 0;
  truth_.push_back(in.truth);
  const Pose2 u = last_odometry_ ? last_odometry_->Between(in.odometry) : Pose2();
  last_odometry_ = in.odometry;
  CatGraphStep step = filter_.Propose(static_cast<int>(k), in.time_s, u, z);
  filter_.Commit(step, decision);
  FrameLocalization f;
  f.frame = static_cast<int>(k);
  f.traversal = in.traversal;
  f.best = step.best;
  f.new_place_probability = step.new_place_probability;
  f.log_evidence = step.log_evidence;
  f.self_evidence = step.self_evidence;
  if (step.best.edge >= 0) {
    f.edge_from_frame = FrameOf(filter_.graph().edge(step.best.edge).from);
    f.edge_to_frame = FrameOf(filter_.graph().edge(step.best.edge).to);
  }
  f.error_m = LocationError(k, step.best);

  const PoseId id(static_cast<std::int64_t>(k));
  result_.graph.vertices[id] = {id, in.odometry, k == 0};
  if (k > 0) {
    const double root_d = std::sqrt(std::max(u.translation().norm(), uncertainty.min_distance_m));
    const Eigen::Matrix3d information = InformationOf(
        Eigen::Vector3d(uncertainty.odometry_m_per_sqrt_m, uncertainty.odometry_m_per_sqrt_m,
                        uncertainty.odometry_rad_per_sqrt_m) *
        root_d);
    result_.graph.constraints.push_back({ClosureId(static_cast<std::int64_t>(result_.graph.constraints.size())),
                                         PoseId(static_cast<std::int64_t>(k - 1)), id, {u, information},
                                         ClosureKind::kOdometry, {}, {}, {}, {}});
  }
  if (step.closure) {
    f.closure = true;
    f.matched_frame = FrameOf(step.matched_node);
    LoopClosure c;
    c.id = static_cast<int>(result_.graph.constraints.size());
    c.frame = f.frame;
    c.matched_frame = f.matched_frame;
    c.T_frame_matched = step.T_node_matched;
    c.hypothesis = step.best.value;
    c.error_m = f.error_m;
    c.injected = decision.force_node >= 0;
    c.vetoed = decision.vetoed;
    AddClosure(c, 1.0);
    // CAT-Graph+: what this visual closure validated or discarded.
    const int reference = ReferenceClosure(step);
    for (const InferredClosure& inferred : step.inference.inferred) {
      LoopClosure i;
      i.id = static_cast<int>(result_.graph.constraints.size());
      i.kind = ClosureKind::kOdometryInferred;
      i.frame = FrameOf(inferred.node);
      i.matched_frame = FrameOf(inferred.matched_node);
      i.T_frame_matched = inferred.T_node_matched;
      i.hypothesis = inferred.location.value;
      i.error_m = LocationError(static_cast<std::size_t>(i.frame), inferred.location);
      i.parents = {reference, c.id};
      const auto siblings = static_cast<double>(step.inference.inferred.size());
      AddClosure(i, uncertainty.share_inferred_information ? 1.0 / siblings : 1.0);
    }
    for (const InferredClosure& inferred : step.inference.discarded) {
      Discard(inferred, reference, c.id, DiscardReason::kTotalPath);
    }
    visual_closure_of_frame_[f.frame] = c.id;
  }
  for (const InferredClosure& inferred : step.inference.lost) {
    Discard(inferred, ReferenceClosure(step), -1, step.inference.lost_reason);
  }
  f.inference_pending = step.inference.pending;
  result_.frames.push_back(f);
  return f;
}

LocalizationResult Localize(const Dataset& d, const std::vector<Observation>& observations,
                            const ObservationModel& model, const LocalizationOptions& options) {
  if (observations.size() != d.frames.size()) {
    throw std::invalid_argument("Localize: " + std::to_string(observations.size()) + " observations for " +
                                std::to_string(d.frames.size()) + " frames");
  }
  if (!options.imposed.empty() && static_cast<std::size_t>(options.imposed.rbegin()->first) >= d.frames.size()) {
    throw std::invalid_argument("Localize: a decision is imposed on frame " +
                                std::to_string(options.imposed.rbegin()->first) +
                                ", which is not a frame of the dataset");
  }
  for (const int f : options.vetoed_frames) {
    if (f < 0 || static_cast<std::size_t>(f) >= d.frames.size()) {
      throw std::invalid_argument("Localize: vetoed frame " + std::to_string(f) + " is not a frame of the dataset");
    }
  }
  Localizer localizer(model, options);
  std::vector<std::size_t> sizes;
  for (const auto& o : observations) sizes.push_back(o.words.size());
  std::nth_element(sizes.begin(), sizes.begin() + static_cast<long>(sizes.size() / 2), sizes.end());
  const std::size_t words_median = sizes.empty() ? 0 : sizes[sizes.size() / 2];

  // Odometry and (when present) ground truth at the frame times.
  const std::vector<Pose2> odometry = PosesAtFrames(d, d.odometry), truth = PosesAtFrames(d, d.ground_truth);
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    FrameInput in;
    in.time_s = d.frames[k].timestamp_s;
    in.odometry = odometry[k];
    in.traversal = d.frames[k].traversal;
    if (!truth.empty()) in.truth = truth[k];
    localizer.AddFrame(in, observations[k]);
    if (options.on_progress && (k % 50 == 0 || k + 1 == d.frames.size())) {
      options.on_progress("filter", k + 1, d.frames.size());
    }
  }
  LocalizationResult result = std::move(localizer).TakeResult();
  result.words_per_frame_median = words_median;
  return result;
}

std::string_view ToString(DiscardReason reason) { return NameOf(kDiscardReasonNames, reason); }

}  // namespace catgraph
