#include "backend/initialization.h"

#include <cmath>
#include <deque>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/SVD>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "backend/factors.h"

namespace catgraph {
namespace {

template <typename PoseT>
void Initialize(PoseGraph<PoseT>& graph, bool overwrite) {
  struct Arc {
    PoseId other;
    PoseT T_self_other;
    bool odometry;
  };
  std::unordered_map<PoseId, std::vector<Arc>> arcs;
  for (const auto& c : graph.constraints) {
    const bool odometry = c.kind == ClosureKind::kOdometry;
    arcs[c.from].push_back({c.to, c.measurement.mean, odometry});
    arcs[c.to].push_back({c.from, c.measurement.mean.Inverse(), odometry});
  }
  std::unordered_map<PoseId, PoseT> placed;
  // Breadth-first from `frontier` over arcs accepted by `use`.
  auto grow = [&](std::deque<PoseId> frontier, bool odometry_only) {
    while (!frontier.empty()) {
      const PoseId id = frontier.front();
      frontier.pop_front();
      for (const Arc& arc : arcs[id]) {
        if ((odometry_only && !arc.odometry) || placed.contains(arc.other)) continue;
        placed.emplace(arc.other, placed.at(id) * arc.T_self_other);
        frontier.push_back(arc.other);
      }
    }
  };
  for (const auto& [root, vertex] : graph.vertices) {  // ascending ids
    if (placed.contains(root)) continue;
    placed.emplace(root, (!overwrite && vertex.pose) ? *vertex.pose : PoseT::Identity());
    std::deque<PoseId> component{root};
    grow(component, true);
    std::deque<PoseId> all;
    for (const auto& [id, pose] : placed) all.push_back(id);
    grow(all, false);
  }
  for (auto& [id, vertex] : graph.vertices) {
    if (overwrite || !vertex.pose) vertex.pose = placed.at(id);
  }
}

}  // namespace

void InitializeBySpanningTree(PoseGraph2& graph, bool overwrite) { Initialize(graph, overwrite); }
void InitializeBySpanningTree(PoseGraph3& graph, bool overwrite) { Initialize(graph, overwrite); }

}  // namespace catgraph

// ---------------------------------------------------------------------------
// Chordal initialisation.

namespace catgraph {
namespace {

template <int D>
using RotationMatrix = Eigen::Matrix<double, D, D>;

RotationMatrix<2> RotationOf(const Pose2& p) { return p.rotation(); }
RotationMatrix<3> RotationOf(const Pose3& p) { return p.rotation().toRotationMatrix(); }
Eigen::Vector2d TranslationOf(const Pose2& p) { return p.translation(); }
Eigen::Vector3d TranslationOf(const Pose3& p) { return p.translation(); }
Pose2 MakePose(const RotationMatrix<2>& r, const Eigen::Vector2d& t) {
  return {t.x(), t.y(), std::atan2(r(1, 0), r(0, 0))};
}
Pose3 MakePose(const RotationMatrix<3>& r, const Eigen::Vector3d& t) {
  return {t, Eigen::Quaterniond(r)};
}

template <int D>
RotationMatrix<D> ProjectToRotation(const RotationMatrix<D>& m) {
  Eigen::JacobiSVD<RotationMatrix<D>> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  RotationMatrix<D> s = RotationMatrix<D>::Identity();
  s(D - 1, D - 1) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * s * svd.matrixV().transpose();
}

// Solves min ||A X - B||_F through the normal equations, for the columns of
// B at once: one factorisation, as many solves.
Eigen::MatrixXd SolveLeastSquares(int unknowns, const std::vector<Eigen::Triplet<double>>& a,
                                  const Eigen::MatrixXd& b) {
  Eigen::SparseMatrix<double> m(b.rows(), unknowns);
  m.setFromTriplets(a.begin(), a.end());
  const Eigen::SparseMatrix<double> normal = m.transpose() * m;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  if (solver.info() != Eigen::Success) {
    throw std::invalid_argument("chordal initialisation: the graph is not connected");
  }
  return solver.solve(m.transpose() * b);
}

template <typename PoseT>
void Chordal(PoseGraph<PoseT>& graph) {
  constexpr int kD = PoseGraph<PoseT>::kDimension;
  const PoseId root = graph.vertices.begin()->first;
  std::unordered_map<PoseId, int> index;  // root excluded: it is the anchor
  for (const auto& [id, v] : graph.vertices) {
    if (id != root) index.emplace(id, static_cast<int>(index.size()));
  }
  const int n = static_cast<int>(index.size());
  const int rows = static_cast<int>(graph.constraints.size()) * kD;
  // Rotations. Row r of each R_j is R_i's row r times R_ij: R_ij^T x_{i,r} -
  // x_{j,r} = 0. The D rows are D least-squares problems with one matrix (D
  // unknowns per vertex) and their own right-hand sides (R_root = I known):
  // one factorisation solves them all.
  std::vector<Eigen::Triplet<double>> a;
  Eigen::MatrixXd b = Eigen::MatrixXd::Zero(rows, kD);
  int row = 0;
  for (const auto& e : graph.constraints) {
    const double w = std::sqrt(ChordalWeightsOf(e.measurement.information).kappa);
    const RotationMatrix<kD> rt = RotationOf(e.measurement.mean).transpose();
    for (int k = 0; k < kD; ++k, ++row) {
      // sum_c rt(k, c) x_{i,r,c} - x_{j,r,k} = 0.
      for (int c = 0; c < kD; ++c) {
        if (e.from == root) {
          b(row, c) -= w * rt(k, c);  // x_{root,r,c} = (r == c)
        } else {
          a.emplace_back(row, index.at(e.from) * kD + c, w * rt(k, c));
        }
      }
      if (e.to == root) {
        b(row, k) += w;
      } else {
        a.emplace_back(row, index.at(e.to) * kD + k, -w);
      }
    }
  }
  const Eigen::MatrixXd x = SolveLeastSquares(n * kD, a, b);  // column r: the rows r
  std::unordered_map<PoseId, RotationMatrix<kD>> rotations;
  rotations.emplace(root, RotationMatrix<kD>::Identity());
  for (const auto& [id, k] : index) {
    RotationMatrix<kD> m;
    for (int r = 0; r < kD; ++r) {
      for (int c = 0; c < kD; ++c) m(r, c) = x(k * kD + c, r);
    }
    rotations.emplace(id, ProjectToRotation<kD>(m));
  }
  // Translations: t_j - t_i = R_i t_ij, t_root = 0; the D coordinates are D
  // problems with one matrix (a weighted graph Laplacian).
  a.clear();
  b.setZero(static_cast<int>(graph.constraints.size()), kD);
  row = 0;
  for (const auto& e : graph.constraints) {
    const double w = std::sqrt(ChordalWeightsOf(e.measurement.information).tau);
    b.row(row) = (w * rotations.at(e.from) * TranslationOf(e.measurement.mean)).transpose();
    if (e.to != root) a.emplace_back(row, index.at(e.to), w);
    if (e.from != root) a.emplace_back(row, index.at(e.from), -w);
    ++row;
  }
  const Eigen::MatrixXd t = SolveLeastSquares(n, a, b);
  const auto& root_vertex = graph.vertices.at(root);
  const PoseT anchor = root_vertex.pose ? *root_vertex.pose : PoseT::Identity();
  for (auto& [id, v] : graph.vertices) {
    Eigen::Matrix<double, kD, 1> translation = Eigen::Matrix<double, kD, 1>::Zero();
    if (id != root) translation = t.row(index.at(id)).transpose();
    v.pose = anchor * MakePose(rotations.at(id), translation);
  }
}

}  // namespace

void InitializeChordal(PoseGraph2& graph) { Chordal(graph); }
void InitializeChordal(PoseGraph3& graph) { Chordal(graph); }

}  // namespace catgraph
