#include "backend/pose_graph_optimizer.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <variant>

#include "backend/chi_square.h"
#include "backend/graph/name_table.h"
#include "backend/initialization.h"
#include "backend/robust_losses.h"

namespace catgraph {
namespace {

constexpr NameTable<RobustMethod, 5> kMethodNames = {{
    {RobustMethod::kNone, "none"},
    {RobustMethod::kSwitchable, "switchable"},
    {RobustMethod::kDcs, "dcs"},
    {RobustMethod::kCauchy, "cauchy"},
    {RobustMethod::kHuber, "huber"},
}};

template <typename PoseT>
Eigen::Matrix<double, PoseT::kTangentDim, 1> Error(const PoseT& from, const PoseT& to,
                                                   const PoseT& z);
template <>
Eigen::Matrix<double, 3, 1> Error(const Pose2& from, const Pose2& to, const Pose2& z) {
  return z.Between(from.Between(to)).ToVector();
}
template <>
Eigen::Matrix<double, 6, 1> Error(const Pose3& from, const Pose3& to, const Pose3& z) {
  const Pose3 d = z.Between(from.Between(to));
  Eigen::Quaterniond q = d.rotation();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  Eigen::Matrix<double, 6, 1> e;
  e << d.translation(), q.vec();
  return e;
}

template <typename PoseT>
double EdgeChi2(const PoseGraph<PoseT>& graph, const Constraint<PoseT>& c) {
  const auto e = Error(*graph.vertices.at(c.from).pose, *graph.vertices.at(c.to).pose,
                       c.measurement.mean);
  return e.dot(c.measurement.information * e);
}

template <typename PoseT>
double GraphChi2(const PoseGraph<PoseT>& graph) {
  double chi2 = 0.0;
  for (const auto& c : graph.constraints) {
    double scale = 1.0;
    if (c.switch_id) scale = std::pow(graph.switches.at(*c.switch_id).value, 2);
    chi2 += scale * EdgeChi2(graph, c);
  }
  for (const auto& [id, s] : graph.switches) {
    if (s.prior) chi2 += s.prior->information * std::pow(s.prior->mean - s.value, 2);
  }
  return chi2;
}

Eigen::Matrix2d RotationMatrixOf(const Pose2& p) { return p.rotation(); }
Eigen::Matrix3d RotationMatrixOf(const Pose3& p) { return p.rotation().toRotationMatrix(); }

template <typename PoseT>
double GraphChordalCost(const PoseGraph<PoseT>& graph) {
  double f = 0.0;
  for (const auto& c : graph.constraints) {
    const PoseT& xi = *graph.vertices.at(c.from).pose;
    const PoseT& xj = *graph.vertices.at(c.to).pose;
    const auto w = ChordalWeightsOf<PoseT::kTangentDim>(c.measurement.information);
    const auto ri = RotationMatrixOf(xi);
    f += w.kappa * (RotationMatrixOf(xj) - ri * RotationMatrixOf(c.measurement.mean)).squaredNorm();
    f += w.tau * (xj.translation() - xi.translation() - ri * c.measurement.mean.translation())
                     .squaredNorm();
  }
  return f;
}

RobustLoss LossFor(const PoseGraphOptimizerOptions& o) {
  switch (o.method) {
    case RobustMethod::kDcs: return {RobustLoss::Type::kDcs, o.dcs_phi};
    case RobustMethod::kCauchy: return {RobustLoss::Type::kCauchy, o.loss_scale_sigma};
    case RobustMethod::kHuber: return {RobustLoss::Type::kHuber, o.loss_scale_sigma};
    default: return {};
  }
}

// rho'(chi2): the IRLS weight on the edge's chi2. Its square root scales the
// residual, as a switch does.
double LossDerivative(const RobustLoss& loss, double chi2) {
  switch (loss.type) {
    case RobustLoss::Type::kNone: return 1.0;
    case RobustLoss::Type::kDcs: return DcsLoss::SquaredWeight(loss.scale, chi2);
    case RobustLoss::Type::kHuber: {
      const double b = loss.scale * loss.scale;
      return chi2 <= b ? 1.0 : std::sqrt(b / chi2);
    }
    case RobustLoss::Type::kCauchy: {
      const double b = loss.scale * loss.scale;
      return 1.0 / (1.0 + chi2 / b);
    }
  }
  return 1.0;
}

constexpr NameTable<InitialGuess, 3> kInitialGuessNames = {{
    {InitialGuess::kFile, "file"},
    {InitialGuess::kSpanningTree, "spanning-tree"},
    {InitialGuess::kChordal, "chordal"},
}};

template <typename PoseT>
PoseGraphOptimization Run(PoseGraph<PoseT> graph, const PoseGraphOptimizerOptions& options) {
  switch (options.initial_guess) {
    case InitialGuess::kFile: InitializeBySpanningTree(graph); break;
    case InitialGuess::kSpanningTree: InitializeBySpanningTree(graph, /*overwrite=*/true); break;
    case InitialGuess::kChordal: InitializeChordal(graph); break;
  }
  const bool switchable = options.method == RobustMethod::kSwitchable;
  const RobustLoss loss = LossFor(options);
  auto robust = [&](const Constraint<PoseT>& c) {
    return options.robust_odometry || c.kind != ClosureKind::kOdometry;
  };

  if (switchable) {
    const double switch_information =
        options.switch_prior_information > 0.0
            ? options.switch_prior_information
            : ChiSquareQuantile(PoseT::kTangentDim, options.switch_gate_probability);
    graph.AddSwitches(robust, SwitchPrior{1.0, switch_information});
  }

  // The poses and the gauge, shared by the robust solve and the refinement.
  auto add_poses = [&graph](FactorGraph& factors, Values& values) {
    for (const auto& [id, v] : graph.vertices) {
      values.Insert(id, *v.pose);
      if (v.fixed) factors.SetConstant(PoseKey(id));
    }
    if (std::none_of(graph.vertices.begin(), graph.vertices.end(),
                     [](const auto& v) { return v.second.fixed; })) {
      factors.SetConstant(PoseKey(graph.vertices.begin()->first));  // gauge
    }
  };
  auto take_poses = [&graph](const Values& values) {
    for (auto& [id, v] : graph.vertices) {
      if constexpr (std::is_same_v<PoseT, Pose2>) {
        v.pose = values.AtPose2(id);
      } else {
        v.pose = values.AtPose3(id);
      }
    }
  };

  Values initial;
  FactorGraph factors;
  add_poses(factors, initial);
  for (const auto& [id, s] : graph.switches) {
    initial.Insert(id, s.value);
    if (s.prior) factors.Emplace<SwitchPriorFactor>(id, *s.prior);
  }
  for (const auto& c : graph.constraints) {
    if (c.switch_id) {
      factors.Emplace<SwitchableBetweenFactor<PoseT>>(c.from, c.to, *c.switch_id, c.measurement,
                                                      options.switch_function);
    } else {
      factors.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement,
                                            robust(c) ? loss : RobustLoss{}, options.cost);
    }
  }

  const OptimizationResult solved = Optimize(factors, initial, options.solver);
  take_poses(solved.values);
  for (auto& [id, s] : graph.switches) s.value = solved.values.AtSwitch(id);

  PoseGraphOptimization out;
  for (const auto& c : graph.constraints) {
    if (c.kind == ClosureKind::kOdometry && !c.switch_id) continue;
    ClosureDecision d{c.id, c.from, c.to, c.kind, 1.0, true};
    if (c.switch_id) {
      const double s = graph.switches.at(*c.switch_id).value;
      d.weight = options.switch_function == SwitchFunction::kLinear ? s : 1.0 / (1.0 + std::exp(-s));
    } else if (robust(c)) {
      d.weight = std::sqrt(LossDerivative(loss, EdgeChi2(graph, c)));
    }
    d.accepted = d.weight > 0.5;
    (d.accepted ? out.accepted : out.rejected) += 1;
    out.closures.push_back(d);
  }
  out.summary = solved.summary;

  // Refinement: the decisions stand; the poses are re-solved by plain least
  // squares over the odometry and the accepted closures at full weight, so
  // that the residual pull of rejected closures (weight up to 0.5) and the
  // down-weighting of accepted ones leave no bias in the map.
  const bool robust_solve = options.method != RobustMethod::kNone || !graph.switches.empty();
  if (options.refine && robust_solve && out.summary.IsUsable()) {
    std::set<ClosureId> rejected;
    for (const ClosureDecision& d : out.closures) {
      if (!d.accepted) rejected.insert(d.id);
    }
    Values start;
    FactorGraph refine;
    add_poses(refine, start);
    for (const auto& c : graph.constraints) {
      if (rejected.contains(c.id)) continue;
      refine.Emplace<BetweenFactor<PoseT>>(c.from, c.to, c.measurement, RobustLoss{}, options.cost);
    }
    const OptimizationResult refined = Optimize(refine, start, options.solver);
    if (refined.summary.IsUsable()) take_poses(refined.values);
    out.refinement = refined.summary;
  }
  out.chi2 = GraphChi2(graph);
  out.chordal_cost = GraphChordalCost(graph);
  out.graph = std::move(graph);
  return out;
}

template <typename PoseT>
PoseGraph<PoseT> Drop(PoseGraph<PoseT> graph, const std::vector<ClosureDecision>& decisions) {
  std::set<ClosureId> rejected;
  for (const auto& d : decisions) {
    if (!d.accepted) rejected.insert(d.id);
  }
  std::erase_if(graph.constraints, [&](const Constraint<PoseT>& c) {
    return rejected.contains(c.id) || (c.switch_id && graph.switches.at(*c.switch_id).value <= 0.5);
  });
  for (auto& c : graph.constraints) c.switch_id.reset();
  graph.switches.clear();
  return graph;
}

}  // namespace

std::string_view ToString(RobustMethod method) { return NameOf(kMethodNames, method); }

std::optional<RobustMethod> RobustMethodFromString(std::string_view text) {
  return ValueOf(kMethodNames, text);
}

std::string_view ToString(InitialGuess guess) { return NameOf(kInitialGuessNames, guess); }

std::optional<InitialGuess> InitialGuessFromString(std::string_view text) {
  return ValueOf(kInitialGuessNames, text);
}

void Validate(const PoseGraphOptimizerOptions& o) {
  if (!(o.switch_prior_information >= 0.0)) {
    throw std::invalid_argument("switch_prior_information must be >= 0 (0: use the gate)");
  }
  if (!(o.switch_gate_probability > 0.0 && o.switch_gate_probability < 1.0)) {
    throw std::invalid_argument("switch_gate_probability must be in (0, 1)");
  }
  if (!(o.dcs_phi > 0.0)) throw std::invalid_argument("dcs_phi must be > 0");
  if (!(o.loss_scale_sigma > 0.0)) throw std::invalid_argument("loss_scale_sigma must be > 0");
  if (o.cost == RelativePoseCostType::kChordal && o.method == RobustMethod::kSwitchable) {
    throw std::invalid_argument(
        "the chordal cost is not available with switchable constraints; use --method none, "
        "dcs, cauchy or huber");
  }
  Validate(o.solver);
}

PoseGraphOptimization OptimizePoseGraph(const AnyPoseGraph& graph,
                                        const PoseGraphOptimizerOptions& options) {
  Validate(options);
  return std::visit([&](const auto& g) { return Run(g, options); }, graph);
}

double ChordalCost(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return GraphChordalCost(g); }, graph);
}

double Chi2(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return GraphChi2(g); }, graph);
}

AnyPoseGraph DropRejected(const AnyPoseGraph& graph,
                          const std::vector<ClosureDecision>& decisions) {
  return std::visit([&](const auto& g) { return AnyPoseGraph(Drop(g, decisions)); }, graph);
}

}  // namespace catgraph
