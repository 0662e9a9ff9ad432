// catgraph evaluate EST --truth GT [--labels L] [--report R] [--json]
#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "backend/chi_square.h"
#include "backend/evaluation.h"
#include "backend/io/closure_labels.h"
#include "backend/io/file_error.h"
#include "backend/io/graph_io.h"
#include "backend/io/trajectory_io.h"

namespace catgraph {
namespace {

struct EvaluateOptions {
  std::string estimate, truth, labels, report;
  std::string format = "auto";
  std::string truth_format = "auto";
  double truth_gate_probability = 0.999;
  bool json = false;
};

// The closure decisions of `catgraph optimize --report`.
std::vector<ClosureOutcome> OutcomesFromReport(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path, 0, "cannot open; expected the JSON report of catgraph optimize");
  nlohmann::json j;
  try {
    in >> j;
    std::vector<ClosureOutcome> outcomes;
    for (const auto& c : j.at("closures")) {
      outcomes.push_back({PoseId(c.at("from").get<std::int64_t>()),
                          PoseId(c.at("to").get<std::int64_t>()), c.at("accepted").get<bool>()});
    }
    return outcomes;
  } catch (const nlohmann::json::exception& e) {
    throw FileError(path, 0,
                    std::string("expected the JSON report of catgraph optimize with a 'closures' "
                                "array of {from, to, accepted}: ") + e.what());
  }
}

nlohmann::json StatisticsJson(const ErrorStatistics& s, double scale = 1.0) {
  return {{"rmse", s.rmse * scale}, {"mean", s.mean * scale}, {"median", s.median * scale},
          {"max", s.max * scale}};
}

void RunEvaluate(const EvaluateOptions& o, std::ostream& out) {
  const GraphFile file = ReadCommandGraph(o.estimate, o.format);
  const AnyPoseGraph& estimate = file.graph;
  const AnyTrajectory truth =
      ReadTrajectoryFile(o.truth, *TrajectoryFormatFromString(o.truth_format));
  AnyTrajectory estimated;
  try {
    estimated = TrajectoryOf(estimate);
  } catch (const std::invalid_argument& e) {
    throw FileError(o.estimate, 0, e.what());
  }
  // A pose without truth is the truth file's fault (or the pairing's).
  const TrajectoryEvaluation t = [&] {
    try {
      return EvaluateTrajectory(estimated, truth);
    } catch (const std::invalid_argument& e) {
      throw FileError(o.truth, 0, e.what());
    }
  }();
  std::optional<ClosureScores> scores;
  if (!o.labels.empty()) {
    std::vector<ClosureOutcome> outcomes =
        o.report.empty() ? ClosureOutcomesOf(estimate) : OutcomesFromReport(o.report);
    AttachChi2AtTruth(outcomes, estimate, truth);
    const int dof = std::holds_alternative<PoseGraph2>(estimate) ? 3 : 6;
    std::vector<int> lines;
    const std::vector<ClosureLabel> labels = ReadClosureLabelsFile(o.labels, &lines);
    if (const auto mismatch = FindLabelMismatch(estimate, labels)) {
      throw FileError(o.labels, mismatch->label ? lines[*mismatch->label] : 0, mismatch->message);
    }
    scores = ScoreClosures(outcomes, labels, ChiSquareQuantile(dof, o.truth_gate_probability));
  }
  constexpr double kDeg = 180.0 / std::numbers::pi;
  if (o.json) {
    nlohmann::json j = {{"estimate", o.estimate},
                        {"truth", o.truth},
                        {"poses", t.poses},
                        {"ate_rmse", t.ate_m.rmse},
                        {"ate_mean", t.ate_m.mean},
                        {"ate_median", t.ate_m.median},
                        {"ate_max", t.ate_m.max},
                        {"rmse_anchored", t.rmse_anchored_m},
                        {"rpe_translation", StatisticsJson(t.rpe_translation_m)},
                        {"rpe_rotation_deg", StatisticsJson(t.rpe_rotation_rad, kDeg)},
                        {"precision", nullptr},
                        {"recall", nullptr},
                        {"f1", nullptr}};
    if (scores) {
      j["precision"] = scores->precision;
      j["recall"] = scores->recall;
      j["f1"] = scores->f1;
      j["true_positives"] = scores->true_positives;
      j["false_positives"] = scores->false_positives;
      j["true_negatives"] = scores->true_negatives;
      j["false_negatives"] = scores->false_negatives;
      j["outlier_rejection"] = scores->outlier_rejection;
      j["outliers_explained_by_truth"] = scores->outliers_explained_by_truth;
      j["explained_outliers_accepted"] = scores->explained_outliers_accepted;
      j["unexplained_outlier_rejection"] = scores->unexplained_outlier_rejection;
    }
    out << j.dump(2) << '\n';
    return;
  }
  WriteSelfEdgeNote(out, o.estimate, file);
  out << o.estimate << " against " << o.truth << " (" << t.poses << " poses)\n"
      << "ATE after alignment (m): rmse " << t.ate_m.rmse << ", mean " << t.ate_m.mean
      << ", median " << t.ate_m.median << ", max " << t.ate_m.max << '\n'
      << "RMSE with pose 0 anchored (m): " << t.rmse_anchored_m << '\n'
      << "RPE per step: translation rmse " << t.rpe_translation_m.rmse << " m, rotation rmse "
      << t.rpe_rotation_rad.rmse * kDeg << " deg\n";
  if (scores) {
    out << "loop closures: precision " << scores->precision << ", recall " << scores->recall
        << ", F1 " << scores->f1 << " (true accepted " << scores->true_positives
        << ", false accepted " << scores->false_positives << ", false rejected "
        << scores->true_negatives << ", true rejected " << scores->false_negatives << ")\n"
        << "outliers rejected: " << 100.0 * scores->outlier_rejection << " %; "
        << scores->outliers_explained_by_truth << " outliers are explained by the truth (chi2 at "
        << "the true poses within the gate), " << scores->explained_outliers_accepted
        << " of them accepted; of the others " << 100.0 * scores->unexplained_outlier_rejection
        << " % rejected\n";
  }
}

}  // namespace

void AddEvaluateCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<EvaluateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "evaluate",
      "Score an optimised graph against ground truth: ATE after rigid alignment, RMSE with "
      "pose 0 anchored, RPE; with --labels, precision and recall of the accepted closures.");
  cmd->add_option("estimate", o->estimate, "Optimised pose graph (g2o, TORO, iSAM)")->required();
  AddGraphFormatOption(*cmd, o->format);
  cmd->add_option("--truth", o->truth,
                  "Ground truth: a pose graph, a pose list ('x y theta' or 'id x y theta' per "
                  "line) or a TUM trajectory")
      ->required();
  cmd->add_option("--truth-format", o->truth_format, "Ground-truth format")
      ->check(CLI::IsMember({"auto", "graph", "poses", "tum"}))
      ->capture_default_str();
  cmd->add_option("--labels", o->labels, "Closure labels written by catgraph inject");
  cmd->add_option("--report", o->report,
                  "With --labels: take each closure's decision from this catgraph optimize "
                  "--report instead of the estimate (whose decisions catgraph optimize writes into it)");
  cmd->add_option("--truth-gate", o->truth_gate_probability,
                  "With --labels: an outlier whose chi2 at the true poses is within this chi2 "
                  "quantile counts as explained by the truth (the optimiser's default gate)")
      ->check(CLI::Range(0.0, 1.0).description("in (0, 1)"))
      ->capture_default_str();
  cmd->add_flag("--json", o->json,
                "Print one JSON object (ate_rmse, rmse_anchored, precision, recall, ...)");
  cmd->callback([o, &out] { RunEvaluate(*o, out); });
}

}  // namespace catgraph
