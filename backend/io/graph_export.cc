#include "backend/io/graph_export.h"

#include <ostream>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "backend/graph/trajectory.h"
#include "backend/io/atomic_file.h"

namespace catgraph {
namespace {

nlohmann::json PoseJson(const Pose2& p) { return {{"x", p.x()}, {"y", p.y()}, {"theta", p.theta()}}; }
nlohmann::json PoseJson(const Pose3& p) {
  const auto& t = p.translation();
  const auto& q = p.rotation();
  return {{"t", {t.x(), t.y(), t.z()}}, {"q", {q.x(), q.y(), q.z(), q.w()}}};
}

template <typename PoseT>
nlohmann::json GraphJson(const PoseGraph<PoseT>& graph) {
  nlohmann::json j = {{"format", "catgraph-graph"},
                      {"version", 1},
                      {"dimension", PoseGraph<PoseT>::kDimension}};
  j["vertices"] = nlohmann::json::array();
  for (const auto& [id, v] : graph.vertices) {
    j["vertices"].push_back({{"id", id.value()},
                             {"pose", v.pose ? PoseJson(*v.pose) : nlohmann::json()},
                             {"fixed", v.fixed}});
  }
  j["constraints"] = nlohmann::json::array();
  for (const auto& c : graph.constraints) {
    nlohmann::json parents = nlohmann::json::array();
    for (ClosureId p : c.provenance.parents) parents.push_back(p.value());
    nlohmann::json information = nlohmann::json::array();
    for (int r = 0; r < PoseT::kTangentDim; ++r) {
      nlohmann::json row = nlohmann::json::array();
      for (int k = 0; k < PoseT::kTangentDim; ++k) row.push_back(c.measurement.information(r, k));
      information.push_back(row);
    }
    nlohmann::json e = {{"id", c.id.value()},
                        {"from", c.from.value()},
                        {"to", c.to.value()},
                        {"kind", ToString(c.kind)},
                        {"parents", parents},
                        {"measurement", PoseJson(c.measurement.mean)},
                        {"information", information},
                        {"accepted", graph.IsAccepted(c)}};
    if (c.switch_id) e["switch"] = c.switch_id->value();
    if (c.maxmix_weight) e["maxmix_weight"] = *c.maxmix_weight;
    j["constraints"].push_back(e);
  }
  j["switches"] = nlohmann::json::array();
  for (const auto& [id, s] : graph.switches) {
    nlohmann::json sj = {{"id", id.value()}, {"value", s.value}};
    if (s.prior) {
      sj["prior_mean"] = s.prior->mean;
      sj["prior_information"] = s.prior->information;
    }
    j["switches"].push_back(sj);
  }
  return j;
}

template <typename PoseT>
void Dot(const PoseGraph<PoseT>& graph, std::ostream& out) {
  constexpr double kPointsPerMetre = 10.0;
  const Trajectory2 positions = ConvertTrajectory<Pose2>(TrajectoryOf(graph));
  out << "graph catgraph {\n"
      << "  // Positions are pinned: render with `neato -n2 -Tpdf`.\n"
      << "  node [shape=point, width=0.03];\n"
      << "  edge [penwidth=0.6];\n";
  for (const auto& [id, p] : positions) {
    out << "  " << id.value() << " [pos=\"" << p.x() * kPointsPerMetre << ','
        << p.y() * kPointsPerMetre << "!\"];\n";
  }
  for (const auto& c : graph.constraints) {
    out << "  " << c.from.value() << " -- " << c.to.value() << " [";
    if (c.kind == ClosureKind::kOdometry) {
      out << "color=gray50";
    } else if (graph.IsAccepted(c)) {
      out << "color=forestgreen, tooltip=\"" << ToString(c.kind) << ' ' << c.id.value() << '"';
    } else {
      out << "color=red, style=dashed, tooltip=\"rejected " << ToString(c.kind) << ' '
          << c.id.value() << '"';
    }
    out << "];\n";
  }
  out << "}\n";
}

}  // namespace

void WriteGraphJson(const AnyPoseGraph& graph, std::ostream& out) {
  out << std::visit([](const auto& g) { return GraphJson(g); }, graph).dump() << '\n';
}

void WriteGraphDot(const AnyPoseGraph& graph, std::ostream& out) {
  std::visit([&out](const auto& g) { Dot(g, out); }, graph);
}

void WriteGraphJsonFile(const AnyPoseGraph& graph, const std::filesystem::path& path) {
  WriteFileAtomically(path, [&](std::ostream& out) { WriteGraphJson(graph, out); });
}

void WriteGraphDotFile(const AnyPoseGraph& graph, const std::filesystem::path& path) {
  WriteFileAtomically(path, [&](std::ostream& out) { WriteGraphDot(graph, out); });
}

}  // namespace catgraph
