#include "apps/localization_report.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <utility>

#include "apps/progress_bar.h"
#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "mapping/options_file.h"

namespace catgraph {

// The default vocabulary: trained on the dataset's first traversal (the map),
// never on the traversals that are localised against it.
Vocabulary VocabularyFor(const Dataset& d, const LocalizeCommandOptions& o, std::ostream& out) {
  if (!o.vocabulary.empty()) return Vocabulary::Load(o.vocabulary);
  const ObservationOptions& observation = o.pipeline.observation;
  MapVocabulary v = TrainMapVocabulary(d, observation.vocabulary, observation.train_every);
  out << "trained a " << v.vocabulary.size() << "-word SIFT vocabulary on " << v.frames << " frames of traversal "
      << v.traversal << "\n";
  return std::move(v.vocabulary);
}

FrontEndInputs PrepareFrontEnd(const Dataset& d, LocalizeCommandOptions& o, std::ostream& out) {
  auto features = std::make_shared<ProgressBar>("frames: features");
  auto filter = std::make_shared<ProgressBar>("frames: filter");
  if (!o.quiet) {
    o.pipeline.front_end.on_progress = [features, filter](const char* stage, std::size_t done, std::size_t total) {
      (std::string(stage) == "features" ? features : filter)->Update(done, total);
    };
  }
  FrontEndInputs in;
  if (o.pipeline.observation.model == ObservationKind::kHolistic) {
    HolisticFrontEnd holistic = PrepareHolistic(d, o.pipeline.observation.holistic, o.pipeline.front_end);
    const HolisticCalibration& c = holistic.model->calibration();
    out << "holistic observation model: " << holistic.model->options().width_px << " px templates, calibrated on "
        << c.frames << " frames of the first traversal: M = " << Number(c.identical_score, "%.2f") << "\n";
    in.observations = std::move(holistic.observations);
    in.model = std::move(holistic.model);
    return in;
  }
  const Vocabulary vocabulary = VocabularyFor(d, o, out);
  in.observations = ExtractObservations(d, &vocabulary, nullptr, o.pipeline.front_end);
  in.model = std::make_unique<FabMapModel>(vocabulary.tree(), o.pipeline.observation.fabmap);
  return in;
}

LocalizationResult RunLocalization(const Dataset& d, LocalizeCommandOptions& o, std::ostream& out) {
  const FrontEndInputs in = PrepareFrontEnd(d, o, out);
  return Localize(d, in.observations, *in.model, o.pipeline.front_end);
}

nlohmann::ordered_json ObservationJson(const ObservationSummary& o) {
  nlohmann::ordered_json j{{"model", o.model}, {"new_place_log_offset", o.new_place_log_offset}};
  if (o.holistic) {
    j["template_width_px"] = o.holistic->width_px;
    j["max_shift_fraction"] = o.holistic->max_shift_fraction;
    j["reference_places"] = o.holistic->reference_places;
  }
  if (o.calibration) {
    j["calibration"] = {{"identical_score", o.calibration->identical_score},
                        {"frames", o.calibration->frames},
                        {"offset_m", o.calibration->offset_m}};
  }
  return j;
}

plot::Series WallsSeries(const Dataset& d, std::string label, plot::Color color, double width_pt) {
  plot::Series walls{std::move(label), {}, {}, plot::SeriesStyle::kSegments, color, width_pt};
  for (const auto& w : d.meta.walls) {
    walls.x.insert(walls.x.end(), {w[0], w[2]});
    walls.y.insert(walls.y.end(), {w[1], w[3]});
  }
  return walls;
}

// The CAT-Graph+ paper's Figs. 7 and 8: the best hypothesis of every frame,
// and the error of every visual and odometry-inferred closure, against the
// frame index, with the frames that see a changed region marked.
plot::Figure LocalizationFigure(const Dataset& d, const LocalizationResult& r, double threshold) {
  plot::Figure figure;
  figure.rows = 2;
  figure.width_px = 1100;
  figure.height_px = 820;
  plot::Series changed{"frames that see a changed region", {}, {}, plot::SeriesStyle::kSegments,
                       plot::kChangedRegionColor, 4.0};
  plot::Series hypothesis{"best hypothesis", {}, {}, plot::SeriesStyle::kLine, plot::kTrajectoryColor, 0.8};
  plot::Series closed{"visual closure", {}, {}, plot::SeriesStyle::kMarkers, plot::kVisualClosureColor, 2.0};
  plot::Series error = closed;
  plot::Series best_error{"best hypothesis, no closure", {}, {}, plot::SeriesStyle::kMarkers,
                          {0.6, 0.6, 0.6, 0.6}, 1.0};
  for (const auto& h : r.frames) {
    const double k = h.frame;
    if (d.frames[static_cast<std::size_t>(h.frame)].changed) {
      changed.x.insert(changed.x.end(), {k - 0.5, k + 0.5});
      changed.y.insert(changed.y.end(), {-0.04, -0.04});
    }
    hypothesis.x.push_back(k);
    hypothesis.y.push_back(h.best.value);
    if (h.closure) {
      closed.x.push_back(k);
      closed.y.push_back(h.best.value);
    }
    if (std::isnan(h.error_m)) continue;
    (h.closure ? error : best_error).x.push_back(k);
    (h.closure ? error : best_error).y.push_back(h.error_m);
  }
  plot::Series inferred{"odometry-inferred closure", {}, {}, plot::SeriesStyle::kMarkers,
                        plot::kInferredClosureColor, 2.0};
  for (const auto& c : r.closures) {
    if (c.kind != ClosureKind::kOdometryInferred || std::isnan(c.error_m)) continue;
    inferred.x.push_back(c.frame);
    inferred.y.push_back(c.error_m);
  }
  const double frames = static_cast<double>(r.frames.size());
  char threshold_label[64];
  std::snprintf(threshold_label, sizeof threshold_label, "closure threshold T_h = %g", threshold);
  plot::Series t_h{threshold_label, {0.0, frames}, {threshold, threshold}, plot::SeriesStyle::kLine,
                   {0.3, 0.3, 0.3, 1.0}, 1.0, true};
  // Both panels span the same frames, so that they line up.
  auto frame_axes = [frames](std::string title, std::string y_label) {
    plot::Axes axes;
    axes.title = std::move(title);
    axes.x_label = "frame";
    axes.y_label = std::move(y_label);
    axes.x_min = 0.0;
    axes.x_max = std::max(frames - 1.0, 1.0);
    return axes;
  };
  plot::Axes top = frame_axes("Best location hypothesis per frame: particle weight near the best place",
                              "hypothesis (0 to 1)");
  top.y_min = -0.08;
  top.y_max = 1.05;
  top.series = {changed, hypothesis, t_h, closed};
  plot::Axes bottom = frame_axes("Distance from the true place", "error (m), log(1 + error) scale");
  bottom.y_scale = plot::Scale::kSymlog;
  changed.y.assign(changed.y.size(), 0.0);
  bottom.series = {changed, best_error, error};
  if (!inferred.x.empty()) bottom.series.push_back(inferred);
  figure.axes = {top, bottom};
  return figure;
}

std::string Number(double value, const char* format) {
  if (std::isnan(value)) return "";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, format, value);
  return buffer;
}

nlohmann::ordered_json ClosureJson(const LoopClosure& c) {
  nlohmann::ordered_json j{{"id", c.id},
                           {"frame", c.frame},
                           {"matched_frame", c.matched_frame},
                           {"kind", ToString(c.kind)},
                           {"hypothesis", c.hypothesis},
                           {"relative_pose", {c.T_frame_matched.x(), c.T_frame_matched.y(), c.T_frame_matched.theta()}}};
  j["error_m"] = std::isnan(c.error_m) ? nlohmann::ordered_json() : nlohmann::ordered_json(c.error_m);
  if (c.kind == ClosureKind::kOdometryInferred) j["parents"] = c.parents;
  if (c.injected) j["injected"] = true;
  if (c.vetoed) j["vetoed"] = true;
  return j;
}

OutputDirectory OpenOutputDirectory(const LocalizeCommandOptions& o, const std::string& command) {
  std::vector<std::filesystem::path> inputs = {o.dataset};
  if (!o.vocabulary.empty()) inputs.emplace_back(o.vocabulary);
  return OutputDirectory(o.output, command, o.overwrite, inputs);
}

void WriteLocalization(const std::filesystem::path& dir, const Dataset& d, const LocalizationResult& r,
                       double closure_threshold) {
  CreateDirectories(dir, "output directory");
  WriteFileAtomically(dir / "hypotheses.csv", [&](std::ostream& f) {
    f << "frame,traversal,edge_from_frame,edge_to_frame,alpha,direction,hypothesis,new_place,closure,"
         "matched_frame,error_m,inference_pending,log_evidence,self_evidence\n";
    for (const auto& h : r.frames) {
      f << h.frame << ',' << h.traversal << ',' << h.edge_from_frame << ',' << h.edge_to_frame << ','
        << Number(h.best.alpha) << ',' << h.best.direction << ',' << Number(h.best.value) << ','
        << Number(h.new_place_probability) << ',' << (h.closure ? 1 : 0) << ',' << h.matched_frame << ','
        << Number(h.error_m) << ',' << (h.inference_pending ? 1 : 0) << ',' << Number(h.log_evidence) << ','
        << Number(h.self_evidence) << '\n';
    }
  });
  nlohmann::ordered_json closures = nlohmann::ordered_json::array();
  for (const auto& c : r.closures) closures.push_back(ClosureJson(c));
  nlohmann::ordered_json discarded = nlohmann::ordered_json::array();
  for (const auto& x : r.discarded_inferences) {
    nlohmann::ordered_json j{{"frame", x.frame},
                             {"matched_frame", x.matched_frame},
                             {"reference_closure", x.reference_closure},
                             {"validating_closure", x.validating_closure}};
    j["error_m"] = std::isnan(x.error_m) ? nlohmann::ordered_json() : nlohmann::ordered_json(x.error_m);
    j["reason"] = ToString(x.reason);
    discarded.push_back(j);
  }
  WriteFileAtomically(dir / "discarded_inferences.json", [&](std::ostream& f) { f << discarded.dump(1) << '\n'; });
  WriteFileAtomically(dir / "closures.json", [&](std::ostream& f) { f << closures.dump(1) << '\n'; });
  WriteFileAtomically(dir / "observation.json",
                      [&](std::ostream& f) { f << ObservationJson(r.observation).dump(1) << '\n'; });
  WriteG2oFile(AnyPoseGraph(r.graph), dir / "graph.g2o");
  const plot::Figure figure = LocalizationFigure(d, r, closure_threshold);
  plot::SaveFigure(figure, dir / "localization.png");
  plot::SaveFigure(figure, dir / "localization.svg");

}

void PrintLocalizationSummary(const Dataset& d, const LocalizationResult& r, bool odometric_inference,
                              std::ostream& out) {
  out << r.frames.size() << " frames (median " << r.words_per_frame_median << " words per frame)\n";
  std::vector<bool> inferred_at(d.frames.size(), false);
  for (const ClosureKind kind : {ClosureKind::kVisual, ClosureKind::kOdometryInferred}) {
    double sum = 0.0, worst = 0.0;
    int count = 0, with_error = 0;
    for (const auto& c : r.closures) {
      if (c.kind != kind) continue;
      ++count;
      if (kind == ClosureKind::kOdometryInferred) inferred_at[static_cast<std::size_t>(c.frame)] = true;
      if (std::isnan(c.error_m)) continue;
      sum += c.error_m;
      worst = std::max(worst, c.error_m);
      ++with_error;
    }
    out << count << (kind == ClosureKind::kVisual ? " visual closures" : " odometry-inferred closures");
    if (with_error > 0) {
      out << ", error mean " << Number(sum / with_error, "%.3f") << " m, max " << Number(worst, "%.3f") << " m";
    }
    out << '\n';
  }
  if (odometric_inference) {
    const auto by_total_path = TotalPathDiscards(r);
    out << by_total_path << " inferences discarded by total-path validation";
    if (r.discarded_inferences.size() > by_total_path) {
      out << ", " << r.discarded_inferences.size() - by_total_path
          << " dropped before a visual closure could validate them";
    }
    out << '\n';
  }
  // Per traversal: how many frames closed, inside and outside the regions
  // that changed (when the dataset flags them).
  struct Counts {
    int frames = 0, visual = 0, inferred = 0;
  };
  std::map<int, std::array<Counts, 2>> counts;  // traversal -> outside, inside changed regions
  for (const auto& h : r.frames) {
    const auto k = static_cast<std::size_t>(h.frame);
    Counts& c = counts[h.traversal][d.frames[k].changed ? 1 : 0];
    ++c.frames;
    c.visual += h.closure ? 1 : 0;
    c.inferred += inferred_at[k] ? 1 : 0;
  }
  auto describe = [&](const Counts& c) {
    std::string text = std::to_string(c.visual) + " of " + std::to_string(c.frames) + " frames closed visually (" +
                       Number(100.0 * c.visual / std::max(1, c.frames), "%.1f") + " %)";
    if (odometric_inference) {
      text += ", " + std::to_string(c.inferred) + " by inference (" +
              Number(100.0 * c.inferred / std::max(1, c.frames), "%.1f") + " %)";
    }
    return text;
  };
  for (const auto& [traversal, c] : counts) {
    out << "traversal " << traversal << ": ";
    if (c[1].frames == 0) {
      out << describe(c[0]) << '\n';
    } else {
      out << "outside changed regions " << describe(c[0]) << "; inside " << describe(c[1]) << '\n';
    }
  }
}

void AddFalseMatchOptions(CLI::App& cmd, FalseMatchOptions& o) {
  cmd.add_option("--false-stretch", o.stretch_m, "Path length of each false match's stretch (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd.add_option("--false-min-error", o.min_error_m, "A false match is at least this far from the truth (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd.add_option("--false-max-error", o.max_error_m, "... and at most this far (m)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

void AddVocabularyOptions(CLI::App& cmd, LocalizeCommandOptions& o) {
  ObservationOptions& observation = o.pipeline.observation;
  cmd.add_option_function<std::string>(
         "--observation",
         [&observation](const std::string& name) {
           const std::optional<ObservationKind> kind = ObservationKindFromString(name);
           if (!kind) throw CLI::ValidationError("--observation", "expected fabmap or holistic, not '" + name + "'");
           observation.model = *kind;
         },
         "Observation model: holistic (whole-image templates, calibrated on the first traversal) or fabmap "
         "(bag of words on a vocabulary). docs/frontend.md \"Observation models\"")
      ->default_str(std::string(ToString(observation.model)));
  cmd.add_option("--vocabulary", o.vocabulary,
                 "Vocabulary file (catgraph vocabulary train); default: train one on the first traversal");
  o.option_fields.emplace_back(
      cmd.add_option("--words", observation.vocabulary.words, "Words of the default vocabulary")->capture_default_str(),
      "vocabulary.words");
  o.option_fields.emplace_back(
      cmd.add_option("--train-every", observation.train_every,
                     "Default vocabulary: every N-th frame of the first traversal (0: about 200 frames)")
          ->capture_default_str(),
      "train_every");
}

namespace {

std::string FormatSigma(const Eigen::Vector3d& sigma) {
  std::ostringstream text;
  text << sigma.x() << ' ' << sigma.y() << ' ' << sigma.z();
  return text.str();
}

// An option of three numbers (σx σy in m, σθ in rad).
CLI::Option* AddSigmaOption(CLI::App& cmd, const std::string& name, const std::string& default_text,
                            const std::string& description, std::function<void(const Eigen::Vector3d&)> set) {
  return cmd
      .add_option_function<std::vector<double>>(
          name, [set](const std::vector<double>& s) { set(Eigen::Vector3d(s[0], s[1], s[2])); }, description)
      ->expected(3)
      ->default_str(default_text);
}

}  // namespace

void AddLocalizationOptions(CLI::App& cmd, LocalizeCommandOptions& o, const std::vector<std::string>& shown) {
  const std::size_t command_options = cmd.get_options().size();  // the command's own stay listed
  // Before every other option, so that their callbacks run first and the
  // flags given override the preset and the file.
  cmd.add_option_function<std::string>(
         "--preset",
         [&o](const std::string& name) {
           const std::optional<mapping::OptionsPreset> preset = mapping::OptionsPresetFromString(name);
           if (!preset) throw CLI::ValidationError("--preset", "expected default or paper, not '" + name + "'");
           o.pipeline = mapping::PresetOptions(*preset);
         },
         "Where the options start: default, or paper (the CAT-Graph+ paper's filter exactly: Table I and the "
         "spec, none of catgraph's additions). docs/frontend.md \"Options\"")
      ->default_str("default");
  cmd.add_option_function<std::string>(
         "--options", [&o](const std::string& path) { mapping::ReadOptionsFile(path, o.pipeline); },
         "YAML file of options (any subset; the options.yaml a run writes is one), read over the preset; the "
         "flags given override it. docs/file-formats.md \"Options files\"");
  CatGraphOptions& f = o.pipeline.front_end.filter;
  AddVocabularyOptions(cmd, o);
  // A flag that sets a library option: the field it sets, as Validate names it.
  auto field = [&o](CLI::Option* option, std::string name) {
    o.option_fields.emplace_back(option, std::move(name));
    return option;
  };
  field(cmd.add_option("--particles", f.num_particles, "n_p"), "num_particles")->capture_default_str();
  field(cmd.add_option("--closure-threshold", f.closure_threshold, "T_h"), "closure_threshold")->capture_default_str();
  field(cmd.add_option("--closure-min-evidence", f.recognition.closure_min_evidence,
                       "A visual closure also needs the frame's evidence to be this fraction of its self-evidence or "
                       "more (0: T_h alone, the spec). docs/frontend.md \"Closing on what the camera sees\""),
        "recognition.closure_min_evidence")
      ->capture_default_str();
  field(cmd.add_option("--hypothesis-radius", f.hypothesis_radius_m, "d_h (m)"), "hypothesis_radius_m")
      ->capture_default_str();
  field(AddSigmaOption(cmd, "--motion-sigma", FormatSigma(f.motion_sigma),
                       "Q = diag(σ)²: the motion noise per frame, along, across (m) and in heading (rad)",
                       [&f](const Eigen::Vector3d& s) { f.motion_sigma = s; }),
        "motion_sigma");
  field(cmd.add_option("--new-place-prior", f.new_place_prior, "p_new while in a new place"), "new_place_prior")
      ->capture_default_str();
  field(cmd.add_option("--leave-probability", f.new_place.leave_probability, "Prior of new place while on the map"),
        "new_place.leave_probability")
      ->capture_default_str();
  field(cmd.add_option_function<double>(
            "--new-place-offset", [&f](double offset) { f.new_place.log_offset = offset; },
            "Added to log p(z | new place), in the observation model's nats (0: the spec as written)"),
        "new_place.log_offset")
      ->default_str("the model's: fabmap 45, holistic 0");
  field(cmd.add_option("--new-place-stay-fraction", f.new_place.stay_fraction,
                       "What staying on the map costs, once on it, as a fraction of the offset, which is what "
                       "entering it costs. docs/frontend.md \"Staying on the map\""),
        "new_place.stay_fraction")
      ->capture_default_str();
  field(cmd.add_option("--observation-window", f.recognition.observation_window_m,
                       "Eq 2 over a stretch of path: a node's likelihood is the mean over the nodes within this many "
                       "metres of path either side (0: its own, the spec). docs/frontend.md \"What stays and what "
                       "changes\""),
        "recognition.observation_window_m")
      ->capture_default_str();
  field(cmd.add_option("--new-place-stay-relative-offset", f.new_place.stay_relative_offset,
                       "Staying on the map also costs this fraction of the frame's self-evidence (at most what "
                       "entering costs). docs/frontend.md \"Staying on the map\""),
        "new_place.stay_relative_offset")
      ->capture_default_str();
  field(AddSigmaOption(cmd, "--new-place-motion-sigma",
                       f.new_place.motion_sigma ? FormatSigma(*f.new_place.motion_sigma) : "Q's",
                       "Eq 6's σ (m, m, rad): the scale a new place's odometry is weighed on against its mean. "
                       "docs/frontend.md \"Corners and Q\"",
                       [&f](const Eigen::Vector3d& s) { f.new_place.motion_sigma = s; }),
        "new_place.motion_sigma");
  cmd.add_flag("--no-heading-likelihood", [&f](std::int64_t) { f.heading_in_position_likelihood = false; },
               "Eq 1 on position alone (spec §6.4 (a)): Q's heading term still spreads the particles but weighs "
               "none. docs/frontend.md \"Closing on what the camera sees\"");
  cmd.add_flag("--hold-after-closure,!--no-hold-after-closure", f.new_place.hold_after_closure,
               "Hold the robot on the map (leave probability, stay credit) only once the cloud has made a visual "
               "closure since it came onto the map (the default; --no-hold-after-closure: any mass on the map "
               "holds it). docs/frontend.md \"Held after a closure\"");
  cmd.add_flag("--no-odometric-gate", [&f](std::int64_t) { f.gate.enabled = false; },
               "Let particles onto nodes that dead reckoning rules out");
  field(cmd.add_option("--gate-base", f.gate.base_m, "Odometric gate: base (m)"), "gate.base_m")->capture_default_str();
  field(cmd.add_option("--gate-fraction", f.gate.fraction, "Odometric gate: fraction of the path since the node"),
        "gate.fraction")
      ->capture_default_str();
  cmd.add_flag("--no-odometric-inference", [&f](std::int64_t) { f.inference.enabled = false; },
               "CAT-Graph alone: no odometry-inferred closures (CAT-Graph+ is the default)");
  field(cmd.add_option("--d-loc", f.inference.local_validation_m, "CAT-Graph+ local validation d_loc (m)"),
        "inference.local_validation_m")
      ->capture_default_str();
  field(cmd.add_option("--d-tot", f.inference.total_validation_m, "CAT-Graph+ total-path validation d_tot (m)"),
        "inference.total_validation_m")
      ->capture_default_str();
  field(cmd.add_option("--total-path-retries", f.inference.total_path_retries,
                       "CAT-Graph+: carry the pending inferences past this many visual closures in a row that they "
                       "fail total-path validation against (0: the spec). docs/catgraph-plus.md \"A chain against a "
                       "false closure\""),
        "inference.total_path_retries")
      ->capture_default_str();
  field(cmd.add_option("--odometric-particle-factor", f.inference.particle_factor,
                       "CAT-Graph+: the odometric filter starts from this many copies of each visual particle (1: "
                       "the spec's copy of the visual filter)"),
        "inference.particle_factor")
      ->capture_default_str();
  field(AddSigmaOption(cmd, "--odometric-motion-sigma", "--motion-sigma's",
                       "CAT-Graph+: the odometric filter's Q, σ per frame (m, m, rad). docs/catgraph-plus.md \"O's "
                       "along-track wander\"",
                       [&f](const Eigen::Vector3d& s) { f.inference.motion_sigma = s; }),
        "inference.motion_sigma");
  cmd.add_flag("--odometric-seed-all", [&f](std::int64_t) { f.inference.seed_local = false; },
               "CAT-Graph+: the odometric filter starts from every visual particle (the spec), not only those within "
               "d_h of the visual match");
  cmd.add_flag("--panoramic", [&f](std::int64_t) { f.recognition.forward_camera = false; },
               "The camera sees all round: particles facing either way use the nodes' words, and either way they close "
               "(a forward camera facing against the nodes makes no visual closure)");
  field(cmd.add_option("--exclusion-s", f.exclusion_window_s, "Self-match exclusion window (s)"), "exclusion_window_s")
      ->capture_default_str();
  field(cmd.add_option("--exclusion-m", f.exclusion_window_m, "Self-match exclusion window (m of path)"),
        "exclusion_window_m")
      ->capture_default_str();
  cmd.add_option("--seed", f.seed, "Filter seed")->capture_default_str();
  // Out of --help, yet named in errors (an option of the empty group, CLI11's
  // hidden one, has no name there).
  class Formatter : public CLI::Formatter {
   public:
    std::string make_group(std::string group, bool is_positional, std::vector<const CLI::Option*> opts) const override {
      return group == kUnlistedGroup ? std::string() : CLI::Formatter::make_group(group, is_positional, opts);
    }
  };
  cmd.formatter(std::make_shared<Formatter>());
  cmd.footer("Every other option is a key of --options FILE (docs/file-formats.md \"Options files\"); the flags "
             "that also set some of them are listed in docs/cli.md.");
  const std::vector<CLI::Option*> options = cmd.get_options();
  for (std::size_t i = command_options; i < options.size(); ++i) {
    const std::string& name = options[i]->get_name();
    if (name != "--preset" && name != "--options" && std::find(shown.begin(), shown.end(), name) == shown.end()) {
      options[i]->group(kUnlistedGroup);
    }
  }
}

void ValidateOptions(const LocalizeCommandOptions& o) {
  try {
    mapping::Validate(o.pipeline);
  } catch (const std::invalid_argument& e) {
    // The flags given, by the field each sets.
    std::map<std::string, const CLI::Option*> given;
    for (const auto& [option, name] : o.option_fields) {
      if (option->count() > 0) given.emplace(name, option);
    }
    std::vector<std::string> fields;
    for (const auto& [name, option] : given) fields.push_back(name);
    const auto named = given.find(mapping::FieldNamedBy(e.what(), fields));
    if (named != given.end()) throw CLI::ValidationError(named->second->get_name(), e.what());
    throw;
  }
}

void WriteOptions(const std::filesystem::path& dir, const LocalizeCommandOptions& o) {
  WriteFileAtomically(dir / "options.yaml", [&o](std::ostream& out) {
    out << "# catgraph: the options of this run; catgraph localize|map --options options.yaml runs it again.\n"
        << mapping::OptionsYaml(o.pipeline);
  });
}

}  // namespace catgraph
