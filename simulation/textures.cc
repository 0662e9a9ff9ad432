#include "simulation/textures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "backend/graph/name_table.h"

namespace catgraph {
namespace {

constexpr NameTable<FurnitureStyle, 8> kStyleNames{{
    {FurnitureStyle::kCabinet, "cabinet"},
    {FurnitureStyle::kBookshelf, "bookshelf"},
    {FurnitureStyle::kDesk, "desk"},
    {FurnitureStyle::kWhiteboard, "whiteboard"},
    {FurnitureStyle::kPlant, "plant"},
    {FurnitureStyle::kBoxes, "boxes"},
    {FurnitureStyle::kChair, "chair"},
    {FurnitureStyle::kSofa, "sofa"},
}};

// A drawing context in metres: x to the right from the left edge, z up from
// the bottom edge, on an image of ppm pixels per metre.
class Canvas {
 public:
  Canvas(double width_m, double height_m, double ppm, cv::Scalar background)
      : ppm_(ppm),
        image_(std::max(2, static_cast<int>(std::lround(height_m * ppm))),
               std::max(2, static_cast<int>(std::lround(width_m * ppm)))),
        height_m_(height_m) {
    image_.setTo(background);
  }

  cv::Point P(double x_m, double z_m) const {
    return {static_cast<int>(std::lround(x_m * ppm_)),
            static_cast<int>(std::lround((height_m_ - z_m) * ppm_))};
  }
  int Px(double m) const { return std::max(1, static_cast<int>(std::lround(m * ppm_))); }

  void Rect(double x0, double z0, double x1, double z1, cv::Scalar c, int thickness = cv::FILLED) {
    cv::rectangle(image_, P(x0, z1), P(x1, z0), c, thickness, cv::LINE_AA);
  }
  void Circle(double x, double z, double r, cv::Scalar c, int thickness = cv::FILLED) {
    cv::circle(image_, P(x, z), Px(r), c, thickness, cv::LINE_AA);
  }
  void Segment(double x0, double z0, double x1, double z1, cv::Scalar c, double width_m) {
    cv::line(image_, P(x0, z0), P(x1, z1), c, Px(width_m), cv::LINE_AA);
  }
  // Text whose capital height is about `height_m`.
  void Text(const std::string& text, double x, double z, double height_m, cv::Scalar c) {
    const double scale = height_m * ppm_ / 22.0;  // Hershey simplex caps are ~22 px at scale 1
    cv::putText(image_, text, P(x, z), cv::FONT_HERSHEY_SIMPLEX, scale, c,
                std::max(1, static_cast<int>(std::lround(scale * 2.0))), cv::LINE_AA);
  }
  cv::Mat3b& image() { return image_; }

 private:
  double ppm_;
  cv::Mat3b image_;
  double height_m_;
};

// The world's random draws. C++ leaves the order in which a call's
// arguments are evaluated unspecified, so no call takes two draws as
// arguments: each is a statement of its own, and a seed gives the same world
// with every compiler (GCC and clang once drew different textures from one
// seed). Where draws were split out, they keep the order GCC gave them, last
// argument first, so that the datasets stayed as they were.
class Dice {
 public:
  explicit Dice(std::mt19937_64& rng) : rng_(rng) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }
  bool Chance(double p) { return Uniform(0.0, 1.0) < p; }
  cv::Scalar Vivid() {
    // HSV with high saturation, converted by hand to BGR.
    const double h = Uniform(0.0, 6.0), s = Uniform(0.55, 1.0), v = Uniform(0.45, 0.95);
    const double c = v * s, x = c * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0)), m = v - c;
    std::array<double, 3> rgb{};
    switch (static_cast<int>(h)) {
      case 0: rgb = {c, x, 0}; break;
      case 1: rgb = {x, c, 0}; break;
      case 2: rgb = {0, c, x}; break;
      case 3: rgb = {0, x, c}; break;
      case 4: rgb = {x, 0, c}; break;
      default: rgb = {c, 0, x}; break;
    }
    return {255.0 * (rgb[2] + m), 255.0 * (rgb[1] + m), 255.0 * (rgb[0] + m)};
  }
  cv::Scalar Pale() {
    const cv::Scalar v = Vivid();
    return {155 + 0.35 * v[0], 155 + 0.35 * v[1], 155 + 0.35 * v[2]};
  }
  cv::Scalar Dark() {
    const cv::Scalar v = Vivid();
    return {0.35 * v[0], 0.35 * v[1], 0.35 * v[2]};
  }
  std::string Word(int min_len, int max_len) {
    static constexpr char kLetters[] = "ABCDEFGHKLMNPRSTUVWXYZ";
    std::string w;
    const int n = Int(min_len, max_len);
    for (int i = 0; i < n; ++i) w += kLetters[Int(0, static_cast<int>(sizeof kLetters) - 2)];
    return w;
  }
  std::string Number(int digits) {
    std::string w;
    for (int i = 0; i < digits; ++i) w += static_cast<char>('0' + Int(0, 9));
    return w;
  }

 private:
  std::mt19937_64& rng_;
};

// --- wall panels; x0 is the panel's left edge, w its width ---------------

void Door(Canvas& c, Dice& d, double x0, double w) {
  const double dw = std::min(0.95, w - 0.2), x = x0 + (w - dw) / 2.0;
  const cv::Scalar wood = d.Chance(0.5) ? cv::Scalar(40, 80, 130) : cv::Scalar(70, 110, 160);
  c.Rect(x - 0.06, 0.0, x + dw + 0.06, 2.16, cv::Scalar(60, 60, 60));
  c.Rect(x, 0.0, x + dw, 2.1, wood);
  if (d.Chance(0.6)) c.Rect(x + 0.2 * dw, 1.3, x + 0.45 * dw, 1.9, cv::Scalar(200, 190, 170));
  c.Rect(x + 0.8 * dw, 0.95, x + 0.92 * dw, 1.0, cv::Scalar(200, 200, 210));
  c.Rect(x0 + w / 2.0 - 0.17, 2.22, x0 + w / 2.0 + 0.17, 2.4, cv::Scalar(235, 235, 235));
  c.Text(d.Number(3), x0 + w / 2.0 - 0.14, 2.26, 0.1, cv::Scalar(20, 20, 20));
}

void Poster(Canvas& c, Dice& d, double x0, double w) {
  const double pw = std::min(w - 0.2, d.Uniform(0.5, 0.9)), ph = d.Uniform(0.6, 1.0);
  const double x = x0 + d.Uniform(0.1, w - pw - 0.1 + 1e-9), z = d.Uniform(0.9, 1.8 - ph / 3.0);
  c.Rect(x - 0.02, z - 0.02, x + pw + 0.02, z + ph + 0.02, cv::Scalar(30, 30, 30));
  c.Rect(x, z, x + pw, z + ph, d.Pale());
  for (int i = d.Int(4, 8); i > 0; --i) {
    const double sx = x + d.Uniform(0.0, pw), sz = z + d.Uniform(0.0, ph), r = d.Uniform(0.04, 0.2);
    switch (d.Int(0, 2)) {
      case 0: c.Circle(sx, sz, r, d.Vivid()); break;
      case 1:
        c.Rect(std::max(x, sx - r), std::max(z, sz - r), std::min(x + pw, sx + r),
               std::min(z + ph, sz + r), d.Vivid());
        break;
      default: {
        const cv::Scalar colour = d.Vivid();
        const double end_z = z + d.Uniform(0.0, ph), end_x = x + d.Uniform(0.0, pw);
        const double start_z = z + d.Uniform(0.0, ph), start_x = x + d.Uniform(0.0, pw);
        c.Segment(start_x, start_z, end_x, end_z, colour, 0.02);
        break;
      }
    }
  }
  const cv::Scalar dark = d.Dark();
  c.Text(d.Word(3, 6), x + 0.05, z + ph - 0.12, 0.07, dark);
}

void NoticeBoard(Canvas& c, Dice& d, double x0, double w) {
  const double bw = std::min(w - 0.2, 1.4), x = x0 + (w - bw) / 2.0, z = 1.0, h = 0.9;
  c.Rect(x - 0.03, z - 0.03, x + bw + 0.03, z + h + 0.03, cv::Scalar(50, 70, 90));
  c.Rect(x, z, x + bw, z + h, cv::Scalar(90, 140, 190));  // cork
  for (int i = d.Int(5, 10); i > 0; --i) {
    const double pw = d.Uniform(0.12, 0.3), ph = d.Uniform(0.15, 0.3);
    const double px = x + d.Uniform(0.0, bw - pw), pz = z + d.Uniform(0.0, h - ph);
    c.Rect(px, pz, px + pw, pz + ph, d.Chance(0.6) ? cv::Scalar(245, 245, 245) : d.Pale());
    for (double lz = pz + ph - 0.05; lz > pz + 0.03; lz -= 0.035) {
      c.Segment(px + 0.02, lz, px + d.Uniform(0.3, 0.95) * pw, lz, cv::Scalar(90, 90, 90), 0.008);
    }
    c.Circle(px + pw / 2.0, pz + ph - 0.015, 0.012, d.Vivid());
  }
}

void PatternPanel(Canvas& c, Dice& d, double x0, double w) {
  const double z0 = 0.4, z1 = d.Uniform(1.6, 2.2), cell = d.Uniform(0.08, 0.2);
  const cv::Scalar a = d.Vivid(), b = d.Pale();
  c.Rect(x0 + 0.1, z0, x0 + w - 0.1, z1, b);
  const int kind = d.Int(0, 2);
  int i = 0;
  for (double x = x0 + 0.1; x + cell <= x0 + w - 0.1; x += cell, ++i) {
    int j = 0;
    for (double z = z0; z + cell <= z1; z += cell, ++j) {
      if (kind == 0 && (i + j) % 2 == 0) c.Rect(x, z, x + cell, z + cell, a);
      if (kind == 1 && j % 3 == 0) c.Rect(x, z, x + cell, z + cell * 0.5, a);
      if (kind == 2 && (i * 7 + j * 3) % 5 == 0) c.Circle(x + cell / 2, z + cell / 2, cell / 3, a);
    }
  }
}

void Window(Canvas& c, Dice& d, double x0, double w) {
  const double z0 = 0.9, z1 = 2.2;
  c.Rect(x0 + 0.1, z0, x0 + w - 0.1, z1, cv::Scalar(210, 190, 160));
  const int panes = std::max(1, static_cast<int>(w / 0.7));
  for (int i = 0; i <= panes; ++i) {
    const double x = x0 + 0.1 + (w - 0.2) * i / panes;
    c.Segment(x, z0, x, z1, cv::Scalar(70, 70, 70), 0.04);
  }
  c.Segment(x0 + 0.1, (z0 + z1) / 2, x0 + w - 0.1, (z0 + z1) / 2, cv::Scalar(70, 70, 70), 0.03);
  for (int i = d.Int(1, 3); i > 0; --i) {  // blinds and what is behind
    const double bx = x0 + d.Uniform(0.1, w - 0.3);
    const cv::Scalar colour = d.Pale();
    c.Rect(bx, z0 + 0.05, bx + 0.2, z1 - d.Uniform(0.2, 0.8), colour);
  }
}

void Sign(Canvas& c, Dice& d, double x0, double w) {
  const double x = x0 + w / 2.0;
  if (d.Chance(0.5)) {  // fire extinguisher and its sign
    c.Rect(x - 0.09, 0.2, x + 0.09, 0.75, cv::Scalar(30, 30, 200));
    c.Rect(x - 0.04, 0.75, x + 0.04, 0.85, cv::Scalar(30, 30, 30));
    c.Rect(x - 0.15, 1.5, x + 0.15, 1.8, cv::Scalar(30, 30, 200));
    c.Text("FIRE", x - 0.12, 1.6, 0.08, cv::Scalar(255, 255, 255));
  } else {  // exit or room-name sign and a light switch
    const cv::Scalar bg = d.Chance(0.5) ? cv::Scalar(60, 150, 40) : cv::Scalar(120, 60, 20);
    c.Rect(x - 0.3, 2.0, x + 0.3, 2.25, bg);
    c.Text(d.Word(4, 5), x - 0.26, 2.06, 0.12, cv::Scalar(255, 255, 255));
    c.Rect(x - 0.05, 1.1, x + 0.05, 1.25, cv::Scalar(230, 230, 230));
    c.Rect(x - 0.05, 1.1, x + 0.05, 1.25, cv::Scalar(120, 120, 120), 1);
  }
}

// --- furniture ------------------------------------------------------------

void FurnitureSide(Canvas& c, Dice& d, FurnitureStyle style, double w, double h) {
  switch (style) {
    case FurnitureStyle::kCabinet: {
      const cv::Scalar body = d.Chance(0.5) ? cv::Scalar(170, 175, 180) : cv::Scalar(150, 185, 205);
      c.Rect(0, 0, w, h, body);
      const int drawers = d.Int(2, 4);
      for (int i = 0; i < drawers; ++i) {
        const double z0 = 0.05 + (h - 0.1) * i / drawers, z1 = 0.05 + (h - 0.1) * (i + 1) / drawers;
        c.Rect(0.04, z0 + 0.02, w - 0.04, z1 - 0.02, cv::Scalar(90, 90, 90), 1);
        c.Rect(w / 2 - 0.08, z1 - 0.12, w / 2 + 0.08, z1 - 0.09, cv::Scalar(40, 40, 40));
        c.Rect(w / 2 - 0.06, z1 - 0.25, w / 2 + 0.06, z1 - 0.17, cv::Scalar(250, 250, 250));
        c.Text(d.Word(1, 2), w / 2 - 0.05, z1 - 0.24, 0.05, cv::Scalar(20, 20, 20));
      }
      break;
    }
    case FurnitureStyle::kBookshelf: {
      c.Rect(0, 0, w, h, cv::Scalar(45, 75, 110));
      const int shelves = std::max(2, static_cast<int>(h / 0.38));
      for (int s = 0; s < shelves; ++s) {
        const double z0 = 0.04 + (h - 0.08) * s / shelves, z1 = 0.04 + (h - 0.08) * (s + 1) / shelves;
        for (double x = 0.05; x < w - 0.07;) {
          const double bw = d.Uniform(0.025, 0.07), bh = d.Uniform(0.55, 0.92) * (z1 - z0 - 0.03);
          c.Rect(x, z0 + 0.02, std::min(w - 0.05, x + bw), z0 + 0.02 + bh, d.Vivid());
          x += bw + (d.Chance(0.1) ? d.Uniform(0.03, 0.12) : 0.004);
        }
        c.Rect(0.03, z0, w - 0.03, z0 + 0.02, cv::Scalar(35, 60, 90));
      }
      break;
    }
    case FurnitureStyle::kDesk: {
      c.Rect(0, h - 0.05, w, h, cv::Scalar(90, 140, 180));
      c.Rect(0.02, 0, 0.07, h - 0.05, cv::Scalar(60, 60, 60));
      c.Rect(w - 0.07, 0, w - 0.02, h - 0.05, cv::Scalar(60, 60, 60));
      c.Rect(w * 0.55, 0.1, w - 0.1, h - 0.08, cv::Scalar(80, 120, 160));
      c.Rect(w * 0.55 + 0.03, h - 0.25, w - 0.13, h - 0.11, cv::Scalar(60, 90, 120), 1);
      break;
    }
    case FurnitureStyle::kWhiteboard: {
      c.Rect(0.05, 0, 0.09, h, cv::Scalar(80, 80, 80));
      c.Rect(w - 0.09, 0, w - 0.05, h, cv::Scalar(80, 80, 80));
      c.Rect(0, 0.8, w, h, cv::Scalar(150, 150, 150));
      c.Rect(0.03, 0.83, w - 0.03, h - 0.03, cv::Scalar(248, 248, 248));
      for (int i = d.Int(3, 7); i > 0; --i) {
        const cv::Scalar ink = d.Chance(0.5) ? cv::Scalar(160, 40, 20) : cv::Scalar(30, 30, 190);
        if (d.Chance(0.5)) {
          const double tz = d.Uniform(0.9, h - 0.15), tx = d.Uniform(0.1, std::max(0.11, w - 0.5));
          c.Text(d.Word(2, 5), tx, tz, 0.07, ink);
        } else {
          const double end_z = d.Uniform(0.9, h - 0.1), end_x = d.Uniform(0.1, w - 0.1);
          const double start_z = d.Uniform(0.9, h - 0.1), start_x = d.Uniform(0.1, w - 0.1);
          c.Segment(start_x, start_z, end_x, end_z, ink, 0.012);
        }
      }
      break;
    }
    case FurnitureStyle::kPlant: {
      c.Rect(w / 2 - 0.18, 0, w / 2 + 0.18, 0.35, cv::Scalar(40, 60, 150));
      for (int i = 60; i > 0; --i) {
        const double x = w / 2 + d.Uniform(-0.45, 0.45) * w, z = d.Uniform(0.35, h);
        const double red = d.Uniform(20, 70), green = d.Uniform(90, 170), blue = d.Uniform(20, 60);
        c.Circle(x, z, d.Uniform(0.03, 0.08), cv::Scalar(blue, green, red));
      }
      break;
    }
    case FurnitureStyle::kBoxes: {
      for (double z = 0.0; z < h - 0.1;) {
        double bh = std::min(h - z, d.Uniform(0.25, 0.45));
        for (double x = 0.0; x < w - 0.05;) {
          const double bw = std::min(w - x, d.Uniform(0.3, 0.6));
          const double red = d.Uniform(180, 210), green = d.Uniform(130, 160), blue = d.Uniform(70, 100);
          c.Rect(x, z, x + bw, z + bh, cv::Scalar(blue, green, red));
          c.Rect(x, z, x + bw, z + bh, cv::Scalar(50, 80, 110), 1);
          c.Rect(x + bw * 0.2, z + bh * 0.45, x + bw * 0.6, z + bh * 0.75, cv::Scalar(245, 245, 245));
          c.Text(d.Number(2), x + bw * 0.22, z + bh * 0.5, 0.05, cv::Scalar(10, 10, 10));
          x += bw;
        }
        z += bh;
      }
      break;
    }
    case FurnitureStyle::kChair: {
      const cv::Scalar fabric = d.Dark();
      c.Rect(0.05, 0.45, w - 0.05, 0.55, fabric);
      c.Rect(0.1, 0.55, w - 0.1, h, fabric);
      c.Rect(w / 2 - 0.03, 0.05, w / 2 + 0.03, 0.45, cv::Scalar(40, 40, 40));
      c.Segment(0.05, 0.05, w - 0.05, 0.05, cv::Scalar(40, 40, 40), 0.04);
      break;
    }
    case FurnitureStyle::kSofa: {
      const cv::Scalar fabric = d.Vivid();
      c.Rect(0, 0.1, w, h * 0.55, fabric);
      c.Rect(0.1, h * 0.55, w - 0.1, h, fabric * 0.8);
      for (double x = 0.1; x < w - 0.2; x += (w - 0.2) / 3.0) {
        c.Rect(x + 0.02, 0.25, x + (w - 0.2) / 3.0 - 0.02, h * 0.5, fabric * 1.15);
        c.Circle(x + (w - 0.2) / 6.0, h * 0.8, 0.04, d.Pale());
      }
      break;
    }
  }
}

cv::Mat3b Finish(Canvas& canvas) {
  cv::GaussianBlur(canvas.image(), canvas.image(), cv::Size(3, 3), 0.6);
  return canvas.image();
}

}  // namespace

std::string_view ToString(FurnitureStyle style) { return NameOf(kStyleNames, style); }

FurnitureStyle FurnitureStyleFromString(std::string_view text) {
  if (const auto style = ValueOf(kStyleNames, text)) return *style;
  std::string names;
  for (const auto& [value, name] : kStyleNames) names += (names.empty() ? "" : ", ") + std::string(name);
  throw std::invalid_argument("unknown furniture style '" + std::string(text) +
                              "'; expected one of " + names);
}

Texture::Texture(const cv::Mat3b& image, double width_m, double height_m)
    : width_m_(width_m), height_m_(height_m), pixels_per_m_(image.cols / width_m) {
  pyramid_.push_back(image);
  while (pyramid_.back().rows > 4 && pyramid_.back().cols > 4) {
    cv::Mat3b next;
    cv::pyrDown(pyramid_.back(), next);
    pyramid_.push_back(next);
  }
}

cv::Vec3f Texture::Sample(double u_m, double z_m, double footprint_m) const {
  const double texels = std::max(1.0, footprint_m * pixels_per_m_);
  const int l = std::min(levels() - 1, static_cast<int>(std::log2(texels)));
  const cv::Mat3b& img = pyramid_[static_cast<std::size_t>(l)];
  const double scale = pixels_per_m_ * img.cols / pyramid_.front().cols;
  const double fx = std::clamp(u_m * scale - 0.5, 0.0, img.cols - 1.001);
  const double fy = std::clamp((height_m_ - z_m) * scale - 0.5, 0.0, img.rows - 1.001);
  const int x = static_cast<int>(fx), y = static_cast<int>(fy);
  const float ax = static_cast<float>(fx - x), ay = static_cast<float>(fy - y);
  const cv::Vec3b* r0 = img.ptr<cv::Vec3b>(y);
  const cv::Vec3b* r1 = img.ptr<cv::Vec3b>(y + 1);
  cv::Vec3f out;
  for (int k = 0; k < 3; ++k) {
    const float top = r0[x][k] + ax * (r0[x + 1][k] - r0[x][k]);
    const float bottom = r1[x][k] + ax * (r1[x + 1][k] - r1[x][k]);
    out[k] = top + ay * (bottom - top);
  }
  return out;
}

Texture MakeWallTexture(double length_m, double height_m, std::mt19937_64& rng) {
  Dice d(rng);
  Canvas c(length_m, height_m, kWallPixelsPerMetre, d.Pale());
  c.Rect(0, 0, length_m, 0.1, cv::Scalar(55, 55, 60));  // skirting board
  if (d.Chance(0.4)) c.Rect(0, 0.95, length_m, 1.0, d.Dark());  // dado rail
  for (double x = 0.0; x < length_m - 0.3;) {
    const double w = std::min(length_m - x, d.Uniform(1.0, 3.0));
    switch (d.Int(0, 9)) {
      case 0: case 1: Door(c, d, x, w); break;
      case 2: case 3: Poster(c, d, x, w); break;
      case 4: NoticeBoard(c, d, x, w); break;
      case 5: PatternPanel(c, d, x, w); break;
      case 6: Window(c, d, x, w); break;
      case 7: Sign(c, d, x, w); break;
      default: if (w > 0.8) Poster(c, d, x, w); break;  // some plain wall remains between
    }
    x += w;
  }
  return {Finish(c), length_m, height_m};
}

Texture MakeFurnitureTexture(FurnitureStyle style, double width_m, double height_m, bool top,
                             std::mt19937_64& rng) {
  Dice d(rng);
  constexpr double kPpm = 100.0;
  if (top) {
    Canvas c(width_m, height_m, kPpm, cv::Scalar(110, 130, 150));
    if (style == FurnitureStyle::kDesk) {
      c.Rect(0.1, 0.1, std::min(width_m - 0.1, 0.5), std::min(height_m - 0.1, 0.35), cv::Scalar(240, 240, 240));
      c.Rect(width_m * 0.6, 0.1, width_m * 0.6 + 0.3, 0.3, cv::Scalar(30, 30, 30));
    }
    return {Finish(c), width_m, height_m};
  }
  Canvas c(width_m, height_m, kPpm, cv::Scalar(120, 120, 120));
  FurnitureSide(c, d, style, width_m, height_m);
  return {Finish(c), width_m, height_m};
}

}  // namespace catgraph
