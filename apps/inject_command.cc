// catgraph inject IN -o OUT --outliers N [--policy P] [--group-size G] ...
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <vector>

#include "apps/commands.h"
#include "backend/io/closure_labels.h"
#include "backend/io/graph_io.h"
#include "backend/io/output_directory.h"
#include "backend/pose_graph_optimizer.h"
#include "simulation/outlier_injection.h"

namespace catgraph {
namespace {

struct InjectOptions {
  std::string input, output, labels;
  std::string format = "auto";
  std::string policy = "random";
  std::vector<double> information;
  bool switchable = false;
  double switch_prior_information = 0.0;  // 0: the optimiser's default gate
  OutlierOptions outliers;
  int groups = -1;  // --groups; -1: --outliers gives the total
};

// One value: that value times the identity; otherwise g2o's upper triangle.
Eigen::MatrixXd InformationFromValues(const std::vector<double>& values, int dim) {
  const auto n = static_cast<std::size_t>(dim * (dim + 1) / 2);
  if (values.size() == 1) return values.front() * Eigen::MatrixXd::Identity(dim, dim);
  if (values.size() != n) {
    throw std::invalid_argument("--information: expected 1 value (times the identity) or the " +
                                std::to_string(n) + " values of the upper triangle for a " +
                                std::to_string(dim) + "D graph, got " +
                                std::to_string(values.size()));
  }
  Eigen::MatrixXd m(dim, dim);
  std::size_t k = 0;
  for (int r = 0; r < dim; ++r) {
    for (int c = r; c < dim; ++c) m(r, c) = m(c, r) = values[k++];
  }
  return m;
}

void RunInject(InjectOptions o, std::ostream& out) {
  RefuseOutputClashes({o.output, o.labels}, {o.input});
  GraphFile file = ReadCommandGraph(o.input, o.format);
  WriteSelfEdgeNote(out, o.input, file);
  AnyPoseGraph graph = std::move(file.graph);
  const int dim = std::holds_alternative<PoseGraph2>(graph) ? 3 : 6;
  o.outliers.policy = *OutlierPolicyFromString(o.policy);
  if (o.groups >= 0) {
    // Vertigo's generateDataset.py: N groups of G edges each.
    const std::int64_t total = std::int64_t{o.groups} * GroupSize(o.outliers);
    if (total > kMaxOutliers) {
      throw std::invalid_argument("--groups " + std::to_string(o.groups) + " x group size " +
                                  std::to_string(GroupSize(o.outliers)) + " is " + std::to_string(total) +
                                  " false edges; expected at most " + std::to_string(kMaxOutliers));
    }
    o.outliers.count = static_cast<int>(total);
  }
  if (!o.information.empty()) o.outliers.information = InformationFromValues(o.information, dim);
  const std::vector<InjectedClosure> injected = InjectOutliers(graph, o.outliers);
  if (o.switchable) {
    if (!(o.switch_prior_information >= 0.0)) {
      throw std::invalid_argument("--switch-prior-information must be > 0 (or 0 for the optimiser's gate)");
    }
    // By default the priors carry the chi2 gate catgraph's optimiser sets
    // (docs/backend.md): a file's switch priors are kept by every solver
    // that reads it, and Vertigo's 1 switches off true closures as soon as
    // their error exceeds one sigma.
    std::visit(
        [&o](auto& g) {
          using PoseT = typename std::decay_t<decltype(g)>::Pose;
          const double information =
              o.switch_prior_information > 0.0
                  ? o.switch_prior_information
                  : Gate<PoseT>(RelativePoseCostType::kG2o, PoseGraphOptimizerOptions{}.gate.probability);
          g.AddSwitches([](const auto& c) { return !c.IsBetweenConsecutivePoses(); },
                        SwitchPrior{1.0, information});
        },
        graph);
  }
  WriteG2oFile(graph, o.output);
  const int groups = injected.empty() ? 0 : injected.back().group + 1;
  out << "injected " << injected.size() << " false loop closures (" << o.policy << ", "
      << groups << " group" << (groups == 1 ? "" : "s") << ", seed " << o.outliers.seed
      << ") into " << o.input << "\nwrote " << o.output
      << (o.switchable ? " (every loop closure switchable)" : "") << '\n';
  if (!o.labels.empty()) {
    WriteClosureLabelsFile(LabelClosures(graph, injected), o.labels);
    out << "wrote " << o.labels << '\n';
  }
}

}  // namespace

void AddInjectCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<InjectOptions>();
  CLI::App* cmd = app.add_subcommand(
      "inject",
      "Add false loop closures to a pose graph (Vertigo's protocol, 2D and 3D) and list "
      "them in a labels file. The same seed gives the same file.");
  cmd->add_option("input", o->input, "Pose-graph file (g2o, TORO, iSAM)")->required();
  cmd->add_option("-o,--output", o->output, "Spoiled graph (g2o)")->required();
  AddGraphFormatOption(*cmd, o->format);
  CLI::Option* outliers = cmd->add_option("--outliers", o->outliers.count, "Number of false edges in all")
                              ->check(CLI::Range(0, kMaxOutliers));
  CLI::Option* groups =
      cmd->add_option("--groups", o->groups,
                      "Number of groups of --group-size edges each (N x G edges, Vertigo's convention); instead of "
                      "--outliers")
          ->check(CLI::Range(0, kMaxOutliers));
  outliers->excludes(groups);
  cmd->add_option("--policy", o->policy,
                  "random, local (pairs at most --local-window apart), random-grouped, "
                  "local-grouped, or hierarchical (a false visual closure and its "
                  "odometry-inferred children)")
      ->check(CLI::IsMember({"random", "local", "random-grouped", "local-grouped", "hierarchical"}))
      ->capture_default_str();
  cmd->add_option("--group-size", o->outliers.group_size,
                  "Edges per group; 0 = the policy's default (1, or 5 for grouped and "
                  "hierarchical)")
      ->check(CLI::Range(0, kMaxOutlierGroupSize))
      ->capture_default_str();
  cmd->add_option("--local-window", o->outliers.local_window,
                  "Largest pose-id gap of a local pair")
      ->check(CLI::Range(2, std::numeric_limits<int>::max()))
      ->capture_default_str();
  cmd->add_option("--seed", o->outliers.seed, "Random seed")->capture_default_str();
  cmd->add_option("--information", o->information,
                  "Information of the false edges: one value (times the identity) or the upper "
                  "triangle as in g2o (6 values in 2D, 21 in 3D); default: copied from the "
                  "first loop closure")
      ->expected(1, 21);
  cmd->add_flag("--switchable", o->switchable,
                "Give every loop closure, true and false, a switch (Vertigo's switchable file)");
  cmd->add_option("--switch-prior-information", o->switch_prior_information,
                  "With --switchable: the switch priors' information; default: the chi2(dof) quantile "
                  "catgraph's optimiser gates with (16.27 in 2D, 22.46 in 3D); Vertigo's files use 1");
  cmd->add_option("--labels", o->labels,
                  "Write a CSV with every loop closure and whether it is false");
  cmd->callback([o, outliers, groups, &out] {
    if (outliers->count() == 0 && groups->count() == 0) throw CLI::RequiredError("--outliers (in all) or --groups");
    RunInject(*o, out);
  });
}

}  // namespace catgraph
