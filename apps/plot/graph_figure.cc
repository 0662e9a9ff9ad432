#include "apps/plot/graph_figure.h"

#include "backend/graph/trajectory.h"

namespace catgraph::plot {
namespace {

Series Segments(const std::string& label, const Color& color) {
  Series s;
  s.label = label;
  s.style = SeriesStyle::kSegments;
  s.color = color;
  s.width_pt = 0.8;
  return s;
}

template <typename PoseT>
Axes Build(const PoseGraph<PoseT>& graph, const std::string& title) {
  const Trajectory2 poses = ConvertTrajectory<Pose2>(TrajectoryOf(graph));
  Series odometry = Segments("odometry", {0.45, 0.45, 0.45});
  Series accepted = Segments("accepted closure", {0.0, 0.62, 0.45});
  Series rejected = Segments("rejected closure", {0.84, 0.15, 0.16});
  rejected.dashed = true;
  for (const auto& c : graph.constraints) {
    Series& s = c.IsBetweenConsecutivePoses() ? odometry
                : graph.IsAccepted(c) ? accepted
                                                                                : rejected;
    const Pose2& a = poses.at(c.from);
    const Pose2& b = poses.at(c.to);
    s.x.insert(s.x.end(), {a.x(), b.x()});
    s.y.insert(s.y.end(), {a.y(), b.y()});
  }
  Axes axes;
  axes.title = title;
  axes.x_label = "x (m)";
  axes.y_label = "y (m)";
  axes.equal_aspect = true;
  for (Series* s : {&odometry, &accepted, &rejected}) {
    s->label += " (" + std::to_string(s->x.size() / 2) + ")";
    axes.series.push_back(std::move(*s));
  }
  return axes;
}

}  // namespace

Axes GraphAxes(const AnyPoseGraph& graph, const std::string& title) {
  return std::visit([&title](const auto& g) { return Build(g, title); }, graph);
}

Figure GraphFigure(const AnyPoseGraph& graph, const std::string& title) {
  Figure figure;
  figure.width_px = figure.height_px = 900;
  figure.axes.push_back(GraphAxes(graph, title));
  return figure;
}

}  // namespace catgraph::plot
