// Publication-style figures — line plots and trajectory maps — drawn with
// cairo and written as PNG or SVG from the same drawing code.
//
// A Figure is a grid of Axes; each Axes holds Series of one of three styles:
// a polyline, separate segments (x0, y0, x1, y1 taken pairwise), or markers.
// Axes pick their ranges from the data unless given; `equal_aspect` keeps one
// metre one metre (maps). Nothing here knows about pose graphs.
#ifndef CATGRAPH_APPS_PLOT_FIGURE_H_
#define CATGRAPH_APPS_PLOT_FIGURE_H_

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace catgraph::plot {

struct Color {
  double r = 0.0, g = 0.0, b = 0.0, a = 1.0;
};

// A colour-blind-safe qualitative palette (Okabe & Ito 2008); wraps around.
Color PaletteColor(int index);

// What every catgraph figure draws in the same colour (from the palette
// above): a trajectory blue and its ground truth dark grey; accepted visual
// loop closures bluish green, accepted odometry-inferred ones orange,
// accepted closures of another or unknown kind sky blue; rejected closures
// vermillion (dashed); frames that see a changed region reddish purple.
inline constexpr Color kTrajectoryColor{0.000, 0.447, 0.698};
inline constexpr Color kTruthColor{0.25, 0.25, 0.25, 0.7};
inline constexpr Color kVisualClosureColor{0.000, 0.620, 0.451};
inline constexpr Color kInferredClosureColor{0.902, 0.624, 0.000};
inline constexpr Color kOtherClosureColor{0.337, 0.706, 0.914};
inline constexpr Color kRejectedClosureColor{0.835, 0.369, 0.000};
inline constexpr Color kChangedRegionColor{0.800, 0.475, 0.655};
inline constexpr Color kWallColor{0.6, 0.6, 0.6};

enum class SeriesStyle { kLine, kSegments, kMarkers };
enum class Scale {
  kLinear,
  kLog,     // log10; values <= 0 are left out
  kSymlog,  // log10(1 + v): 0, 10, 100, 1000 evenly apart (outlier counts)
};

struct Series {
  std::string label;  // empty: not in the legend
  std::vector<double> x, y;
  SeriesStyle style = SeriesStyle::kLine;
  Color color;
  double width_pt = 1.5;
  bool dashed = false;
  bool markers = false;  // kLine: also mark every point
};

struct Axes {
  std::string title, x_label, y_label;
  Scale x_scale = Scale::kLinear, y_scale = Scale::kLinear;
  std::optional<double> x_min, x_max, y_min, y_max;  // unset: from the data
  bool equal_aspect = false;
  bool legend = true;  // below the x label, outside the data
  std::vector<Series> series;
};

struct Figure {
  int width_px = 900, height_px = 600;  // one panel's size is this / the grid
  int rows = 1, cols = 1;
  std::string title;
  std::vector<Axes> axes;  // row-major; at most rows * cols
};

// Writes `figure` as PNG or SVG, chosen by the extension (.png, .svg),
// atomically. Throws FileError on an unknown extension or a write failure.
void SaveFigure(const Figure& figure, const std::filesystem::path& path);

// The extension of `path` without its dot, in lower case ("x.PNG" -> "png"):
// how every command tells an output's format from its name.
std::string LowerCaseExtension(const std::filesystem::path& path);

}  // namespace catgraph::plot

#endif  // CATGRAPH_APPS_PLOT_FIGURE_H_
