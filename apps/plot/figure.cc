#include "apps/plot/figure.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <ostream>
#include <string>

#include <cairo-svg.h>
#include <cairo.h>

#include "backend/io/atomic_file.h"
#include "backend/io/file_error.h"

namespace catgraph::plot {
namespace {

constexpr double kMarginLeft = 72.0, kMarginRight = 16.0, kMarginTop = 34.0, kMarginBottom = 48.0;
constexpr double kFontSize = 12.0;

double Forward(Scale scale, double v) {
  switch (scale) {
    case Scale::kLinear: return v;
    case Scale::kLog: return v > 0.0 ? std::log10(v) : std::numeric_limits<double>::quiet_NaN();
    case Scale::kSymlog: return v > -1.0 ? std::log10(1.0 + v) : std::numeric_limits<double>::quiet_NaN();
  }
  return v;
}

struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  void Add(double v) {
    if (!std::isfinite(v)) return;
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  bool Empty() const { return !(lo <= hi); }
  double Span() const { return hi - lo; }
};

// The range in scaled units, padded and never empty.
Range ScaledRange(const Axes& axes, bool x) {
  const Scale scale = x ? axes.x_scale : axes.y_scale;
  Range r;
  for (const Series& s : axes.series) {
    for (double v : x ? s.x : s.y) r.Add(Forward(scale, v));
  }
  const auto& lo = x ? axes.x_min : axes.y_min;
  const auto& hi = x ? axes.x_max : axes.y_max;
  if (r.Empty()) r = {Forward(scale, scale == Scale::kLog ? 1.0 : 0.0), Forward(scale, 1.0)};
  if (r.Span() == 0.0) {
    const double pad = r.lo == 0.0 ? 1.0 : 0.1 * std::abs(r.lo);
    r = {r.lo - pad, r.hi + pad};
  } else if (scale == Scale::kLinear) {
    const double pad = 0.04 * r.Span();
    r = {r.lo - pad, r.hi + pad};
  }
  if (lo) r.lo = Forward(scale, *lo);
  if (hi) r.hi = Forward(scale, *hi);
  return r;
}

std::string FormatTick(double v) {
  char buffer[32];
  if (v != 0.0 && (std::abs(v) >= 1e5 || std::abs(v) < 1e-3)) {
    std::snprintf(buffer, sizeof buffer, "%.0e", v);
  } else {
    std::snprintf(buffer, sizeof buffer, "%g", v);
  }
  return buffer;
}

// Tick positions in scaled units with their labels.
std::vector<std::pair<double, std::string>> Ticks(Scale scale, const Range& r) {
  std::vector<std::pair<double, std::string>> ticks;
  if (scale == Scale::kLinear) {
    const double raw = r.Span() / 5.0;
    const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
    double step = magnitude;
    for (double m : {1.0, 2.0, 5.0, 10.0}) {
      step = m * magnitude;
      if (step >= raw) break;
    }
    for (double v = std::ceil(r.lo / step) * step; v <= r.hi + 1e-9 * step; v += step) {
      ticks.emplace_back(v, FormatTick(std::abs(v) < 1e-12 * step ? 0.0 : v));
    }
    return ticks;
  }
  // Powers of ten (and 0 for symlog); also 2 and 5 times them when the
  // range spans less than two decades.
  if (scale == Scale::kSymlog && r.lo <= 0.0) ticks.emplace_back(0.0, "0");
  const bool fine = r.Span() < 2.0;
  for (int e = -12; e <= 12; ++e) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double v = m * std::pow(10.0, e);
      const double f = Forward(scale, v);
      if (f >= r.lo - 1e-9 && f <= r.hi + 1e-9 && (scale == Scale::kLog || e >= 0)) {
        ticks.emplace_back(f, FormatTick(v));
      }
    }
  }
  return ticks;
}

void SetColor(cairo_t* cr, const Color& c) { cairo_set_source_rgba(cr, c.r, c.g, c.b, c.a); }

double TextWidth(cairo_t* cr, const std::string& text) {
  cairo_text_extents_t e;
  cairo_text_extents(cr, text.c_str(), &e);
  return e.x_advance;
}

void ShowText(cairo_t* cr, double x, double y, const std::string& text, double align_x = 0.0) {
  cairo_move_to(cr, x - align_x * TextWidth(cr, text), y);
  cairo_show_text(cr, text.c_str());
}

// The legend's entries laid out left to right below the x label, wrapping
// at `width`: each entry's top-left corner, relative to the legend's.
struct LegendLayout {
  std::vector<const Series*> entries;
  std::vector<std::pair<double, double>> at;
  double height = 0.0;
};

constexpr double kLegendRow = kFontSize + 6.0, kLegendKey = 30.0, kLegendGap = 18.0;

LegendLayout LayOutLegend(cairo_t* cr, const Axes& axes, double width) {
  LegendLayout layout;
  if (!axes.legend) return layout;
  for (const Series& s : axes.series) {
    if (!s.label.empty()) layout.entries.push_back(&s);
  }
  if (layout.entries.empty()) return layout;
  cairo_set_font_size(cr, kFontSize);
  double x = 0.0, y = 0.0;
  for (const Series* s : layout.entries) {
    const double entry_w = kLegendKey + 4.0 + TextWidth(cr, s->label);
    if (x > 0.0 && x + entry_w > width) {
      x = 0.0;
      y += kLegendRow;
    }
    layout.at.emplace_back(x, y);
    x += entry_w + kLegendGap;
  }
  layout.height = y + kLegendRow + 4.0;
  return layout;
}

void DrawLegend(cairo_t* cr, const LegendLayout& layout, double left, double top) {
  for (std::size_t k = 0; k < layout.entries.size(); ++k) {
    const Series& s = *layout.entries[k];
    const double x = left + layout.at[k].first, y = top + layout.at[k].second + kLegendRow / 2.0;
    SetColor(cr, Color{s.color.r, s.color.g, s.color.b, std::max(s.color.a, 0.8)});
    cairo_set_line_width(cr, std::max(s.width_pt, 1.2));
    const double dash[] = {4.0 * s.width_pt, 3.0 * s.width_pt};
    cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0.0);
    if (s.style == SeriesStyle::kMarkers) {
      cairo_arc(cr, x + kLegendKey / 2.0, y, 3.0, 0.0, 2.0 * std::numbers::pi);
      cairo_fill(cr);
    } else {
      cairo_move_to(cr, x, y);
      cairo_line_to(cr, x + kLegendKey, y);
      cairo_stroke(cr);
    }
    cairo_set_dash(cr, nullptr, 0, 0.0);
    SetColor(cr, {0.1, 0.1, 0.1});
    ShowText(cr, x + kLegendKey + 4.0, y + 4.0, s.label);
  }
}

// `legend_h`: the height kept below the x label for the legend, the same
// for every panel of a row so that their plot boxes match.
void DrawAxes(cairo_t* cr, const Axes& axes, const LegendLayout& legend, double legend_h, double x0, double y0,
              double w, double h) {
  // Plot box in device units; the legend sits below the x label, outside
  // the data.
  const double left = x0 + kMarginLeft, top = y0 + kMarginTop;
  const double pw = w - kMarginLeft - kMarginRight;
  const double ph = h - kMarginTop - kMarginBottom - legend_h;
  Range xr = ScaledRange(axes, true), yr = ScaledRange(axes, false);
  if (axes.equal_aspect) {
    const double sx = pw / xr.Span(), sy = ph / yr.Span();
    if (sx > sy) {
      const double extra = (pw / sy - xr.Span()) / 2.0;
      xr = {xr.lo - extra, xr.hi + extra};
    } else {
      const double extra = (ph / sx - yr.Span()) / 2.0;
      yr = {yr.lo - extra, yr.hi + extra};
    }
  }
  auto px = [&](double v) { return left + (Forward(axes.x_scale, v) - xr.lo) / xr.Span() * pw; };
  auto py = [&](double v) { return top + ph - (Forward(axes.y_scale, v) - yr.lo) / yr.Span() * ph; };

  cairo_set_font_size(cr, kFontSize);
  // Grid and tick labels.
  cairo_set_line_width(cr, 0.5);
  for (const auto& [t, label] : Ticks(axes.x_scale, xr)) {
    const double x = left + (t - xr.lo) / xr.Span() * pw;
    SetColor(cr, {0.88, 0.88, 0.88});
    cairo_move_to(cr, x, top);
    cairo_line_to(cr, x, top + ph);
    cairo_stroke(cr);
    SetColor(cr, {0.2, 0.2, 0.2});
    ShowText(cr, x, top + ph + 15.0, label, 0.5);
  }
  for (const auto& [t, label] : Ticks(axes.y_scale, yr)) {
    const double y = top + ph - (t - yr.lo) / yr.Span() * ph;
    SetColor(cr, {0.88, 0.88, 0.88});
    cairo_move_to(cr, left, y);
    cairo_line_to(cr, left + pw, y);
    cairo_stroke(cr);
    SetColor(cr, {0.2, 0.2, 0.2});
    ShowText(cr, left - 5.0, y + 4.0, label, 1.0);
  }
  // Frame, title and labels.
  SetColor(cr, {0.2, 0.2, 0.2});
  cairo_set_line_width(cr, 1.0);
  cairo_rectangle(cr, left, top, pw, ph);
  cairo_stroke(cr);
  cairo_set_font_size(cr, kFontSize + 1.0);
  ShowText(cr, left + pw / 2.0, top - 10.0, axes.title, 0.5);
  cairo_set_font_size(cr, kFontSize);
  ShowText(cr, left + pw / 2.0, top + ph + 36.0, axes.x_label, 0.5);
  cairo_save(cr);
  cairo_move_to(cr, x0 + 16.0, top + ph / 2.0 + TextWidth(cr, axes.y_label) / 2.0);
  cairo_rotate(cr, -std::numbers::pi / 2.0);
  cairo_show_text(cr, axes.y_label.c_str());
  cairo_restore(cr);

  // Data, clipped to the box.
  cairo_save(cr);
  cairo_rectangle(cr, left, top, pw, ph);
  cairo_clip(cr);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_ROUND);
  for (const Series& s : axes.series) {
    SetColor(cr, s.color);
    cairo_set_line_width(cr, s.width_pt);
    const double dash[] = {4.0 * s.width_pt, 3.0 * s.width_pt};
    cairo_set_dash(cr, dash, s.dashed ? 2 : 0, 0.0);
    const std::size_t n = std::min(s.x.size(), s.y.size());
    auto finite = [&](std::size_t k) { return std::isfinite(px(s.x[k])) && std::isfinite(py(s.y[k])); };
    if (s.style == SeriesStyle::kLine) {
      bool pen_down = false;
      for (std::size_t k = 0; k < n; ++k) {
        if (!finite(k)) {
          pen_down = false;
          continue;
        }
        if (pen_down) cairo_line_to(cr, px(s.x[k]), py(s.y[k]));
        else cairo_move_to(cr, px(s.x[k]), py(s.y[k]));
        pen_down = true;
      }
      cairo_stroke(cr);
    } else if (s.style == SeriesStyle::kSegments) {
      for (std::size_t k = 0; k + 1 < n; k += 2) {
        if (!finite(k) || !finite(k + 1)) continue;
        cairo_move_to(cr, px(s.x[k]), py(s.y[k]));
        cairo_line_to(cr, px(s.x[k + 1]), py(s.y[k + 1]));
      }
      cairo_stroke(cr);
    }
    if (s.style == SeriesStyle::kMarkers || s.markers) {
      cairo_set_dash(cr, nullptr, 0, 0.0);
      for (std::size_t k = 0; k < n; ++k) {
        if (!finite(k)) continue;
        cairo_arc(cr, px(s.x[k]), py(s.y[k]), 1.2 * s.width_pt + 1.0, 0.0, 2.0 * std::numbers::pi);
        cairo_fill(cr);
      }
    }
  }
  cairo_restore(cr);

  DrawLegend(cr, legend, left, top + ph + kMarginBottom - 4.0);
}

void Draw(cairo_t* cr, const Figure& figure) {
  SetColor(cr, {1.0, 1.0, 1.0});
  cairo_paint(cr);
  cairo_select_font_face(cr, "sans-serif", CAIRO_FONT_SLANT_NORMAL, CAIRO_FONT_WEIGHT_NORMAL);
  const double title_h = figure.title.empty() ? 0.0 : 28.0;
  const double w = static_cast<double>(figure.width_px) / figure.cols;
  const double h = (static_cast<double>(figure.height_px) - title_h) / figure.rows;
  std::vector<LegendLayout> legends;
  std::vector<double> legend_h(static_cast<std::size_t>(figure.rows), 0.0);
  for (std::size_t k = 0; k < figure.axes.size(); ++k) {
    legends.push_back(LayOutLegend(cr, figure.axes[k], w - kMarginLeft - kMarginRight));
    double& row_h = legend_h[k / static_cast<std::size_t>(figure.cols)];
    row_h = std::max(row_h, legends.back().height);
  }
  for (std::size_t k = 0; k < figure.axes.size(); ++k) {
    const std::size_t r = k / static_cast<std::size_t>(figure.cols), c = k % static_cast<std::size_t>(figure.cols);
    DrawAxes(cr, figure.axes[k], legends[k], legend_h[r], static_cast<double>(c) * w,
             title_h + static_cast<double>(r) * h, w, h);
  }
  if (!figure.title.empty()) {
    SetColor(cr, {0.0, 0.0, 0.0});
    cairo_set_font_size(cr, kFontSize + 3.0);
    ShowText(cr, figure.width_px / 2.0, 20.0, figure.title, 0.5);
  }
}

cairo_status_t AppendToString(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const { cairo_destroy(c); }
};

}  // namespace

Color PaletteColor(int index) {
  static constexpr Color kPalette[] = {
      {0.000, 0.447, 0.698}, {0.835, 0.369, 0.000}, {0.000, 0.620, 0.451},
      {0.800, 0.475, 0.655}, {0.902, 0.624, 0.000}, {0.337, 0.706, 0.914},
      {0.941, 0.894, 0.259}, {0.0, 0.0, 0.0}};
  const int n = static_cast<int>(std::size(kPalette));
  return kPalette[((index % n) + n) % n];
}

std::string LowerCaseExtension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  if (!extension.empty()) extension.erase(0, 1);
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension;
}

void SaveFigure(const Figure& figure, const std::filesystem::path& path) {
  const std::string name = path.string();
  const std::string extension = LowerCaseExtension(path);
  if (extension != "png" && extension != "svg") {
    throw FileError(name, 0, "unknown picture type '" + path.extension().string() + "'; expected .png or .svg");
  }
  if (figure.rows < 1 || figure.cols < 1 || figure.width_px < 1 || figure.height_px < 1 ||
      static_cast<int>(figure.axes.size()) > figure.rows * figure.cols) {
    throw std::invalid_argument("SaveFigure: the figure's grid does not hold its axes");
  }
  std::string bytes;
  std::unique_ptr<cairo_surface_t, SurfaceDeleter> surface(
      extension == "svg"
          ? cairo_svg_surface_create_for_stream(AppendToString, &bytes, figure.width_px,
                                                figure.height_px)
          : cairo_image_surface_create(CAIRO_FORMAT_ARGB32, figure.width_px, figure.height_px));
  {
    std::unique_ptr<cairo_t, ContextDeleter> cr(cairo_create(surface.get()));
    Draw(cr.get(), figure);
    if (cairo_status(cr.get()) != CAIRO_STATUS_SUCCESS) {
      throw FileError(name, 0, std::string("drawing failed: ") +
                                   cairo_status_to_string(cairo_status(cr.get())));
    }
  }
  if (extension == "png") {
    const cairo_status_t status =
        cairo_surface_write_to_png_stream(surface.get(), AppendToString, &bytes);
    if (status != CAIRO_STATUS_SUCCESS) {
      throw FileError(name, 0, std::string("PNG encoding failed: ") + cairo_status_to_string(status));
    }
  }
  cairo_surface_finish(surface.get());  // flushes the SVG stream
  WriteFileAtomically(path, [&bytes](std::ostream& out) { out.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
}

}  // namespace catgraph::plot
