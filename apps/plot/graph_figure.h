// Pictures of pose graphs: the trajectory with its loop closures.
#ifndef CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_
#define CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_

#include <string>

#include "apps/plot/figure.h"
#include "backend/graph/pose_graph.h"

namespace catgraph::plot {

// The x-y plane of the graph, one metre one metre: odometry as a grey line,
// accepted loop closures green, rejected ones (switch <= 0.5) red and dashed.
// Throws std::invalid_argument when a pose has no value.
Axes GraphAxes(const AnyPoseGraph& graph, const std::string& title);
Figure GraphFigure(const AnyPoseGraph& graph, const std::string& title);

}  // namespace catgraph::plot

#endif  // CATGRAPH_APPS_PLOT_GRAPH_FIGURE_H_
