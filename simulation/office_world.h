// The office world: a floor plan of solid blocks (offices, pillars) inside a
// building outline, furniture that stands in some traversals and not in
// others, and lighting regions, rendered by ray casting into the forward
// camera patch of the CAT-Graph+ paper.
//
// Geometry is 2.5D: every obstacle is an axis-aligned box standing on the
// floor. Blocks and the building walls reach the ceiling; furniture has its
// own height, so a ray can pass over a desk and hit the wall behind it or
// land on the desk's top. The camera is cylindrical (one ray per column,
// equal angles per column, like the paper's unwrapped panorama); rows are
// equally spaced in tan(elevation).
//
// Rendering is a pure function of (pose, traversal, frame seed): the same
// inputs give the same pixels. Thread-compatible: Render is const and can be
// called from several threads.
#ifndef CATGRAPH_SIMULATION_OFFICE_WORLD_H_
#define CATGRAPH_SIMULATION_OFFICE_WORLD_H_

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "backend/graph/pose2.h"
#include "backend/io/dataset.h"
#include "simulation/textures.h"

namespace catgraph {

// An axis-aligned rectangle [x0, x1] × [y0, y1] in metres.
struct Box2 {
  double x0 = 0.0, y0 = 0.0, x1 = 0.0, y1 = 0.0;
  bool Contains(const Eigen::Vector2d& p, double margin_m = 0.0) const {
    return p.x() > x0 - margin_m && p.x() < x1 + margin_m && p.y() > y0 - margin_m &&
           p.y() < y1 + margin_m;
  }
  Polygon2 ToPolygon() const { return {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}}; }
};

struct FloorPlan {
  Box2 building;                     // the outer walls, seen from inside
  double ceiling_height_m = 2.7;     // > 0
  std::vector<Box2> blocks;          // solid and full height: offices, pillars
  std::uint64_t texture_seed = 1;    // wall textures depend only on this
};

struct Furniture {
  std::string name;
  FurnitureStyle style = FurnitureStyle::kCabinet;
  Box2 footprint;
  double height_m = 1.0;        // (0, ceiling)
  std::vector<int> traversals;  // the traversals in which it stands
  bool StandsIn(int traversal) const;
};

struct LightingRegion {
  std::string name;
  Polygon2 polygon;
  std::map<int, double> gain;  // per traversal; 1 when absent
  cv::Vec3d tint{1.0, 1.0, 1.0};  // BGR factors applied with the gain when it is not 1
  double GainIn(int traversal) const;
};

struct CameraOptions {
  int width_px = 261;         // the paper's forward patch
  int height_px = 101;
  double hfov_deg = 100.0;    // (0, 360)
  double vfov_deg = 45.0;     // (0, 170)
  double height_m = 1.0;      // above the floor, below the ceiling
  double frame_rate_hz = 7.5;
  double noise_sigma = 2.0;   // grey levels of sensor noise, >= 0
};

// True when p is in free space: inside the building, outside every block and
// every furniture item standing in `traversal`, with `margin_m` to spare.
bool IsFreeSpace(const FloorPlan& plan, const std::vector<Furniture>& furniture,
                 const Eigen::Vector2d& p, int traversal, double margin_m);

enum class SurfaceKind : std::uint8_t { kFloor, kCeiling, kWall, kFurniture };

// Per-pixel by-products of a render, for ground truth and tests.
struct RenderDetail {
  cv::Mat1f depth_m;        // horizontal distance to what the pixel sees
  cv::Mat1b surface;        // SurfaceKind per pixel
  // Pixels whose view differs from another traversal's at the same pose: they
  // see (or look through the place of) furniture that is not there in every
  // traversal, or a surface whose lighting changes between traversals.
  double changed_fraction = 0.0;
};

class OfficeWorld {
 public:
  // Builds every texture (deterministic from floor_plan.texture_seed and the
  // furniture names). `traversals` lists every traversal id, so that the
  // world knows what changes between them. Throws std::invalid_argument on
  // inconsistent geometry.
  OfficeWorld(FloorPlan floor_plan, std::vector<Furniture> furniture,
              std::vector<LightingRegion> lighting, CameraOptions camera,
              std::vector<int> traversals);
  ~OfficeWorld();
  OfficeWorld(OfficeWorld&&) noexcept;
  OfficeWorld& operator=(OfficeWorld&&) noexcept;

  // The image (CV_8UC3, BGR) the camera at `T_world_camera` sees during
  // `traversal`; `noise_seed` seeds the sensor noise. `detail` may be null.
  cv::Mat3b Render(const Pose2& T_world_camera, int traversal, std::uint64_t noise_seed,
                   RenderDetail* detail = nullptr) const;

  const FloorPlan& floor_plan() const { return floor_plan_; }
  const std::vector<Furniture>& furniture() const { return furniture_; }
  const CameraOptions& camera() const { return camera_; }
  // Wall segments (x0, y0, x1, y1) of the floor plan, for pictures.
  std::vector<Eigen::Vector4d> WallSegments() const;

 private:
  struct Scene;
  FloorPlan floor_plan_;
  std::vector<Furniture> furniture_;
  std::vector<LightingRegion> lighting_;
  CameraOptions camera_;
  std::vector<int> traversals_;
  std::unique_ptr<Scene> scene_;  // textures and per-face geometry
};

}  // namespace catgraph

#endif  // CATGRAPH_SIMULATION_OFFICE_WORLD_H_
