#include "apps/plot/graph_figure.h"

#include <stdexcept>
#include <string>
#include <variant>
#include <utility>

namespace catgraph::plot {

Series PathSeries(std::string label, const Trajectory2& poses, Color color, double width_pt) {
  Series s{std::move(label), {}, {}, SeriesStyle::kLine, color, width_pt};
  for (const auto& [id, p] : poses) {
    s.x.push_back(p.x());
    s.y.push_back(p.y());
  }
  return s;
}

template <typename PoseT>
std::vector<Series> ClosureSeries(const PoseGraph<PoseT>& graph, const Trajectory2& at) {
  struct Group {
    std::string label;
    Color color;
    bool dashed = false;
    std::vector<const Constraint<PoseT>*> closures;
  };
  Group visual{"visual closure", kVisualClosureColor, false, {}};
  Group inferred{"inferred closure", kInferredClosureColor, false, {}};
  Group other{"accepted closure", kOtherClosureColor, false, {}};
  Group rejected{"rejected closure", kRejectedClosureColor, true, {}};
  for (const auto& c : graph.constraints) {
    if (c.IsBetweenConsecutivePoses()) continue;
    Group& g = !graph.IsAccepted(c)                       ? rejected
               : c.kind == ClosureKind::kVisual           ? visual
               : c.kind == ClosureKind::kOdometryInferred ? inferred
                                                          : other;
    g.closures.push_back(&c);
  }
  auto pose = [&at](PoseId id) -> const Pose2& {
    const auto it = at.find(id);
    if (it == at.end()) throw std::invalid_argument("no position to draw pose " + std::to_string(id.value()) + " at");
    return it->second;
  };
  std::vector<Series> series;
  for (Group* g : {&rejected, &visual, &inferred, &other}) {
    const std::size_t n = g->closures.size();
    if (n == 0) continue;
    // Every step-th closure, so that at most kMaxDrawnClosures are drawn.
    const std::size_t step = (n + kMaxDrawnClosures - 1) / kMaxDrawnClosures;
    Series s{g->label + " (" + std::to_string(n) + (step > 1 ? ", 1 in " + std::to_string(step) + " drawn)" : ")"),
             {},
             {},
             SeriesStyle::kSegments,
             Color{g->color.r, g->color.g, g->color.b, 0.55},
             0.7,
             g->dashed};
    for (std::size_t k = 0; k < n; k += step) {
      const Pose2& a = pose(g->closures[k]->from);
      const Pose2& b = pose(g->closures[k]->to);
      s.x.insert(s.x.end(), {a.x(), b.x()});
      s.y.insert(s.y.end(), {a.y(), b.y()});
    }
    series.push_back(std::move(s));
  }
  return series;
}

template std::vector<Series> ClosureSeries(const PoseGraph2&, const Trajectory2&);
template std::vector<Series> ClosureSeries(const PoseGraph3&, const Trajectory2&);

Axes GraphAxes(const AnyPoseGraph& any, const std::string& title) {
  const Trajectory2 poses =
      std::visit([](const auto& g) { return ConvertTrajectory<Pose2>(TrajectoryOf(g)); }, any);
  Axes axes;
  axes.title = title;
  axes.x_label = "x (m)";
  axes.y_label = "y (m)";
  axes.equal_aspect = true;
  axes.series = std::visit([&poses](const auto& g) { return ClosureSeries(g, poses); }, any);
  axes.series.push_back(PathSeries("trajectory", poses, kTrajectoryColor, 1.0));
  return axes;
}

Figure GraphFigure(const AnyPoseGraph& graph, const std::string& title) {
  Figure figure;
  figure.width_px = figure.height_px = 900;
  figure.axes.push_back(GraphAxes(graph, title));
  return figure;
}

}  // namespace catgraph::plot
