// Pictures of pose graphs: the trajectory with its loop closures.
#ifndef CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_
#define CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_

#include <string>
#include <vector>

#include "apps/plot/figure.h"
#include "backend/graph/pose_graph.h"
#include "backend/graph/trajectory.h"

namespace catgraph::plot {

// A series of more loop closures than this is thinned evenly when drawn
// (its legend says so): beyond it the lines hide the path they join.
inline constexpr std::size_t kMaxDrawnClosures = 200;

// The poses of `poses` in id order as one polyline.
Series PathSeries(std::string label, const Trajectory2& poses, Color color, double width_pt);

// The loop closures of `graph` as lines between their poses in `at` (the
// graph's own poses, or the same poses moved), one series per decision and
// kind in figure.h's colours, thin and translucent so that a path drawn
// after them stays visible; each legend gives the count. Series without a
// closure are left out. Throws std::invalid_argument when `at` lacks an
// endpoint. Defined for PoseGraph2 and PoseGraph3 (drawn from above).
template <typename PoseT>
std::vector<Series> ClosureSeries(const PoseGraph<PoseT>& graph, const Trajectory2& at);

// The x-y plane of the graph, one metre one metre: its closures, then its
// trajectory over them. Throws std::invalid_argument when a pose has no value.
Axes GraphAxes(const AnyPoseGraph& graph, const std::string& title);
Figure GraphFigure(const AnyPoseGraph& graph, const std::string& title);

}  // namespace catgraph::plot

#endif  // CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_
