#include "backend/graph_summary.h"

#include <cmath>
#include <numeric>
#include <sstream>
#include <unordered_map>
#include <variant>
#include <vector>

#include <Eigen/Cholesky>

namespace catgraph {
namespace {

// Disjoint sets over vertex indices, with path halving.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    std::iota(parent_.begin(), parent_.end(), std::size_t{0});
  }
  std::size_t Find(std::size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  void Union(std::size_t a, std::size_t b) { parent_[Find(a)] = Find(b); }

 private:
  std::vector<std::size_t> parent_;
};

// The nearest number with two significant digits, e.g. 1999.88 -> 2000.
double RoundToTwoSignificantDigits(double v) {
  const double scale = std::pow(10.0, std::floor(std::log10(v)) - 1.0);
  return std::round(v / scale) * scale;
}

bool IsRound(double v, double relative_tolerance) {
  const double r = RoundToTwoSignificantDigits(v);
  return std::abs(v - r) <= relative_tolerance * r;
}

// True when a diagonal entry d is not itself round but d^2 is round to the
// precision such files are printed with (44.72^2 = 1999.88 ~ 2000).
template <int N>
bool DiagonalLooksLikeSquareRoot(const Eigen::Matrix<double, N, N>& information,
                                 std::string* example) {
  for (int k = 0; k < N; ++k) {
    const double d = information(k, k);
    if (d > 0.0 && !IsRound(d, 2e-4) && IsRound(d * d, 2e-4)) {
      std::ostringstream text;
      text << d << " = sqrt(" << RoundToTwoSignificantDigits(d * d) << ")";
      *example = text.str();
      return true;
    }
  }
  return false;
}

template <typename PoseT>
GraphSummary SummarizeGraph(const PoseGraph<PoseT>& graph) {
  GraphSummary s;
  s.dimension = PoseGraph<PoseT>::kDimension;
  s.vertices = graph.vertices.size();
  s.edges = graph.constraints.size();
  s.switches = graph.switches.size();
  std::unordered_map<PoseId, std::size_t> index;
  for (const auto& [id, vertex] : graph.vertices) {
    index.emplace(id, index.size());
    if (!vertex.pose) ++s.vertices_without_pose;
    if (vertex.fixed) ++s.fixed_vertices;
  }
  DisjointSets sets(s.vertices);
  std::size_t square_root_like = 0;
  for (const Constraint<PoseT>& c : graph.constraints) {
    (c.IsBetweenConsecutivePoses() ? s.odometry_edges : s.loop_closures) += 1;
    if (c.switch_id) ++s.switchable_edges;
    if (c.maxmix_weight) ++s.maxmix_edges;
    ++s.edges_by_kind[c.kind];
    sets.Union(index.at(c.from), index.at(c.to));
    if (c.measurement.information.llt().info() != Eigen::Success) ++s.indefinite_information_edges;
    std::string example;
    if (DiagonalLooksLikeSquareRoot<PoseT::kTangentDim>(c.measurement.information, &example)) {
      ++square_root_like;
      if (s.square_root_information_example.empty()) s.square_root_information_example = example;
    }
  }
  for (std::size_t i = 0; i < s.vertices; ++i) {
    if (sets.Find(i) == i) ++s.connected_components;
  }
  s.connected = s.connected_components == 1;
  s.looks_like_square_root_information = s.edges > 0 && 2 * square_root_like > s.edges;
  if (!s.looks_like_square_root_information) s.square_root_information_example.clear();
  return s;
}

}  // namespace

GraphSummary Summarize(const AnyPoseGraph& graph) {
  return std::visit([](const auto& g) { return SummarizeGraph(g); }, graph);
}

}  // namespace catgraph
