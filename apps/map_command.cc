// catgraph map DATASET -o OUT/ [--hierarchy cascade|coupled|flat] [--method M]
//
// The whole pipeline: vocabulary, CAT-Graph and CAT-Graph+, the pose graph
// (odometry, visual and inferred closures), the robust solve under the
// closure hierarchy, then the corrected graph, the trajectory, report.json,
// the CAT-Graph+ paper's figures and an index.html. docs/mapping.md.
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "mapping/map_dataset.h"
#include "apps/plot/graph_figure.h"
#include "backend/evaluation.h"
#include "backend/graph/trajectory.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"
#include "backend/pose_graph_optimizer.h"
#include "hierarchy/closure_hierarchy.h"

namespace catgraph {

using mapping::InjectionOutcome;
using mapping::KindCounts;
using mapping::MapOutcome;
using mapping::MappingResult;
using mapping::SolveWithFeedback;
using mapping::TruthAtFrames;
using mapping::kDefaultFeedbackReruns;
namespace {

struct MapCommandOptions {
  LocalizeCommandOptions front;  // every library option in front.pipeline
  FalseMatchOptions injection;  // its seed is the filter's
  std::vector<FalseVisualMatch> false_matches;  // planned by RunMap from `injection`
  int feedback_reruns = kDefaultFeedbackReruns;
};

// `estimate` moved by the rigid transform the ATE aligns it with, so that
// the picture shows the error the report gives; unchanged without truth.
Trajectory2 Aligned(const Trajectory2& estimate, const Trajectory2& truth) {
  if (truth.empty() || estimate.size() < 2) return estimate;
  const Pose2 align = AlignmentOnto(estimate, truth);
  Trajectory2 aligned;
  for (const auto& [id, pose] : estimate) aligned.emplace_hint(aligned.end(), id, align * pose);
  return aligned;
}

// The CAT-Graph+ paper's Fig. 10: odometry alone beside the corrected map
// with its loop closures (graph_figure.h's colours and thinning), each
// aligned to the ground truth as the ATE is, over the floor plan when the
// dataset has one.
plot::Figure MapFigure(const Dataset& d, const PoseGraph2& front, const PoseGraph2& corrected,
                       const Trajectory2& truth) {
  const plot::Series walls = WallsSeries(d, "", plot::kWallColor, 0.6);
  auto panel = [&](const std::string& title, const PoseGraph2& graph, bool closures) {
    plot::Axes axes;
    axes.title = title;
    axes.x_label = "x (m)";
    axes.y_label = "y (m)";
    axes.equal_aspect = true;
    if (!walls.x.empty()) axes.series.push_back(walls);
    const Trajectory2 poses = Aligned(TrajectoryOf(graph), truth);
    if (closures) {
      for (plot::Series& s : plot::ClosureSeries(graph, poses)) axes.series.push_back(std::move(s));
    }
    if (!truth.empty()) axes.series.push_back(plot::PathSeries("ground truth", truth, plot::kTruthColor, 0.8));
    axes.series.push_back(plot::PathSeries(truth.empty() ? "trajectory" : "trajectory (aligned to the truth)", poses,
                                           plot::kTrajectoryColor, 1.2));
    return axes;
  };
  plot::Figure figure;
  figure.cols = 2;
  figure.width_px = 1200;
  figure.height_px = 680;
  figure.axes = {panel("odometry alone", front, false), panel("corrected map", corrected, true)};
  return figure;
}

nlohmann::ordered_json AteJson(const std::optional<TrajectoryEvaluation>& e) {
  if (!e) return nullptr;
  return {{"rmse_m", e->ate_m.rmse}, {"mean_m", e->ate_m.mean}, {"median_m", e->ate_m.median},
          {"max_m", e->ate_m.max}, {"rmse_anchored_m", e->rmse_anchored_m}};
}

std::string HtmlEscape(const std::string& text) {
  std::string out;
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

void RunMap(MapCommandOptions& o, std::ostream& out) {
  ValidateOptions(o.front);
  const PoseGraphOptimizerOptions& optimizer = o.front.pipeline.back_end;
  const HierarchyOptions& hierarchy_options = o.front.pipeline.hierarchy;
  const std::string method(ToString(optimizer.method)), hierarchy(ToString(hierarchy_options.policy));
  OutputDirectory output = OpenOutputDirectory(o.front, "map");
  const Dataset d = ReadDataset(o.front.dataset);
  const std::filesystem::path& dir = output.path();
  o.injection.seed = o.front.pipeline.front_end.filter.seed;
  o.false_matches = PlanFalseVisualMatches(d, o.front.pipeline.front_end.filter, o.injection);
  o.front.pipeline.front_end.imposed = ImposedDecisions(o.false_matches);

  out << "[1/3] front end: CAT-Graph" << (o.front.pipeline.front_end.filter.inference.enabled ? "+" : "") << " on "
      << d.frames.size() << " frames";
  if (o.injection.count > 0) out << ", " << o.injection.count << " false visual matches injected";
  out << "\n";
  const FrontEndInputs inputs = PrepareFrontEnd(d, o.front, out);
  LocalizationResult first = Localize(d, inputs.observations, *inputs.model, o.front.pipeline.front_end);
  PrintLocalizationSummary(d, first, o.front.pipeline.front_end.filter.inference.enabled, out);

  out << "[2/3] back end: " << method << " with the " << hierarchy << " hierarchy on "
      << first.graph.vertices.size() << " poses and " << first.closures.size() << " closures\n";
  const Trajectory2 truth = TruthAtFrames(d);
  const MappingResult fed = SolveWithFeedback(d, inputs.observations, *inputs.model, std::move(first), optimizer,
                                         hierarchy_options, truth, o.feedback_reruns);
  const LocalizationResult& r = fed.front;
  const MapOutcome& m = fed.outcome;
  std::vector<int> vetoed_frames;
  for (const LoopClosure& c : r.closures) {
    if (c.vetoed) vetoed_frames.push_back(c.frame);
  }
  if (fed.reruns > 0) {
    out << "feedback: CAT-Graph+ re-run " << fed.reruns << (fed.reruns == 1 ? " time" : " times") << " with the "
        << vetoed_frames.size() << " rejected visual closures vetoed; now "
        << m.by_kind.at(ClosureKind::kOdometryInferred).count << " inferred closures (were "
        << fed.first.by_kind.at(ClosureKind::kOdometryInferred).count << ")\n";
  }
  WriteLocalization(dir, d, r, o.front.pipeline.front_end.filter.closure_threshold);
  const HierarchicalOptimization& solved = m.solved;
  const PoseGraphOptimization& result = solved.optimization;
  const PoseGraph2& corrected = std::get<PoseGraph2>(result.graph);
  out << solved.solves << (solved.solves == 1 ? " solve" : " solves") << " in " << Number(solved.time_s, "%.2f")
      << " s; " << result.accepted << " closures accepted, " << result.rejected << " rejected";
  if (hierarchy_options.policy == HierarchyPolicy::kFlat) {
    out << "; " << solved.surviving_children.size() << " children of rejected parents survive\n";
  } else {
    out << " (" << solved.turned_off.size() << " turned off by the hierarchy)\n";
  }
  // What the hierarchy did to the false closures' children: the first solve
  // (after feedback the false closures are vetoed and have none).
  const InjectionOutcome& injection = fed.first.injection;
  if (o.injection.count > 0) {
    out << "injected: " << injection.parents_rejected << " of " << injection.parents
        << " false visual closures rejected; " << injection.children_accepted << " of their " << injection.children
        << " inferred children accepted, " << injection.children_of_rejected_accepted << " of them children of a "
        << "rejected one\n";
  }

  out << "[3/3] outputs\n";
  WriteG2oFile(result.graph, dir / "corrected.g2o");
  WriteG2oFile(DropRejected(result.graph, result.closures), dir / "corrected_accepted.g2o");
  // TUM with the frames' times, so that evo pairs the map with the truth:
  // evo_ape tum groundtruth.tum trajectory.tum -a
  std::map<PoseId, double> frame_times;
  for (std::size_t i = 0; i < d.frames.size(); ++i) frame_times.emplace(PoseId(i), d.frames[i].timestamp_s);
  WriteTumFile(AnyTrajectory(TrajectoryOf(corrected)), dir / "trajectory.tum", &frame_times);
  if (!truth.empty()) WriteTumFile(AnyTrajectory(truth), dir / "groundtruth.tum", &frame_times);

  // report.json: the headline numbers, then every closure.
  std::map<ClosureId, SwitchId> switch_of;
  for (const auto& c : corrected.constraints) {
    if (c.switch_id) switch_of.emplace(c.id, *c.switch_id);
  }
  // null when there is nothing to give (no switch, no ground truth, ...).
  auto optional_number = [](bool present, double value) {
    return present ? nlohmann::ordered_json(value) : nlohmann::ordered_json();
  };
  nlohmann::ordered_json closures = nlohmann::ordered_json::array();
  for (const LoopClosure& c : r.closures) {
    const ClosureDecision& decision = m.decision_of.at(ClosureId(c.id));
    nlohmann::ordered_json j = ClosureJson(c);
    const auto switch_id = switch_of.find(decision.id);
    j["switch"] = switch_id == switch_of.end() ? nlohmann::ordered_json()
                                               : nlohmann::ordered_json(corrected.switches.at(switch_id->second).value);
    j["weight"] = decision.weight;
    j["accepted"] = decision.accepted;
    const auto off = m.turned_off_by.find(decision.id);
    j["turned_off_by"] = off == m.turned_off_by.end() ? nlohmann::ordered_json() : nlohmann::ordered_json(off->second.value());
    closures.push_back(j);
  }
  nlohmann::ordered_json kinds = nlohmann::ordered_json::object();
  for (const ClosureKind kind : {ClosureKind::kVisual, ClosureKind::kOdometryInferred}) {
    const KindCounts& k = m.by_kind.at(kind);
    kinds[std::string(ToString(kind))] = {
        {"count", k.count},
        {"accepted", k.accepted},
        {"rejected", k.count - k.accepted},
        {"error_mean_m", optional_number(!k.errors.empty(), k.all.mean)},
        {"error_max_m", optional_number(!k.errors.empty(), k.all.max)},
        {"accepted_error_max_m", optional_number(!k.accepted_errors.empty(), k.kept.max)}};
  }
  auto decisions_json = [](const std::vector<HierarchyDecision>& list) {
    nlohmann::ordered_json a = nlohmann::ordered_json::array();
    for (const HierarchyDecision& h : list) {
      a.push_back({{"child", h.child.value()}, {"parent", h.parent.value()}, {"round", h.round}});
    }
    return a;
  };
  nlohmann::ordered_json report{{"dataset", o.front.dataset},
                                {"frames", d.frames.size()},
                                {"method", method},
                                {"hierarchy", hierarchy},
                                {"observation", ObservationJson(r.observation)},
                                {"odometric_inference", o.front.pipeline.front_end.filter.inference.enabled},
                                {"solves", solved.solves},
                                {"time_s", solved.time_s},
                                {"iterations", result.summary.iterations},
                                {"chi2", result.chi2},
                                {"accepted", result.accepted},
                                {"rejected", result.rejected},
                                {"closures_by_kind", kinds},
                                {"ate_odometry", AteJson(m.ate_odometry)},
                                {"ate_corrected", AteJson(m.ate_corrected)},
                                {"turned_off", decisions_json(solved.turned_off)},
                                {"surviving_children", decisions_json(solved.surviving_children)},
                                {"feedback", {{"reruns", fed.reruns}, {"vetoed_frames", vetoed_frames}}}};
  if (o.injection.count > 0) {
    nlohmann::ordered_json matches = nlohmann::ordered_json::array();
    for (const FalseVisualMatch& f : o.false_matches) {
      matches.push_back({{"first_frame", f.first_frame},
                         {"last_frame", f.last_frame},
                         {"matched_first_frame", f.matched_first_frame},
                         {"matched_last_frame", f.matched_last_frame}});
    }
    const ErrorStatistics child_errors = StatisticsOf(injection.accepted_child_errors);
    report["injected_false_visual"] = {
        {"count", o.injection.count},
        {"seed", o.injection.seed},
        {"matches", matches},
        {"false_closures", injection.parents},
        {"false_closures_rejected", injection.parents_rejected},
        {"children", injection.children},
        {"children_accepted", injection.children_accepted},
        {"children_of_rejected", injection.children_of_rejected},
        {"children_of_rejected_accepted", injection.children_of_rejected_accepted},
        {"children_turned_off", injection.children_turned_off},
        {"accepted_children_error_max_m",
         optional_number(!injection.accepted_child_errors.empty(), child_errors.max)}};
  }
  report["closures"] = closures;
  WriteFileAtomically(dir / "report.json", [&](std::ostream& f) { f << report.dump(1) << '\n'; });
  WriteOptions(dir, o.front);

  const plot::Figure map = MapFigure(d, r.graph, corrected, truth);
  plot::SaveFigure(map, dir / "map.png");
  plot::SaveFigure(map, dir / "map.svg");

  // index.html: the pictures and the headline numbers.
  std::ostringstream headline;
  for (const ClosureKind kind : {ClosureKind::kVisual, ClosureKind::kOdometryInferred}) {
    const KindCounts& k = m.by_kind.at(kind);
    headline << "<tr><td>" << ToString(kind) << " closures</td><td>" << k.count << " (" << k.accepted
             << " accepted)";
    if (!k.errors.empty()) {
      headline << ", error mean " << Number(k.all.mean, "%.3f") << " m, max " << Number(k.all.max, "%.3f") << " m";
    }
    headline << "</td></tr>\n";
  }
  headline << "<tr><td>turned off by the hierarchy</td><td>" << solved.turned_off.size() << "</td></tr>\n";
  if (o.injection.count > 0) {
    headline << "<tr><td>injected false visual closures</td><td>" << injection.parents << " ("
             << injection.parents_rejected << " rejected); their inferred children " << injection.children << " ("
             << injection.children_accepted << " accepted)</td></tr>\n";
  }
  if (m.ate_odometry) {
    headline << "<tr><td>ATE (RMSE, aligned)</td><td>odometry " << Number(m.ate_odometry->ate_m.rmse, "%.3f")
             << " m &rarr; corrected " << Number(m.ate_corrected->ate_m.rmse, "%.3f") << " m</td></tr>\n";
  }
  std::ostringstream files;
  auto file = [&files](const std::string& name, const std::string& what) {
    files << "<li><a href=\"" << name << "\">" << name << "</a>: " << what << "</li>\n";
  };
  file("corrected.g2o", "the corrected graph, every closure with its decision and weight");
  file("corrected_accepted.g2o", "the same without the rejected closures");
  file("trajectory.tum", "the corrected trajectory at the frames' times (TUM format)");
  if (!truth.empty()) {
    file("groundtruth.tum", "the ground truth at the same times: evo_ape tum groundtruth.tum trajectory.tum -a");
  }
  file("report.json", "the numbers above and every closure");
  file("options.yaml", "every option of this run (catgraph map --options options.yaml runs it again)");
  file("closures.json", "the front end's closures");
  file("hypotheses.csv", "the front end's hypothesis per frame");
  file("graph.g2o", "the front end's graph, before the back end");
  for (const char* picture : {"map.png", "map.svg", "localization.png", "localization.svg"}) file(picture, "the figure");
  WriteFileAtomically(dir / "index.html", [&](std::ostream& f) {
    f << "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>catgraph map: "
      << HtmlEscape(o.front.dataset) << "</title>\n<style>body{font-family:sans-serif;max-width:1200px;margin:auto}"
      << "img{max-width:100%}td{padding:2px 12px}body,td{font-size:16px}</style></head><body>\n<h1>catgraph map</h1>\n<p>"
      << HtmlEscape(o.front.dataset) << ": " << d.frames.size() << " frames; " << HtmlEscape(method)
      << " back end, " << HtmlEscape(hierarchy) << " hierarchy.</p>\n<table>\n" << headline.str() << "</table>\n"
      << "<h2>Map (Fig. 10)</h2>\n<img src=\"map.svg\" alt=\"odometry alone and the corrected map\">\n"
      << "<h2>Hypothesis and closure error per frame (Figs. 7, 8, 11)</h2>\n"
      << "<img src=\"localization.svg\" alt=\"hypothesis and closure error per frame\">\n"
      << "<h2>Files</h2>\n<ul>\n" << files.str() << "</ul>\n"
      << "</body></html>\n";
  });

  if (m.ate_odometry) {
    out << "ATE (RMSE after alignment): odometry " << Number(m.ate_odometry->ate_m.rmse, "%.3f") << " m, corrected map "
        << Number(m.ate_corrected->ate_m.rmse, "%.3f") << " m\n";
  }
  output.Commit();
  out << "wrote " << o.front.output
      << ": corrected.g2o, corrected_accepted.g2o, trajectory.tum" << (truth.empty() ? "" : ", groundtruth.tum")
      << ", report.json, options.yaml, map.png/svg, "
         "localization.png/svg, index.html\n";
}

}  // namespace

void AddMapCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<MapCommandOptions>();
  CLI::App* cmd = app.add_subcommand(
      "map",
      "The whole pipeline on a dataset: CAT-Graph and CAT-Graph+ closures, robust pose-graph solve with the "
      "closure hierarchy, corrected graph (g2o, TUM), report.json, figures and index.html. docs/mapping.md.");
  cmd->add_option("dataset", o->front.dataset, "Dataset directory")->required();
  cmd->add_option("-o,--output", o->front.output, "Output directory")->required();
  AddLocalizationOptions(*cmd, o->front, {"--observation", "--vocabulary", "--seed", "--no-odometric-inference"});
  mapping::MapperOptions& pipeline = o->front.pipeline;
  cmd->add_option_function<std::string>(
         "--hierarchy",
         [&pipeline](const std::string& name) { pipeline.hierarchy.policy = *HierarchyPolicyFromString(name); },
         "cascade: turn off the children of rejected visual closures and re-solve; coupled: scale each child by "
         "its parents' switches in one solve; flat: plain switchable constraints")
      ->check(CLI::IsMember({"cascade", "coupled", "flat"}))
      ->default_str(std::string(ToString(pipeline.hierarchy.policy)));
  cmd->add_option_function<std::string>(
         "--method", [&pipeline](const std::string& name) { pipeline.back_end.method = *RobustMethodFromString(name); },
         "Robust method for loop closures (as catgraph optimize)")
      ->check(CLI::IsMember(RobustMethodNames()))
      ->default_str(std::string(ToString(pipeline.back_end.method)));
  cmd->add_option("--inject-false-visual", o->injection.count,
                  "Make the visual filter report N false matches (pairs of consistent false visual closures "
                  "around a stretch of path; drawn by --seed; needs ground truth). docs/mapping.md")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  AddFalseMatchOptions(*cmd, o->injection);
  for (const char* shape : {"--false-stretch", "--false-min-error", "--false-max-error"}) {
    cmd->get_option(shape)->group(kUnlistedGroup);
  }
  cmd->add_option("--feedback-reruns", o->feedback_reruns,
                  "cascade and coupled: re-run CAT-Graph+ with the visual closures the back end rejected vetoed, "
                  "and solve again, at most this many times (0: off). docs/mapping.md")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str()
      ->group(kUnlistedGroup);
  cmd->add_option("--threads", o->front.pipeline.front_end.threads, "Feature-extraction threads (0: every core)")
      ->check(CLI::Range(0, kMaxThreads))
      ->capture_default_str();
  cmd->add_flag("--quiet", o->front.quiet, "No progress bars");
  AddOverwriteFlag(*cmd, o->front.overwrite);
  cmd->callback([o, &out] { RunMap(*o, out); });
}

}  // namespace catgraph
