#include "simulation/outlier_injection.h"

#include <algorithm>
#include <map>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr NameTable<OutlierPolicy, 5> kPolicyNames = {{
    {OutlierPolicy::kRandom, "random"},
    {OutlierPolicy::kLocal, "local"},
    {OutlierPolicy::kRandomGrouped, "random-grouped"},
    {OutlierPolicy::kLocalGrouped, "local-grouped"},
    {OutlierPolicy::kHierarchical, "hierarchical"},
}};

constexpr double kSigmaTranslationM = 0.3;
constexpr double kSigmaRotationRad = 10.0 * std::numbers::pi / 180.0;

bool IsLocal(OutlierPolicy p) {
  return p == OutlierPolicy::kLocal || p == OutlierPolicy::kLocalGrouped;
}

// One false measurement, drawn in the order the protocol lists the values.
Pose2 DrawMeasurement(std::mt19937_64& rng, const Pose2*) {
  std::normal_distribution<double> t(0.0, kSigmaTranslationM), r(0.0, kSigmaRotationRad);
  const double dx = t(rng), dy = t(rng), dtheta = r(rng);
  return {dx, dy, dtheta};
}

Pose3 DrawMeasurement(std::mt19937_64& rng, const Pose3*) {
  std::normal_distribution<double> t(0.0, kSigmaTranslationM), r(0.0, kSigmaRotationRad);
  const double dx = t(rng), dy = t(rng), dz = t(rng);
  const double roll = r(rng), pitch = r(rng), yaw = r(rng);
  const Eigen::Quaterniond q = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX());
  return {Eigen::Vector3d(dx, dy, dz), q};
}

template <typename PoseT>
InformationMatrix<PoseT> OutlierInformation(const PoseGraph<PoseT>& graph,
                                            const OutlierOptions& options) {
  constexpr int kDim = PoseT::kTangentDim;
  if (options.information) {
    const Eigen::MatrixXd& m = *options.information;
    if (m.rows() != kDim || m.cols() != kDim) {
      throw std::invalid_argument("OutlierOptions::information: expected a " +
                                  std::to_string(kDim) + "x" + std::to_string(kDim) +
                                  " matrix for this graph, got " + std::to_string(m.rows()) +
                                  "x" + std::to_string(m.cols()));
    }
    return m;
  }
  for (const auto& c : graph.constraints) {
    if (!c.IsBetweenConsecutivePoses()) return c.measurement.information;
  }
  throw std::invalid_argument(
      "the graph has no loop closure to copy the outliers' information from; give it "
      "explicitly (--information)");
}

// The measured odometry from poses[a] to poses[b], a <= b, composed from the
// constraints between consecutive poses (either direction).
template <typename PoseT>
class OdometryChain {
 public:
  OdometryChain(const PoseGraph<PoseT>& graph, const std::vector<PoseId>& poses) {
    std::map<PoseId, std::size_t> index;
    for (std::size_t k = 0; k < poses.size(); ++k) index[poses[k]] = k;
    step_.resize(poses.size());
    for (const auto& c : graph.constraints) {
      const auto from = index.find(c.from), to = index.find(c.to);
      if (from == index.end() || to == index.end()) continue;
      if (to->second == from->second + 1 && !step_[from->second]) {
        step_[from->second] = c.measurement.mean;
      } else if (from->second == to->second + 1 && !step_[to->second]) {
        step_[to->second] = c.measurement.mean.Inverse();
      }
    }
    poses_ = &poses;
  }

  PoseT Between(std::size_t a, std::size_t b) const {
    PoseT t = PoseT::Identity();
    for (std::size_t k = a; k < b; ++k) {
      if (!step_[k]) {
        throw std::invalid_argument(
            "hierarchical outliers need the odometry between consecutive poses, but the graph "
            "has no constraint between poses " +
            std::to_string((*poses_)[k].value()) + " and " +
            std::to_string((*poses_)[k + 1].value()));
      }
      t = t * *step_[k];
    }
    return t;
  }

 private:
  std::vector<std::optional<PoseT>> step_;  // step_[k]: poses[k] -> poses[k + 1]
  const std::vector<PoseId>* poses_ = nullptr;
};

}  // namespace

std::string_view ToString(OutlierPolicy policy) { return NameOf(kPolicyNames, policy); }
std::optional<OutlierPolicy> OutlierPolicyFromString(std::string_view text) {
  return ValueOf(kPolicyNames, text);
}

int GroupSize(const OutlierOptions& options) {
  const bool single =
      options.policy == OutlierPolicy::kRandom || options.policy == OutlierPolicy::kLocal;
  if (options.group_size < 0 || options.group_size > kMaxOutlierGroupSize) {
    throw std::invalid_argument("OutlierOptions::group_size must be in [0, " +
                                std::to_string(kMaxOutlierGroupSize) + "], got " +
                                std::to_string(options.group_size));
  }
  if (options.group_size == 0) return single ? 1 : 5;
  if (single && options.group_size != 1) {
    throw std::invalid_argument("policy " + std::string(ToString(options.policy)) +
                                " takes groups of 1, got group size " +
                                std::to_string(options.group_size) + " (use " +
                                std::string(ToString(options.policy)) + "-grouped)");
  }
  if (options.policy == OutlierPolicy::kHierarchical && options.group_size < 2) {
    throw std::invalid_argument(
        "policy hierarchical needs a group size >= 2 (one visual closure and its children), "
        "got " + std::to_string(options.group_size));
  }
  return options.group_size;
}

void Validate(const OutlierOptions& options) {
  if (options.count < 0 || options.count > kMaxOutliers) {
    throw std::invalid_argument("OutlierOptions::count must be in [0, " + std::to_string(kMaxOutliers) + "], got " +
                                std::to_string(options.count));
  }
  if (options.local_window < 2) {
    throw std::invalid_argument("OutlierOptions::local_window must be >= 2, got " +
                                std::to_string(options.local_window));
  }
  GroupSize(options);
  if (options.information) {
    const Eigen::MatrixXd& m = *options.information;
    if (m.rows() != m.cols() || !m.isApprox(m.transpose()) || m.llt().info() != Eigen::Success) {
      throw std::invalid_argument(
          "OutlierOptions::information must be symmetric positive definite");
    }
  }
}

template <typename PoseT>
std::vector<InjectedClosure> InjectOutliers(PoseGraph<PoseT>& graph,
                                            const OutlierOptions& options) {
  Validate(options);
  const int g = GroupSize(options);
  std::vector<PoseId> poses;
  for (const auto& [id, v] : graph.vertices) poses.push_back(id);
  const int n = static_cast<int>(poses.size());
  if (options.count == 0) return {};
  if (n < g + 3) {
    throw std::invalid_argument("outlier injection with groups of " + std::to_string(g) +
                                " needs at least " + std::to_string(g + 3) +
                                " poses; the graph has " + std::to_string(n));
  }
  const InformationMatrix<PoseT> information = OutlierInformation(graph, options);
  const bool hierarchical = options.policy == OutlierPolicy::kHierarchical;
  std::optional<OdometryChain<PoseT>> odometry;
  if (hierarchical) odometry.emplace(graph, poses);

  std::mt19937_64 rng(options.seed);
  const int last = n - 1 - g;  // v1, v2 in {0 ... last}
  std::uniform_int_distribution<int> anywhere(0, last);
  std::vector<InjectedClosure> injected;
  ClosureId next_id = graph.NextClosureId();
  for (int group = 0; static_cast<int>(injected.size()) < options.count; ++group) {
    // Redraw the pair while equal (a local v1 at the end of the range has no
    // other partner, so v1 is redrawn too).
    int v1 = 0, v2 = 0;
    do {
      v1 = anywhere(rng);
      if (IsLocal(options.policy)) {
        v2 = std::uniform_int_distribution<int>(v1, std::min(last, v1 + options.local_window))(rng);
      } else {
        v2 = anywhere(rng);
      }
    } while (v1 == v2);
    if (v1 > v2) std::swap(v1, v2);
    if (v2 == v1 + 1) v2 = v1 + 2;
    const PoseT z = DrawMeasurement(rng, static_cast<const PoseT*>(nullptr));

    const int size = std::min(g, options.count - static_cast<int>(injected.size()));
    std::optional<ClosureId> parent;
    for (int j = 0; j < size; ++j) {
      Constraint<PoseT> c;
      c.id = next_id;
      next_id = ClosureId(next_id.value() + 1);
      c.from = poses[v1 + j];
      c.to = poses[v2 + j];
      c.kind = ClosureKind::kInjected;
      c.measurement = {z, information};
      if (hierarchical) {
        if (j == 0) {
          c.kind = ClosureKind::kVisual;
          parent = c.id;
        } else {
          c.kind = ClosureKind::kOdometryInferred;
          c.provenance.parents = {*parent};
          c.measurement.mean = odometry->Between(v1, v1 + j).Inverse() * z *
                               odometry->Between(v2, v2 + j);
        }
      }
      injected.push_back({c.id, c.from, c.to, group, j == 0 ? std::nullopt : parent});
      graph.constraints.push_back(std::move(c));
    }
  }
  return injected;
}

template std::vector<InjectedClosure> InjectOutliers(PoseGraph2&, const OutlierOptions&);
template std::vector<InjectedClosure> InjectOutliers(PoseGraph3&, const OutlierOptions&);

std::vector<InjectedClosure> InjectOutliers(AnyPoseGraph& graph, const OutlierOptions& options) {
  return std::visit([&](auto& g) { return InjectOutliers(g, options); }, graph);
}

std::vector<ClosureLabel> LabelClosures(const AnyPoseGraph& graph,
                                        const std::vector<InjectedClosure>& injected) {
  std::map<ClosureId, const InjectedClosure*> by_id;
  for (const InjectedClosure& c : injected) by_id[c.id] = &c;
  return std::visit(
      [&by_id](const auto& g) {
        std::vector<ClosureLabel> labels;
        for (const auto& c : g.constraints) {
          if (c.IsBetweenConsecutivePoses()) continue;
          ClosureLabel label{c.id, c.from, c.to, false, c.kind, std::nullopt, std::nullopt};
          if (const auto it = by_id.find(c.id); it != by_id.end()) {
            label.outlier = true;
            label.group = it->second->group;
            label.parent = it->second->parent;
          }
          labels.push_back(label);
        }
        return labels;
      },
      graph);
}

}  // namespace catgraph
