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

LocalizationResult Localize(const Dataset& d, const std::vector<Observation>& observations,
                            const ObservationModel& model, const LocalizationOptions& options) {
  const PoseGraphUncertainty& uncertainty = options.graph_uncertainty;
  if (!(uncertainty.odometry_m_per_sqrt_m > 0.0 && uncertainty.odometry_rad_per_sqrt_m > 0.0 &&
        uncertainty.min_distance_m > 0.0 && (uncertainty.closure_sigma.array() > 0.0).all())) {
    throw std::invalid_argument("Localize: every PoseGraphUncertainty field must be > 0");
  }
  if (observations.size() != d.frames.size()) {
    throw std::invalid_argument("Localize: " + std::to_string(observations.size()) + " observations for " +
                                std::to_string(d.frames.size()) + " frames");
  }
  // The aliasing of every frame; the filter's node of frame k is k.
  std::vector<Aliasing> aliasing(d.frames.size());
  std::vector<bool> injected(d.frames.size(), false);
  for (const FalseVisualMatch& m : options.false_matches) {
    auto frame_ok = [&](int f) { return f >= 0 && static_cast<std::size_t>(f) < d.frames.size(); };
    if (!(frame_ok(m.first_frame) && frame_ok(m.last_frame) && frame_ok(m.matched_first_frame) &&
          frame_ok(m.matched_last_frame) && m.first_frame < m.last_frame &&
          m.matched_first_frame < m.first_frame && m.matched_last_frame < m.first_frame)) {
      throw std::invalid_argument("Localize: a false visual match must map frames first < last onto older frames " +
                                  std::string("of the dataset, not ") + std::to_string(m.first_frame) + "-" +
                                  std::to_string(m.last_frame) + " onto " + std::to_string(m.matched_first_frame) +
                                  "-" + std::to_string(m.matched_last_frame));
    }
    for (int f = m.first_frame; f <= m.last_frame; ++f) {
      if (aliasing[static_cast<std::size_t>(f)].withhold_closure) {
        throw std::invalid_argument("Localize: false visual matches overlap at frame " + std::to_string(f));
      }
      aliasing[static_cast<std::size_t>(f)].withhold_closure = true;
    }
    aliasing[static_cast<std::size_t>(m.first_frame)].false_match = m.matched_first_frame;
    aliasing[static_cast<std::size_t>(m.last_frame)].false_match = m.matched_last_frame;
    injected[static_cast<std::size_t>(m.first_frame)] = injected[static_cast<std::size_t>(m.last_frame)] = true;
  }
  for (const int f : options.vetoed_frames) {
    if (f < 0 || static_cast<std::size_t>(f) >= d.frames.size()) {
      throw std::invalid_argument("Localize: vetoed frame " + std::to_string(f) + " is not a frame of the dataset");
    }
    aliasing[static_cast<std::size_t>(f)].vetoed = true;
  }
  CatGraphFilter filter(model, options.filter);
  LocalizationResult result;
  result.options = options;
  result.observation.model = model.Name();
  result.observation.new_place_log_offset = options.filter.new_place_log_offset.value_or(model.NewPlaceLogOffset());
  if (const auto* holistic = dynamic_cast<const HolisticModel*>(&model)) {
    result.observation.holistic = holistic->options();
    result.observation.calibration = holistic->calibration();
  }
  std::vector<std::size_t> sizes;
  for (const auto& o : observations) sizes.push_back(o.words.size());
  std::nth_element(sizes.begin(), sizes.begin() + static_cast<long>(sizes.size() / 2), sizes.end());
  result.words_per_frame_median = sizes.empty() ? 0 : sizes[sizes.size() / 2];

  // Odometry and (when present) ground truth at the frame times.
  const std::vector<Pose2> odometry = PosesAtFrames(d, d.odometry), truth = PosesAtFrames(d, d.ground_truth);
  auto information_of = [](const Eigen::Vector3d& sigma) -> Eigen::Matrix3d {
    return sigma.cwiseProduct(sigma).cwiseInverse().asDiagonal();
  };
  const Eigen::Matrix3d closure_information = information_of(uncertainty.closure_sigma);
  auto odometry_information = [&](const Pose2& step) {
    const double root_d = std::sqrt(std::max(step.translation().norm(), uncertainty.min_distance_m));
    return information_of(Eigen::Vector3d(uncertainty.odometry_m_per_sqrt_m, uncertainty.odometry_m_per_sqrt_m,
                                          uncertainty.odometry_rad_per_sqrt_m) *
                          root_d);
  };
  auto frame_of = [&](int node) { return filter.graph().node(node).frame; };
  auto location_error = [&](std::size_t k, const LocationHypothesis& h) {
    if (truth.empty() || h.edge < 0) return kNoError;
    const GraphEdge& e = filter.graph().edge(h.edge);
    const Pose2& a = truth[static_cast<std::size_t>(frame_of(e.from))];
    const Pose2& b = truth[static_cast<std::size_t>(frame_of(e.to))];
    return (truth[k].translation() - InterpolateTranslation(a, b, h.alpha)).norm();
  };

  std::map<int, int> visual_closure_of_frame;  // frame -> closure id
  // The id of the visual closure a step's inferences hung from (-1: none).
  auto reference_closure = [&](const CatGraphStep& step) {
    const auto found = visual_closure_of_frame.find(step.reference_node >= 0 ? frame_of(step.reference_node) : -1);
    return found == visual_closure_of_frame.end() ? -1 : found->second;
  };
  auto discard = [&](const InferredClosure& inferred, int reference, int validating, DiscardReason reason) {
    const int at = frame_of(inferred.node);
    result.discarded_inferences.push_back({at, frame_of(inferred.matched_node), reference, validating,
                                           location_error(static_cast<std::size_t>(at), inferred.location), reason});
  };
  auto add_closure = [&](const LoopClosure& c, double information_scale = 1.0) {
    result.closures.push_back(c);
    Provenance provenance;
    for (const int parent : c.parents) provenance.parents.push_back(ClosureId(parent));
    result.graph.constraints.push_back({ClosureId(c.id), PoseId(c.frame), PoseId(c.matched_frame),
                                        {c.T_frame_matched, information_scale * closure_information}, c.kind, provenance, {}, {}, {}});
  };
  for (std::size_t k = 0; k < d.frames.size(); ++k) {
    const Pose2 u = k == 0 ? Pose2() : odometry[k - 1].Between(odometry[k]);
    const CatGraphStep step = filter.Step(static_cast<int>(k), d.frames[k].timestamp_s, u, observations[k], aliasing[k]);
    FrameLocalization f;
    f.frame = static_cast<int>(k);
    f.traversal = d.frames[k].traversal;
    f.best = step.best;
    f.new_place_probability = step.new_place_probability;
    f.log_evidence = step.log_evidence;
    f.self_evidence = step.self_evidence;
    if (step.best.edge >= 0) {
      f.edge_from_frame = frame_of(filter.graph().edge(step.best.edge).from);
      f.edge_to_frame = frame_of(filter.graph().edge(step.best.edge).to);
    }
    f.error_m = location_error(k, step.best);

    const PoseId id(static_cast<std::int64_t>(k));
    result.graph.vertices[id] = {id, odometry[k], k == 0};
    if (k > 0) {
      result.graph.constraints.push_back({ClosureId(static_cast<std::int64_t>(result.graph.constraints.size())),
                                          PoseId(static_cast<std::int64_t>(k - 1)), id,
                                          {u, odometry_information(u)}, ClosureKind::kOdometry, {}, {}, {}, {}});
    }
    if (step.closure) {
      f.closure = true;
      f.matched_frame = frame_of(step.matched_node);
      LoopClosure c;
      c.id = static_cast<int>(result.graph.constraints.size());
      c.frame = f.frame;
      c.matched_frame = f.matched_frame;
      c.T_frame_matched = step.T_node_matched;
      c.hypothesis = step.best.value;
      c.error_m = f.error_m;
      c.injected = injected[k];
      c.vetoed = aliasing[k].vetoed;
      add_closure(c);
      // CAT-Graph+: what this visual closure validated or discarded.
      const int reference = reference_closure(step);
      for (const InferredClosure& inferred : step.inferred) {
        LoopClosure i;
        i.id = static_cast<int>(result.graph.constraints.size());
        i.kind = ClosureKind::kOdometryInferred;
        i.frame = frame_of(inferred.node);
        i.matched_frame = frame_of(inferred.matched_node);
        i.T_frame_matched = inferred.T_node_matched;
        i.hypothesis = inferred.location.value;
        i.error_m = location_error(static_cast<std::size_t>(i.frame), inferred.location);
        i.parents = {reference, c.id};
        add_closure(i, uncertainty.share_inferred_information ? 1.0 / static_cast<double>(step.inferred.size()) : 1.0);
      }
      for (const InferredClosure& inferred : step.discarded) discard(inferred, reference, c.id, DiscardReason::kTotalPath);
      visual_closure_of_frame[f.frame] = c.id;
    }
    for (const InferredClosure& inferred : step.lost) discard(inferred, reference_closure(step), -1, step.lost_reason);
    f.inference_pending = step.inference_pending;
    result.frames.push_back(f);
    if (options.on_progress && (k % 50 == 0 || k + 1 == d.frames.size())) {
      options.on_progress("filter", k + 1, d.frames.size());
    }
  }
  return result;
}

std::string_view ToString(DiscardReason reason) { return NameOf(kDiscardReasonNames, reason); }

}  // namespace catgraph
