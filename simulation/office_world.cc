#include "simulation/office_world.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "simulation/hashing.h"

namespace catgraph {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Approximately standard-normal noise from a hash (Irwin–Hall sum of four
// uniform 16-bit variates): cheap, deterministic per pixel.
float HashNormal(std::uint64_t h) {
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) sum += static_cast<double>((h >> (16 * i)) & 0xffff) / 65535.0;
  return static_cast<float>((sum - 2.0) * std::sqrt(3.0));
}

void CheckBox(const Box2& b, const std::string& what) {
  if (!(b.x1 > b.x0) || !(b.y1 > b.y0) || !std::isfinite(b.x0 + b.x1 + b.y0 + b.y1)) {
    throw std::invalid_argument(what + ": expected a box [x0, y0, x1, y1] with x0 < x1 and y0 < y1");
  }
}

}  // namespace

bool Furniture::StandsIn(int traversal) const {
  return std::find(traversals.begin(), traversals.end(), traversal) != traversals.end();
}

double LightingRegion::GainIn(int traversal) const {
  const auto it = gain.find(traversal);
  return it == gain.end() ? 1.0 : it->second;
}

// One vertical face of a box. `right` runs along the face from `left_end`,
// left to right as seen from the front (against `normal`).
struct Face {
  int texture = -1;
  Eigen::Vector2d left_end = Eigen::Vector2d::Zero();
  Eigen::Vector2d right = Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
  double length_m = 0.0;
};

// Faces 0..3 of a box: x0 (normal −x), x1 (+x), y0 (−y), y1 (+y); `sign` −1
// turns the normals inward (the building seen from inside).
std::array<Face, 4> BoxFaces(const Box2& b, double sign) {
  const std::array<Eigen::Vector2d, 4> normals = {Eigen::Vector2d(-1, 0), Eigen::Vector2d(1, 0),
                                                  Eigen::Vector2d(0, -1), Eigen::Vector2d(0, 1)};
  const std::array<std::array<Eigen::Vector2d, 2>, 4> ends = {{
      {Eigen::Vector2d(b.x0, b.y0), Eigen::Vector2d(b.x0, b.y1)},
      {Eigen::Vector2d(b.x1, b.y0), Eigen::Vector2d(b.x1, b.y1)},
      {Eigen::Vector2d(b.x0, b.y0), Eigen::Vector2d(b.x1, b.y0)},
      {Eigen::Vector2d(b.x0, b.y1), Eigen::Vector2d(b.x1, b.y1)},
  }};
  std::array<Face, 4> faces;
  for (int i = 0; i < 4; ++i) {
    Face& f = faces[static_cast<std::size_t>(i)];
    f.normal = sign * normals[static_cast<std::size_t>(i)];
    f.right = Eigen::Vector2d(-f.normal.y(), f.normal.x());
    const auto& e = ends[static_cast<std::size_t>(i)];
    f.left_end = e[0].dot(f.right) < e[1].dot(f.right) ? e[0] : e[1];
    f.length_m = (e[1] - e[0]).norm();
  }
  return faces;
}

struct OfficeWorld::Scene {
  struct Solid {
    Box2 box;
    std::array<Face, 4> faces;
  };
  struct Item {
    Box2 box;
    double height_m;
    std::array<Face, 4> faces;
    int top_texture;
    const Furniture* furniture;
    bool changes;  // absent from at least one traversal
  };
  std::vector<Texture> textures;
  std::array<Face, 4> building_faces;
  std::vector<Solid> blocks;
  std::vector<Item> items;
};

OfficeWorld::~OfficeWorld() = default;
OfficeWorld::OfficeWorld(OfficeWorld&&) noexcept = default;
OfficeWorld& OfficeWorld::operator=(OfficeWorld&&) noexcept = default;

OfficeWorld::OfficeWorld(FloorPlan floor_plan, std::vector<Furniture> furniture,
                         std::vector<LightingRegion> lighting,
                         CameraOptions camera,
                         std::vector<int> traversals)
    : floor_plan_(std::move(floor_plan)),
      furniture_(std::move(furniture)),
      lighting_(std::move(lighting)),
      camera_(camera),
      traversals_(std::move(traversals)),
      scene_(std::make_unique<Scene>()) {
  const double ceiling = floor_plan_.ceiling_height_m;
  CheckBox(floor_plan_.building, "building");
  if (!(ceiling > 0.0)) throw std::invalid_argument("ceiling_height_m: expected > 0");
  if (camera_.width_px < 2 || camera_.height_px < 2 || camera_.width_px > 8192 ||
      camera_.height_px > 8192) {
    throw std::invalid_argument("camera: expected 2..8192 pixels in width and height");
  }
  if (!(camera_.hfov_deg > 0.0 && camera_.hfov_deg < 360.0) ||
      !(camera_.vfov_deg > 0.0 && camera_.vfov_deg < 170.0)) {
    throw std::invalid_argument("camera: expected hfov_deg in (0, 360) and vfov_deg in (0, 170)");
  }
  if (!(camera_.height_m > 0.0 && camera_.height_m < ceiling)) {
    throw std::invalid_argument("camera.height_m: expected between the floor and the ceiling");
  }
  if (!(camera_.noise_sigma >= 0.0) || !(camera_.frame_rate_hz > 0.0)) {
    throw std::invalid_argument("camera: expected noise_sigma >= 0 and frame_rate_hz > 0");
  }

  Scene& s = *scene_;
  auto add_texture = [&](Texture t) {
    s.textures.push_back(std::move(t));
    return static_cast<int>(s.textures.size()) - 1;
  };
  auto wall_rng = [&](std::uint64_t part) {
    return std::mt19937_64(SplitMix64(floor_plan_.texture_seed * 0x100000001b3ULL + part));
  };
  s.building_faces = BoxFaces(floor_plan_.building, -1.0);
  for (std::size_t f = 0; f < 4; ++f) {
    auto rng = wall_rng(f);
    s.building_faces[f].texture = add_texture(MakeWallTexture(s.building_faces[f].length_m, ceiling, rng));
  }
  for (std::size_t b = 0; b < floor_plan_.blocks.size(); ++b) {
    const Box2& box = floor_plan_.blocks[b];
    CheckBox(box, "block " + std::to_string(b));
    Scene::Solid solid{box, BoxFaces(box, 1.0)};
    for (std::size_t f = 0; f < 4; ++f) {
      auto rng = wall_rng(16 + 4 * b + f);
      solid.faces[f].texture = add_texture(MakeWallTexture(solid.faces[f].length_m, ceiling, rng));
    }
    s.blocks.push_back(solid);
  }
  for (const Furniture& item : furniture_) {
    CheckBox(item.footprint, "furniture '" + item.name + "'");
    if (!(item.height_m > 0.0 && item.height_m < ceiling)) {
      throw std::invalid_argument("furniture '" + item.name +
                                  "': expected height_m between 0 and the ceiling");
    }
    std::mt19937_64 rng(SplitMix64(floor_plan_.texture_seed ^ StableHash(item.name)));
    const bool changes = std::any_of(traversals_.begin(), traversals_.end(),
                                     [&](int id) { return !item.StandsIn(id); });
    Scene::Item it{item.footprint, item.height_m, BoxFaces(item.footprint, 1.0), -1, &item, changes};
    for (Face& f : it.faces) {
      f.texture = add_texture(MakeFurnitureTexture(item.style, f.length_m, item.height_m, false, rng));
    }
    const Box2& b = item.footprint;
    it.top_texture = add_texture(MakeFurnitureTexture(item.style, b.x1 - b.x0, b.y1 - b.y0, true, rng));
    s.items.push_back(it);
  }
  for (const auto& r : lighting_) {
    if (r.polygon.size() < 3) throw std::invalid_argument("lighting region '" + r.name + "': expected >= 3 points");
  }
}

bool IsFreeSpace(const FloorPlan& plan, const std::vector<Furniture>& furniture,
                 const Eigen::Vector2d& p, int traversal, double margin_m) {
  const Box2& b = plan.building;
  if (!(p.x() > b.x0 + margin_m && p.x() < b.x1 - margin_m && p.y() > b.y0 + margin_m &&
        p.y() < b.y1 - margin_m)) {
    return false;
  }
  for (const Box2& block : plan.blocks) {
    if (block.Contains(p, margin_m)) return false;
  }
  for (const Furniture& f : furniture) {
    if (f.StandsIn(traversal) && f.footprint.Contains(p, margin_m)) return false;
  }
  return true;
}

std::vector<Eigen::Vector4d> OfficeWorld::WallSegments() const {
  std::vector<Eigen::Vector4d> segments;
  auto add_box = [&](const Box2& b) {
    segments.emplace_back(b.x0, b.y0, b.x1, b.y0);
    segments.emplace_back(b.x1, b.y0, b.x1, b.y1);
    segments.emplace_back(b.x1, b.y1, b.x0, b.y1);
    segments.emplace_back(b.x0, b.y1, b.x0, b.y0);
  };
  add_box(floor_plan_.building);
  for (const Box2& b : floor_plan_.blocks) add_box(b);
  return segments;
}

namespace {

// Slab test of a ray (origin o, inverse direction inv) against a box:
// entry and exit distances and faces (BoxFaces order).
struct SlabHit {
  double t_in, t_out;
  int entry_face, exit_face;
};

bool Slab(const Box2& b, const Eigen::Vector2d& o, const Eigen::Vector2d& inv, SlabHit& hit) {
  const double tx1 = (b.x0 - o.x()) * inv.x(), tx2 = (b.x1 - o.x()) * inv.x();
  const double ty1 = (b.y0 - o.y()) * inv.y(), ty2 = (b.y1 - o.y()) * inv.y();
  const double txn = std::min(tx1, tx2), tyn = std::min(ty1, ty2);
  const double txf = std::max(tx1, tx2), tyf = std::max(ty1, ty2);
  hit.t_in = std::max(txn, tyn);
  hit.t_out = std::min(txf, tyf);
  if (hit.t_out < std::max(hit.t_in, 0.0)) return false;
  hit.entry_face = txn > tyn ? (inv.x() > 0 ? 0 : 1) : (inv.y() > 0 ? 2 : 3);
  hit.exit_face = txf < tyf ? (inv.x() > 0 ? 1 : 0) : (inv.y() > 0 ? 3 : 2);
  return true;
}

struct ItemHit {
  double t_in, t_out;
  int face;
  int item;
  bool ghost;  // a changing item absent from this traversal: changes pixels, hides nothing
};

// Where a ray at elevation tan_el meets a box item of height h (entered at
// t_in, left at t_out): on its side (returns t_in, top = false), on its top
// (top = true), or not at all (infinity: over it, or the floor comes first).
double MeetItem(double camera_height, double tan_el, double t_in, double t_out, double h, bool& top) {
  top = false;
  const double z_in = camera_height + t_in * tan_el;
  if (z_in < 0.0) return kInf;
  if (z_in <= h) return t_in;
  if (tan_el < 0.0) {
    const double t_top = (h - camera_height) / tan_el;
    if (t_top <= t_out) {
      top = true;
      return t_top;
    }
  }
  return kInf;
}

// Procedural floor (carpet tiles) and ceiling (tiles with light panels):
// tile lines fade once a pixel covers more than a line's width.
cv::Vec3f FloorColour(double x, double y, double footprint_m) {
  const double tile = 0.5;
  const double fx = std::floor(x / tile), fy = std::floor(y / tile);
  const auto h = SplitMix64(static_cast<std::uint64_t>(static_cast<std::int64_t>(fx) * 73856093) ^
                            static_cast<std::uint64_t>(static_cast<std::int64_t>(fy) * 19349663));
  const float shade = 0.9f + 0.2f * static_cast<float>(h & 0xff) / 255.0f;
  cv::Vec3f c(95.0f * shade, 90.0f * shade, 85.0f * shade);
  const double line = std::min(x / tile - fx, y / tile - fy) * tile;
  if (line < 0.015) {
    const float fade = static_cast<float>(std::min(1.0, 0.015 / std::max(footprint_m, 1e-9)));
    c *= 1.0f - 0.35f * std::min(1.0f, fade);
  }
  return c;
}

cv::Vec3f CeilingColour(double x, double y, double footprint_m) {
  const double tile = 0.6;
  const double fx = std::floor(x / tile), fy = std::floor(y / tile);
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  cv::Vec3f c = (ix % 4 == 0 && iy % 2 == 0) ? cv::Vec3f(250, 250, 245) : cv::Vec3f(205, 205, 200);
  const double line = std::min(x / tile - fx, y / tile - fy) * tile;
  if (line < 0.02) {
    const float fade = static_cast<float>(std::min(1.0, 0.02 / std::max(footprint_m, 1e-9)));
    c *= 1.0f - 0.3f * fade;
  }
  return c;
}

}  // namespace

cv::Mat3b OfficeWorld::Render(const Pose2& T_world_camera, int traversal,
                              std::uint64_t noise_seed, RenderDetail* detail) const {
  const Scene& s = *scene_;
  const int width = camera_.width_px, height = camera_.height_px;
  const double hc = camera_.height_m, ceiling = floor_plan_.ceiling_height_m;
  const double hfov = camera_.hfov_deg * std::numbers::pi / 180.0;
  const double pixel_angle = hfov / width;
  const double fv = 0.5 * height / std::tan(0.5 * camera_.vfov_deg * std::numbers::pi / 180.0);
  const double cx = 0.5 * (width - 1), cy = 0.5 * (height - 1);
  const Eigen::Vector2d o = T_world_camera.translation();
  const Eigen::Vector2d light = Eigen::Vector2d(0.6, 0.8);

  std::vector<std::pair<int, bool>> candidates;  // item, ghost
  for (std::size_t i = 0; i < s.items.size(); ++i) {
    const bool stands = s.items[i].furniture->StandsIn(traversal);
    if (stands || s.items[i].changes) candidates.emplace_back(static_cast<int>(i), !stands);
  }
  std::vector<const LightingRegion*> lights, changing_lights;
  for (const auto& r : lighting_) {
    if (r.GainIn(traversal) != 1.0) lights.push_back(&r);
    if (std::any_of(traversals_.begin(), traversals_.end(),
                    [&](int id) { return r.GainIn(id) != r.GainIn(traversal); })) {
      changing_lights.push_back(&r);
    }
  }

  cv::Mat3b image(height, width);
  if (detail != nullptr) {
    detail->depth_m.create(height, width);
    detail->surface.create(height, width);
  }
  std::size_t changed_pixels = 0;
  std::vector<ItemHit> hits;
  for (int c = 0; c < width; ++c) {
    const double psi = T_world_camera.theta() + (cx - c) * pixel_angle;
    Eigen::Vector2d dir(std::cos(psi), std::sin(psi));
    for (int k = 0; k < 2; ++k) {
      if (std::abs(dir[k]) < 1e-12) dir[k] = 1e-12;
    }
    const Eigen::Vector2d inv = dir.cwiseInverse();

    // The wall: the building's exit or the nearest block's entry. The
    // camera is inside the building (the trajectory is checked for that).
    SlabHit slab{};
    Slab(floor_plan_.building, o, inv, slab);
    double t_wall = slab.t_out;
    const Face* wall = &s.building_faces[static_cast<std::size_t>(slab.exit_face)];
    for (const auto& b : s.blocks) {
      if (Slab(b.box, o, inv, slab) && slab.t_in > 0.0 && slab.t_in < t_wall) {
        t_wall = slab.t_in;
        wall = &b.faces[static_cast<std::size_t>(slab.entry_face)];
      }
    }
    hits.clear();
    for (const auto& [i, ghost] : candidates) {
      if (Slab(s.items[static_cast<std::size_t>(i)].box, o, inv, slab) && slab.t_in > 0.0 &&
          slab.t_in < t_wall) {
        hits.push_back({slab.t_in, slab.t_out, slab.entry_face, i, ghost});
      }
    }
    std::sort(hits.begin(), hits.end(), [](const ItemHit& a, const ItemHit& b) { return a.t_in < b.t_in; });

    for (int r = 0; r < height; ++r) {
      const double tan_el = (cy - r) / fv;
      const double sin_el = std::abs(tan_el) / std::sqrt(1.0 + tan_el * tan_el);
      double t = kInf;
      SurfaceKind kind = SurfaceKind::kWall;
      cv::Vec3f colour;
      double shade = 1.0;
      bool changed = false;  // differs from some other traversal
      for (const ItemHit& h : hits) {
        const auto& item = s.items[static_cast<std::size_t>(h.item)];
        bool top = false;
        const double t_hit = MeetItem(hc, tan_el, h.t_in, h.t_out, item.height_m, top);
        if (t_hit == kInf) {
          if (hc + h.t_in * tan_el < 0.0) break;  // the floor comes first
          continue;
        }
        changed = changed || item.changes;
        if (h.ghost) continue;
        const Eigen::Vector2d p = o + t_hit * dir;
        if (top) {
          const double footprint = t_hit * pixel_angle / std::max(0.2, sin_el);
          colour = s.textures[static_cast<std::size_t>(item.top_texture)].Sample(
              p.x() - item.box.x0, p.y() - item.box.y0, footprint);
        } else {
          const Face& f = item.faces[static_cast<std::size_t>(h.face)];
          const double footprint = t_hit * pixel_angle / std::max(0.25, std::abs(dir.dot(f.normal)));
          colour = s.textures[static_cast<std::size_t>(f.texture)].Sample(
              (p - f.left_end).dot(f.right), hc + t_hit * tan_el, footprint);
          shade = 0.8 + 0.2 * f.normal.dot(light);
        }
        t = t_hit;
        kind = SurfaceKind::kFurniture;
        break;
      }
      if (t == kInf) {
        const double z = hc + t_wall * tan_el;
        if (z >= 0.0 && z <= ceiling) {
          const double cos_inc = std::max(0.25, std::abs(dir.dot(wall->normal)));
          const double footprint = t_wall * pixel_angle / cos_inc;
          const Eigen::Vector2d p = o + t_wall * dir;
          colour = s.textures[static_cast<std::size_t>(wall->texture)].Sample((p - wall->left_end).dot(wall->right), z, footprint);
          shade = 0.8 + 0.2 * wall->normal.dot(light);
          t = t_wall;
        } else if (z < 0.0) {
          t = -hc / tan_el;
          const Eigen::Vector2d p = o + t * dir;
          colour = FloorColour(p.x(), p.y(), t * pixel_angle / std::max(0.05, sin_el));
          kind = SurfaceKind::kFloor;
        } else {
          t = (ceiling - hc) / tan_el;
          const Eigen::Vector2d p = o + t * dir;
          colour = CeilingColour(p.x(), p.y(), t * pixel_angle / std::max(0.05, sin_el));
          kind = SurfaceKind::kCeiling;
        }
      }
      const Eigen::Vector2d p = o + t * dir;
      shade /= 1.0 + 0.02 * t;
      cv::Vec3f gain(1.0f, 1.0f, 1.0f);
      for (const LightingRegion* l : lights) {
        if (PointInPolygon(l->polygon, p)) {
          const double g = l->GainIn(traversal);
          gain = cv::Vec3f(static_cast<float>(g * l->tint[0]), static_cast<float>(g * l->tint[1]),
                           static_cast<float>(g * l->tint[2]));
          break;
        }
      }
      for (const LightingRegion* l : changing_lights) {
        if (!changed && PointInPolygon(l->polygon, p)) changed = true;
      }
      changed_pixels += changed ? 1 : 0;
      const std::uint64_t pixel = static_cast<std::uint64_t>(r) * static_cast<std::uint64_t>(width) +
                                  static_cast<std::uint64_t>(c);
      const float noise = camera_.noise_sigma > 0.0
                              ? static_cast<float>(camera_.noise_sigma) *
                                    HashNormal(SplitMix64(noise_seed ^ SplitMix64(pixel)))
                              : 0.0f;
      cv::Vec3b& out = image(r, c);
      for (int k = 0; k < 3; ++k) {
        out[k] = cv::saturate_cast<std::uint8_t>(colour[k] * static_cast<float>(shade) * gain[k] + noise);
      }
      if (detail != nullptr) {
        detail->depth_m(r, c) = static_cast<float>(t);
        detail->surface(r, c) = static_cast<std::uint8_t>(kind);
      }
    }
  }
  if (detail != nullptr) {
    detail->changed_fraction = static_cast<double>(changed_pixels) / (static_cast<double>(width) * height);
  }
  return image;
}

}  // namespace catgraph
