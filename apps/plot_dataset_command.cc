// catgraph plot-dataset DATASET -o plan.svg|png [--pair-at X,Y --pair-output pair.png]
//
// The floor plan of a simulated dataset with every traversal's true path,
// the furniture of each traversal and the changed regions; optionally the
// frames of each traversal nearest to one place, side by side.
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "apps/commands.h"
#include "apps/localization_report.h"
#include "apps/plot/figure.h"
#include "backend/io/atomic_file.h"
#include "backend/io/dataset.h"
#include "backend/io/output_directory.h"
#include "frontend/vocabulary.h"

namespace catgraph {
namespace {

struct PlotDatasetOptions {
  std::string dataset, output, title, pair_at, pair_output;
};

void AddPolygon(plot::Series& s, const Polygon2& polygon) {
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const auto& a = polygon[i];
    const auto& b = polygon[(i + 1) % polygon.size()];
    s.x.insert(s.x.end(), {a.x(), b.x()});
    s.y.insert(s.y.end(), {a.y(), b.y()});
  }
}

plot::Figure PlanFigure(const Dataset& d, const std::string& title) {
  plot::Axes axes;
  axes.title = title.empty() ? d.meta.scenario : title;
  axes.x_label = "x (m)";
  axes.y_label = "y (m)";
  axes.equal_aspect = true;
  for (const auto& r : d.meta.changed_regions) {
    plot::Series s{r.name.empty() ? "changed region" : r.name, {}, {}, plot::SeriesStyle::kSegments,
                   plot::Color{plot::kChangedRegionColor.r, plot::kChangedRegionColor.g, plot::kChangedRegionColor.b, 0.4},
                   7.0};
    AddPolygon(s, r.polygon);
    axes.series.push_back(std::move(s));
  }
  plot::Series walls = WallsSeries(d, "walls", {0.1, 0.1, 0.1, 1.0}, 1.0);
  if (!walls.x.empty()) axes.series.push_back(std::move(walls));
  const std::vector<int> traversals = d.Traversals();
  plot::Series everywhere{"furniture (every traversal)", {}, {}, plot::SeriesStyle::kSegments, {0.45, 0.45, 0.45, 1.0}, 1.2};
  for (std::size_t k = 0; k < traversals.size(); ++k) {
    plot::Series only{"furniture (traversal " + std::to_string(traversals[k]) + " only)", {}, {},
                      plot::SeriesStyle::kSegments, plot::PaletteColor(static_cast<int>(k)), 1.6};
    for (const auto& f : d.meta.furniture) {
      if (f.traversals.size() >= traversals.size()) {
        if (k == 0) AddPolygon(everywhere, f.polygon);
      } else if (f.traversals == std::vector<int>{traversals[k]}) {
        AddPolygon(only, f.polygon);
      }
    }
    if (!only.x.empty()) axes.series.push_back(std::move(only));
  }
  if (!everywhere.x.empty()) axes.series.push_back(std::move(everywhere));
  if (d.HasGroundTruth()) {
    for (std::size_t k = 0; k < traversals.size(); ++k) {
      plot::Series path{"traversal " + std::to_string(traversals[k]), {}, {}, plot::SeriesStyle::kLine,
                        plot::PaletteColor(static_cast<int>(k)), 1.2};
      path.dashed = k > 0;
      for (const auto& f : d.frames) {
        if (f.traversal != traversals[k]) continue;
        const Pose2 p = InterpolatePose(d.ground_truth, f.timestamp_s);
        path.x.push_back(p.x());
        path.y.push_back(p.y());
      }
      axes.series.push_back(std::move(path));
    }
  }
  plot::Figure figure;
  figure.width_px = 1400;
  figure.height_px = 800;
  figure.axes.push_back(std::move(axes));
  return figure;
}

// The frames of each traversal nearest to `place`, side by side, enlarged
// three times (nearest neighbour: the pixels as they are).
void WritePair(const Dataset& d, const Eigen::Vector2d& place, const std::filesystem::path& output,
               std::ostream& out) {
  if (!d.HasGroundTruth()) throw std::invalid_argument(d.root.string() + ": --pair-at needs ground truth");
  std::vector<cv::Mat> panels;
  for (const int traversal : d.Traversals()) {
    std::size_t best = 0;
    double best_d = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < d.frames.size(); ++i) {
      if (d.frames[i].traversal != traversal) continue;
      const double dist = (InterpolatePose(d.ground_truth, d.frames[i].timestamp_s).translation() - place).norm();
      if (dist < best_d) best_d = dist, best = i;
    }
    const cv::Mat image = ReadImage(d.ImagePath(best));
    cv::Mat big;
    cv::resize(image, big, cv::Size(), 3.0, 3.0, cv::INTER_NEAREST);
    cv::Mat panel(big.rows + 36, big.cols, CV_8UC3, cv::Scalar(255, 255, 255));
    big.copyTo(panel(cv::Rect(0, 36, big.cols, big.rows)));
    char caption[128];
    std::snprintf(caption, sizeof caption, "traversal %d, frame %zu (%.2f m away)%s", traversal, best,
                  best_d, d.frames[best].changed ? ", changed" : "");
    cv::putText(panel, caption, cv::Point(8, 25), cv::FONT_HERSHEY_SIMPLEX, 0.7, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    if (!panels.empty()) panels.push_back(cv::Mat(panel.rows, 12, CV_8UC3, cv::Scalar(255, 255, 255)));
    panels.push_back(panel);
  }
  cv::Mat pair;
  cv::hconcat(panels, pair);
  std::vector<std::uint8_t> png;
  cv::imencode(".png", pair, png);
  WriteBytesAtomically(output, png);
  out << "wrote " << output.string() << '\n';
}

Eigen::Vector2d ParsePlace(const std::string& text) {
  std::istringstream in(text);
  double x = 0.0, y = 0.0;
  char comma = 0;
  if (!(in >> x >> comma >> y) || comma != ',' || !in.eof()) {
    throw std::invalid_argument("--pair-at '" + text + "': expected X,Y in metres");
  }
  return {x, y};
}

void RunPlotDataset(const PlotDatasetOptions& o, std::ostream& out) {
  const Dataset d = ReadDataset(o.dataset);
  RefuseOutputClashes({o.output, o.pair_output}, DatasetFiles(d));
  plot::SaveFigure(PlanFigure(d, o.title), o.output);
  out << "wrote " << o.output << '\n';
  if (!o.pair_at.empty() || !o.pair_output.empty()) {
    if (o.pair_at.empty() || o.pair_output.empty()) {
      throw std::invalid_argument("--pair-at and --pair-output go together");
    }
    WritePair(d, ParsePlace(o.pair_at), o.pair_output, out);
  }
}

}  // namespace

void AddPlotDatasetCommand(CLI::App& app, std::ostream& out) {
  auto o = std::make_shared<PlotDatasetOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plot-dataset",
      "Draw a dataset's floor plan with each traversal's true path, the furniture of each "
      "traversal and the changed regions (PNG or SVG); optionally each traversal's frame nearest "
      "to one place, side by side.");
  cmd->add_option("dataset", o->dataset, "Dataset directory")->required();
  cmd->add_option("-o,--output", o->output, "Picture to write (.png or .svg)")->required();
  cmd->add_option("--title", o->title, "Title (default: the scenario)");
  cmd->add_option("--pair-at", o->pair_at, "X,Y: also show the frames nearest to this place");
  cmd->add_option("--pair-output", o->pair_output, "PNG for the frames of --pair-at");
  cmd->callback([o, &out] { RunPlotDataset(*o, out); });
}

}  // namespace catgraph
