// Procedural, deterministic textures for the office world: wall faces with
// doors, posters, notice boards, patterned panels, windows and signs, and
// furniture (cabinets, bookshelves, desks, whiteboards, plants, boxes).
//
// Every texture is drawn once with OpenCV primitives from a seeded generator
// (the same seed gives the same pixels) and kept as a mip-map pyramid so that
// the renderer can sample it without aliasing at any distance. Walls are
// drawn at `kWallPixelsPerMetre`; a surface of L × H metres is an image of
// L·ppm × H·ppm pixels, u (metres along the face, left to right as seen from
// the front) and z (metres above the floor) map to columns and rows.
//
// Thread-compatible: a Texture is immutable after construction and can be
// sampled from several threads.
#ifndef CATGRAPH_SIMULATION_TEXTURES_H_
#define CATGRAPH_SIMULATION_TEXTURES_H_

#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

#include <opencv2/core.hpp>

namespace catgraph {

inline constexpr double kWallPixelsPerMetre = 80.0;

enum class FurnitureStyle { kCabinet, kBookshelf, kDesk, kWhiteboard, kPlant, kBoxes, kChair, kSofa };

std::string_view ToString(FurnitureStyle style);
// Throws std::invalid_argument listing the styles.
FurnitureStyle FurnitureStyleFromString(std::string_view text);

class Texture {
 public:
  Texture() = default;
  // `image` is level 0 (CV_8UC3, BGR); `width_m` × `height_m` is its size in
  // the world.
  Texture(const cv::Mat3b& image, double width_m, double height_m);

  double width_m() const { return width_m_; }
  double height_m() const { return height_m_; }
  int levels() const { return static_cast<int>(pyramid_.size()); }
  const cv::Mat3b& level(int i) const { return pyramid_.at(static_cast<std::size_t>(i)); }

  // Colour at u metres from the left edge and z metres above the bottom edge
  // (clamped to the texture), filtered for a pixel footprint of
  // `footprint_m` metres: bilinear on the pyramid level whose texels are
  // closest to that size. Returns BGR in [0, 255].
  cv::Vec3f Sample(double u_m, double z_m, double footprint_m) const;

 private:
  std::vector<cv::Mat3b> pyramid_;
  double width_m_ = 0.0, height_m_ = 0.0;
  double pixels_per_m_ = 1.0;  // of level 0
};

// A wall face of `length_m` × `height_m`: a painted wall with a skirting
// board, divided into panels of 1–3 m, each a door, poster, notice board,
// patterned panel, window or sign, drawn from `rng`.
Texture MakeWallTexture(double length_m, double height_m, std::mt19937_64& rng);

// One side of a piece of furniture of the given style, `width_m` ×
// `height_m`. `top` selects the texture of its top surface instead.
Texture MakeFurnitureTexture(FurnitureStyle style, double width_m, double height_m, bool top,
                             std::mt19937_64& rng);

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_TEXTURES_H_
