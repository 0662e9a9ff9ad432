#include "backend/evaluation.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <set>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "backend/graph/relative_pose_error.h"

namespace catgraph {
namespace {

// Values keyed by a closure's endpoints, either direction, handed out in
// the order they were added: how labels, decisions and measurements of the
// same closure are matched (a false edge duplicating a true closure's
// endpoints comes after it).
template <typename T>
class ByEndpoints {
 public:
  void Add(PoseId a, PoseId b, T value) { queues_[Key(a, b)].push_back(std::move(value)); }
  // The next value added for these endpoints; nullopt when there is none left.
  std::optional<T> Take(PoseId a, PoseId b) {
    const auto it = queues_.find(Key(a, b));
    if (it == queues_.end() || it->second.empty()) return std::nullopt;
    T value = std::move(it->second.front());
    it->second.pop_front();
    return value;
  }

 private:
  using Pair = std::pair<std::int64_t, std::int64_t>;
  static Pair Key(PoseId a, PoseId b) {
    return a.value() <= b.value() ? Pair(a.value(), b.value()) : Pair(b.value(), a.value());
  }
  std::map<Pair, std::deque<T>> queues_;
};

Eigen::Vector2d Position(const Pose2& p) { return {p.x(), p.y()}; }
const Eigen::Vector3d& Position(const Pose3& p) { return p.translation(); }

double RotationAngleOf(const Pose2& p) { return std::abs(p.theta()); }
double RotationAngleOf(const Pose3& p) { return RotationAngle(p.rotation()); }

// The rigid transform (rotation, translation) applied to a pose from the left.
Pose2 RigidTransform(const Eigen::Matrix3d& t) {
  return {t(0, 2), t(1, 2), std::atan2(t(1, 0), t(0, 0))};
}
Pose3 RigidTransform(const Eigen::Matrix4d& t) {
  return {t.block<3, 1>(0, 3), Eigen::Quaterniond(Eigen::Matrix3d(t.block<3, 3>(0, 0)))};
}

// (estimate, truth) pose pairs by id; throws as EvaluateTrajectory documents.
template <typename PoseT>
std::vector<std::pair<PoseT, PoseT>> PosePairs(const Trajectory<PoseT>& estimate, const Trajectory<PoseT>& truth) {
  if (estimate.size() < 2) {
    throw std::invalid_argument("trajectory evaluation needs at least 2 poses, the estimate has " +
                                std::to_string(estimate.size()));
  }
  std::vector<std::pair<PoseT, PoseT>> pairs;
  pairs.reserve(estimate.size());
  for (const auto& [id, pose] : estimate) {
    const auto it = truth.find(id);
    if (it == truth.end()) {
      throw std::invalid_argument("pose " + std::to_string(id.value()) +
                                  " of the estimate has no ground truth (the truth has " +
                                  std::to_string(truth.size()) + " poses)");
    }
    pairs.emplace_back(pose, it->second);
  }
  return pairs;
}

// The rigid transform taking the estimate's positions onto the truth's with
// the least squared error (Umeyama 1991, no scale).
template <typename PoseT>
PoseT AlignmentOf(const std::vector<std::pair<PoseT, PoseT>>& pairs) {
  constexpr int kDim = std::is_same_v<PoseT, Pose2> ? 2 : 3;
  // Dynamic sizes: GCC 12 reports a false stringop-overread inside Eigen's
  // umeyama() for fixed-row matrices.
  const auto n = static_cast<Eigen::Index>(pairs.size());
  Eigen::MatrixXd est(kDim, n), gt(kDim, n);
  for (Eigen::Index k = 0; k < n; ++k) {
    est.col(k) = Position(pairs[static_cast<std::size_t>(k)].first);
    gt.col(k) = Position(pairs[static_cast<std::size_t>(k)].second);
  }
  const Eigen::MatrixXd transform = Eigen::umeyama(est, gt, /*with_scaling=*/false);
  return RigidTransform(Eigen::Matrix<double, kDim + 1, kDim + 1>(transform));
}

}  // namespace

ErrorStatistics StatisticsOf(std::vector<double> errors) {
  ErrorStatistics s;
  s.count = errors.size();
  if (errors.empty()) return s;
  double sum = 0.0, sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
    s.max = std::max(s.max, e);
  }
  const double n = static_cast<double>(errors.size());
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  const std::size_t mid = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(mid), errors.end());
  s.median = errors[mid];
  if (errors.size() % 2 == 0) {
    const double lower = *std::max_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(mid));
    s.median = 0.5 * (s.median + lower);
  }
  return s;
}

template <typename PoseT>
PoseT AlignmentOnto(const Trajectory<PoseT>& estimate, const Trajectory<PoseT>& truth) {
  return AlignmentOf(PosePairs(estimate, truth));
}

template Pose2 AlignmentOnto(const Trajectory2&, const Trajectory2&);
template Pose3 AlignmentOnto(const Trajectory3&, const Trajectory3&);

template <typename PoseT>
TrajectoryEvaluation EvaluateTrajectory(const Trajectory<PoseT>& estimate,
                                        const Trajectory<PoseT>& truth) {
  const std::vector<std::pair<PoseT, PoseT>> pairs = PosePairs(estimate, truth);
  TrajectoryEvaluation result;
  result.poses = pairs.size();
  const PoseT align = AlignmentOf(pairs);
  const PoseT anchor = pairs.front().second * pairs.front().first.Inverse();
  std::vector<double> ate, anchored, rpe_t, rpe_r;
  for (const auto& [e, g] : pairs) {
    ate.push_back((Position(align * e) - Position(g)).norm());
    anchored.push_back((Position(anchor * e) - Position(g)).norm());
  }
  for (std::size_t k = 0; k + 1 < pairs.size(); ++k) {
    const PoseT d_est = pairs[k].first.Between(pairs[k + 1].first);
    const PoseT d_gt = pairs[k].second.Between(pairs[k + 1].second);
    const PoseT error = d_gt.Between(d_est);
    rpe_t.push_back(Position(error).norm());
    rpe_r.push_back(RotationAngleOf(error));
  }
  result.ate_m = StatisticsOf(std::move(ate));
  result.rmse_anchored_m = StatisticsOf(std::move(anchored)).rmse;
  result.rpe_translation_m = StatisticsOf(std::move(rpe_t));
  result.rpe_rotation_rad = StatisticsOf(std::move(rpe_r));
  return result;
}

template TrajectoryEvaluation EvaluateTrajectory(const Trajectory2&, const Trajectory2&);
template TrajectoryEvaluation EvaluateTrajectory(const Trajectory3&, const Trajectory3&);

TrajectoryEvaluation EvaluateTrajectory(const AnyTrajectory& estimate, const AnyTrajectory& truth) {
  return std::visit(
      [&truth](const auto& est) {
        using PoseT = typename std::decay_t<decltype(est)>::mapped_type;
        const Trajectory<PoseT> gt =
            std::visit([](const auto& t) { return ConvertTrajectory<PoseT>(t); }, truth);
        return EvaluateTrajectory(est, gt);
      },
      estimate);
}

std::vector<ClosureOutcome> ClosureOutcomesOf(const AnyPoseGraph& graph) {
  return std::visit(
      [](const auto& g) {
        std::vector<ClosureOutcome> outcomes;
        for (const auto& c : g.constraints) {
          if (c.IsBetweenConsecutivePoses()) continue;
          outcomes.push_back({c.from, c.to, g.IsAccepted(c)});
        }
        return outcomes;
      },
      graph);
}

std::optional<LabelMismatch> FindLabelMismatch(const AnyPoseGraph& graph, const std::vector<ClosureLabel>& labels) {
  using Pair = std::pair<PoseId, PoseId>;
  auto key = [](PoseId a, PoseId b) { return a < b ? Pair{a, b} : Pair{b, a}; };
  std::map<Pair, int> closures;  // loop closures between two poses, either direction
  std::set<PoseId> poses;
  std::visit(
      [&](const auto& g) {
        for (const auto& [id, vertex] : g.vertices) poses.insert(id);
        for (const auto& c : g.constraints) {
          if (!c.IsBetweenConsecutivePoses()) ++closures[key(c.from, c.to)];
        }
      },
      graph);
  std::map<Pair, int> labelled;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const ClosureLabel& l = labels[i];
    for (const PoseId p : {l.from, l.to}) {
      if (!poses.contains(p)) {
        return LabelMismatch{i, "pose " + std::to_string(p.value()) + " is not in the estimate; expected the labels "
                                "of this graph (catgraph inject --labels)"};
      }
    }
    const Pair k = key(l.from, l.to);
    const auto present = closures.find(k);
    // A label without its closure is one the optimiser dropped (rejected);
    // more labels than closures where some remain is a repeated row.
    if (++labelled[k] > 1 && present != closures.end() && labelled[k] > present->second) {
      return LabelMismatch{i, "closure " + std::to_string(l.from.value()) + "-" + std::to_string(l.to.value()) +
                                  " is labelled more often than the estimate has it (a repeated row?)"};
    }
  }
  for (const auto& [k, count] : closures) {
    if (labelled[k] < count) {
      return LabelMismatch{std::nullopt, "has no label for the estimate's closure " + std::to_string(k.first.value()) +
                                             "-" + std::to_string(k.second.value()) +
                                             "; expected one row per loop closure"};
    }
  }
  return std::nullopt;
}

ClosureScores ScoreClosures(const std::vector<ClosureOutcome>& outcomes,
                            const std::vector<ClosureLabel>& labels, double truth_gate) {
  ByEndpoints<const ClosureOutcome*> by_pair;
  for (const ClosureOutcome& o : outcomes) by_pair.Add(o.from, o.to, &o);
  ClosureScores s;
  for (const ClosureLabel& label : labels) {
    bool accepted = false;
    double chi2_at_truth = std::numeric_limits<double>::quiet_NaN();
    if (const auto o = by_pair.Take(label.from, label.to)) {
      accepted = (*o)->accepted;
      chi2_at_truth = (*o)->chi2_at_truth;
    }
    if (label.outlier) {
      ++(accepted ? s.false_positives : s.true_negatives);
      if (chi2_at_truth <= truth_gate) {
        ++s.outliers_explained_by_truth;
        s.explained_outliers_accepted += accepted ? 1 : 0;
      }
    } else {
      ++(accepted ? s.true_positives : s.false_negatives);
    }
  }
  const double tp = static_cast<double>(s.true_positives);
  if (s.true_positives + s.false_positives > 0) {
    s.precision = tp / static_cast<double>(s.true_positives + s.false_positives);
  }
  if (s.true_positives + s.false_negatives > 0) {
    s.recall = tp / static_cast<double>(s.true_positives + s.false_negatives);
  }
  s.f1 = s.precision + s.recall > 0.0 ? 2.0 * s.precision * s.recall / (s.precision + s.recall)
                                      : 0.0;
  const std::size_t outliers = s.true_negatives + s.false_positives;
  if (outliers > 0) {
    s.outlier_rejection = static_cast<double>(s.true_negatives) / static_cast<double>(outliers);
  }
  const std::size_t unexplained = outliers - s.outliers_explained_by_truth;
  if (unexplained > 0) {
    const std::size_t unexplained_accepted = s.false_positives - s.explained_outliers_accepted;
    s.unexplained_outlier_rejection =
        static_cast<double>(unexplained - unexplained_accepted) / static_cast<double>(unexplained);
  }
  return s;
}

void AttachChi2AtTruth(std::vector<ClosureOutcome>& outcomes, const AnyPoseGraph& graph,
                       const AnyTrajectory& truth) {
  std::visit(
      [&](const auto& g) {
        using PoseT = typename std::decay_t<decltype(g)>::Pose;
        const Trajectory<PoseT> gt =
            std::visit([](const auto& t) { return ConvertTrajectory<PoseT>(t); }, truth);
        ByEndpoints<double> by_pair;
        for (const auto& c : g.constraints) {
          if (c.IsBetweenConsecutivePoses()) continue;
          const auto from = gt.find(c.from), to = gt.find(c.to);
          by_pair.Add(c.from, c.to,
                      from == gt.end() || to == gt.end()
                          ? std::numeric_limits<double>::quiet_NaN()
                          : RelativePoseChi2(from->second, to->second, c.measurement));
        }
        for (ClosureOutcome& o : outcomes) {
          if (const auto chi2 = by_pair.Take(o.from, o.to)) o.chi2_at_truth = *chi2;
        }
      },
      graph);
}

}  // namespace catgraph
