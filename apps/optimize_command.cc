// catgraph optimize IN -o OUT [--method M] [--report R] [--drop-rejected] [--json]
#include <fstream>
#include <memory>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "backend/io/atomic_file.h"
#include "backend/io/graph_io.h"
#include "backend/io/output_directory.h"
#include "backend/pose_graph_optimizer.h"

namespace catgraph {
namespace {

struct OptimizeOptions {
  std::string input;
  std::string output;
  std::string format = "auto";
  std::string method = "switchable";
  std::string init = "auto";
  std::string cost = "g2o";
  std::string report;
  bool drop_rejected = false;
  bool json = false;
  PoseGraphOptimizerOptions optimizer;
};

nlohmann::json ReportJson(const OptimizeOptions& o, const GraphFile& file, const PoseGraphOptimization& r,
                          bool with_closures) {
  nlohmann::json j;
  j["input"] = o.input;
  j["self_edges_skipped"] = file.self_edge_lines.size();
  j["output"] = o.output;
  j["method"] = o.method;
  j["init"] = o.init;
  j["initial_guess"] = ToString(r.initial_guess);
  j["termination"] = r.summary.IsUsable() ? "usable" : "failed";
  j["message"] = r.summary.message;
  j["iterations"] = r.summary.iterations;
  j["settled"] = r.summary.stopped_by_test;  // ended when its decisions settled
  // final_cost is that of the last stage run (the poses written), as the
  // text report ends; robust_final_cost the robust solve's own.
  const Summary& last = r.readmission ? *r.readmission
                        : r.refinement ? *r.refinement
                        : (r.narrowed && r.narrow_factor < 1.0) ? *r.narrowed
                                                                : r.summary;
  j["initial_cost"] = r.summary.initial_cost;
  j["final_cost"] = last.final_cost;
  j["robust_final_cost"] = r.summary.final_cost;
  j["chi2"] = r.chi2;
  j["cost"] = o.cost;
  j["chordal_cost"] = r.chordal_cost;
  j["time_s"] = r.TotalTimeS();
  j["refined"] = r.refinement.has_value();
  j["refine_iterations"] = r.refinement ? r.refinement->iterations : 0;
  j["refine_time_s"] = r.refinement ? r.refinement->time_s : 0.0;
  // Where time_s went, and the initial guess's time, which it excludes.
  const Summary solves = r.SolveTimes();
  j["preprocessor_time_s"] = solves.preprocessor_time_s;
  j["linear_solver_time_s"] = solves.linear_solver_time_s;
  j["jacobian_time_s"] = solves.jacobian_time_s;
  j["residual_time_s"] = solves.residual_time_s;
  j["initial_guess_time_s"] = r.initial_guess_time_s;
  j["noise_scale"] = r.noise_scale.scale;
  j["noise_scale_cycles"] = r.noise_scale.cycles;
  j["gate_factor"] = r.gate_factor;
  j["inlier_noise_scale"] = r.inlier_noise_scale.scale;
  j["inlier_noise_upper_scale"] = r.inlier_noise_scale.upper_scale;
  j["inlier_noise_cycles"] = r.inlier_noise_scale.cycles;
  j["narrow_factor"] = r.narrow_factor;
  j["narrowed"] = r.narrow_factor < 1.0;  // ran, and its result was kept
  j["narrow_newly_rejected"] = r.narrow_newly_rejected;
  j["narrow_iterations"] = r.narrowed ? r.narrowed->iterations : 0;
  j["narrow_time_s"] = r.narrowed ? r.narrowed->time_s : 0.0;
  j["readmitted"] = r.readmitted;
  j["readmit_test_time_s"] = r.readmit_test_time_s;
  j["readmit_time_s"] = r.readmit_test_time_s + (r.readmission ? r.readmission->time_s : 0.0);
  // Every stage's wall-clock time (problems built included) and iterations.
  j["wall_time_s"] = r.WallTimeS();
  j["stages"] = nlohmann::json::array();
  for (const StageTime& s : r.stages) {
    j["stages"].push_back({{"stage", s.stage}, {"time_s", s.time_s}, {"iterations", s.iterations}});
  }
  j["accepted"] = r.accepted;
  j["rejected"] = r.rejected;
  if (with_closures) {
    j["closures"] = nlohmann::json::array();
    for (const auto& d : r.closures) {
      j["closures"].push_back({{"id", d.id.value()},
                               {"from", d.from.value()},
                               {"to", d.to.value()},
                               {"kind", ToString(d.kind)},
                               {"weight", d.weight},
                               {"accepted", d.accepted},
                               {"readmitted", d.readmitted}});
    }
  }
  return j;
}

void RunOptimize(OptimizeOptions options, std::ostream& out) {
  RefuseOutputClashes({options.output, options.report}, {options.input});
  const GraphFile file = ReadCommandGraph(options.input, options.format);
  options.optimizer.method = *RobustMethodFromString(options.method);
  options.optimizer.initial_guess = *InitialGuessFromString(options.init);
  options.optimizer.cost =
      options.cost == "chordal" ? RelativePoseCostType::kChordal : RelativePoseCostType::kG2o;
  const PoseGraphOptimization result = OptimizePoseGraph(file.graph, options.optimizer);
  if (!result.summary.IsUsable()) {
    throw std::runtime_error("the solver failed: " + result.summary.message);
  }
  WriteG2oFile(options.drop_rejected ? DropRejected(result.graph, result.closures) : result.graph,
               options.output);
  if (!options.report.empty()) {
    WriteFileAtomically(options.report, [&](std::ostream& report) {
      report << ReportJson(options, file, result, true).dump(2) << '\n';
    });
  }
  if (options.json) {
    out << ReportJson(options, file, result, false).dump(2) << '\n';
    return;
  }
  WriteSelfEdgeNote(out, options.input, file);
  if (result.gate_factor > 1.0) {
    out << "the graph's short cycles show " << result.gate_factor
        << " times the noise its information states (" << result.noise_scale.cycles
        << " cycles): the gate widened by that factor (--no-noise-scale to keep it)\n";
  }
  out << "optimised " << options.input << " with " << options.method << " from the "
      << ToString(result.initial_guess) << " initial guess (" << result.initial_guess_time_s
      << " s): " << result.summary.BriefReport() << '\n';
  if (result.narrow_factor < 1.0) {
    out << "the accepted closures' short cycles show Gaussian noise " << result.inlier_noise_scale.upper_scale
        << " times what their information states (" << result.inlier_noise_scale.cycles
        << " cycles): decided again at a gate " << result.narrow_factor
        << " times the first (--no-narrow-gate to keep it): " << result.narrowed->BriefReport() << '\n';
  }
  out << (result.refinement ? "refined without the rejected closures: " +
                                  result.refinement->BriefReport() + "\n"
                            : std::string());
  if (result.readmitted > 0) {
    out << result.readmitted << " rejected closures consistent with the refined map by their innovation, "
        << "readmitted (--no-readmit to keep them out; test " << result.readmit_test_time_s
        << " s), refined again: " << result.readmission->BriefReport() << '\n';
  }
  out << "chi2 " << result.chi2 << ", chordal cost " << result.chordal_cost << "; loop closures: "
      << result.accepted << " accepted, " << result.rejected << " rejected\n"
      << "time by stage:";
  const auto precision = out.precision(3);
  const char* separator = " ";
  for (const StageTime& s : result.stages) {
    out << separator << s.stage << ' ' << s.time_s << " s";
    if (s.iterations > 0) out << " (" << s.iterations << " iterations)";
    separator = ", ";
  }
  out << "; " << result.WallTimeS() << " s in all\n";
  out.precision(precision);
  out << "wrote " << options.output << (options.drop_rejected ? " (rejected closures dropped)" : "") << '\n';
}

}  // namespace

void AddOptimizeCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<OptimizeOptions>();
  CLI::App* cmd = app.add_subcommand(
      "optimize", "Optimise a 2D or 3D pose graph robustly to false loop closures and write "
                  "the corrected graph (g2o) with what was decided about every closure.");
  cmd->alias("optimise");
  cmd->add_option("input", o->input, "Pose-graph file (g2o, TORO, iSAM)")->required();
  cmd->add_option("-o,--output", o->output, "Corrected graph (g2o)")->required();
  AddGraphFormatOption(*cmd, o->format);
  cmd->add_option("--method", o->method, "Robust method for loop closures")
      ->check(CLI::IsMember(RobustMethodNames()))
      ->capture_default_str();
  cmd->add_option("--init", o->init,
                  "Initial guess: the file's poses (missing ones chained along a spanning "
                  "tree), spanning-tree for all, chordal (rotation-first), or auto: file or "
                  "chordal, whichever has the lower robust cost")
      ->check(CLI::IsMember({"auto", "file", "spanning-tree", "chordal"}))
      ->capture_default_str();
  cmd->add_option("--cost", o->cost,
                  "Objective: g2o (full information) or chordal (SE-Sync's F, compares with "
                  "certified optima)")
      ->check(CLI::IsMember({"g2o", "chordal"}))
      ->capture_default_str();
  cmd->add_option("--report", o->report,
                  "Write a JSON report with every loop closure's weight and decision");
  cmd->add_flag("--drop-rejected", o->drop_rejected,
                "Write only accepted closures and no switches (the graph for a planner)");
  cmd->add_flag("--json", o->json,
                "Print one JSON object (iterations, initial_cost, final_cost, chi2, time_s, "
                "accepted, rejected, ...)");
  cmd->add_option("--switch-gate", o->optimizer.gate.probability,
                  "Every method: a closure is rejected when its chi2 (chordal cost) exceeds "
                  "the chi2(dof) quantile (the chordal cost's) at this probability (sets each "
                  "switch prior and the losses' scales; no per-dataset tuning)")
      ->capture_default_str();
  cmd->add_flag("--no-noise-scale{false}", o->optimizer.gate.estimate_noise_scale,
                "Keep the gate where the file's information puts it, even when short cycles "
                "of the graph show its noise to be three times or more what that information states");
  cmd->add_flag("--no-narrow-gate{false}", o->optimizer.gate.narrow,
                "Keep the first robust solve's decisions, even when the accepted closures' "
                "short cycles show Gaussian noise far below what their information states");
  cmd->add_flag("--no-readmit{false}", o->optimizer.readmission.enabled,
                "Keep every closure the robust solve rejected out, even when its innovation "
                "against the refined map (the map's uncertainty counted) passes the family-wise gate");
  cmd->add_option("--switch-prior-information", o->optimizer.switch_prior_information,
                  "Switchable: a fixed switch-prior information Xi^-1 instead of the gate "
                  "(Vertigo uses 1); 0 = use the gate")
      ->capture_default_str();
  cmd->add_option("--dcs-phi", o->optimizer.dcs_phi,
                  "DCS Phi; 0 = gate / 3, so DCS rejects exactly above the chi2 gate")
      ->capture_default_str();
  cmd->add_option("--loss-scale", o->optimizer.loss_scale_sigma,
                  "Huber/Cauchy scale in sigmas; 0 = from the chi2 gate")
      ->capture_default_str();
  cmd->add_option("--gnc-mu-step", o->optimizer.gnc_mu_step, "GNC: growth of mu per round")
      ->capture_default_str();
  cmd->add_flag("--robust-odometry", o->optimizer.robust_odometry,
                "Apply the robust method to odometry too");
  cmd->add_flag("--no-settled-stop{false}", o->optimizer.refinement.stop_when_settled,
                "Run the robust solve to the solver's tolerances, even though the refinement "
                "re-solves its map once its decisions have settled");
  cmd->add_flag("--no-refine{false}", o->optimizer.refinement.enabled,
                "Keep the robust solve's poses instead of re-solving them with the rejected "
                "closures removed and the accepted ones at full weight");
  cmd->add_option("--max-iterations", o->optimizer.solver.max_iterations,
                  "Levenberg-Marquardt iterations")
      ->capture_default_str();
  cmd->callback([o, &out] { RunOptimize(*o, out); });
}

}  // namespace catgraph
