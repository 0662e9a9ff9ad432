#include "simulation/scenario.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "backend/io/file_error.h"
#include "backend/io/internal/text_line.h"
#include "backend/io/yaml_text.h"

namespace catgraph {
namespace {

constexpr std::uintmax_t kMaxScenarioBytes = 4u << 20;
constexpr double kRobotRadiusM = 0.25;  // clearance a route keeps from walls and furniture

// Reads one YAML mapping, remembering which keys were used so that a
// misspelt key is an error instead of silently ignored.
class MapReader {
 public:
  MapReader(const YAML::Node& node, const std::string& source, std::string path)
      : node_(node), source_(source), path_(std::move(path)) {
    if (!node.IsMap()) Fail(node, "expected a mapping of keys to values");
  }

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& message) const {
    throw FileError(source_, at.Mark().is_null() ? 0 : at.Mark().line + 1,
                    (path_.empty() ? "" : path_ + ": ") + message);
  }
  [[noreturn]] void FailKey(const std::string& key, const std::string& message) const {
    Fail(node_[key], path_.empty() ? key + ": " + message : key + ": " + message);
  }

  bool Has(const std::string& key) {
    used_.insert(key);
    return node_[key].IsDefined() && !node_[key].IsNull();
  }
  YAML::Node Node(const std::string& key) {
    if (!Has(key)) Fail(node_, "missing key '" + key + "'");
    return node_[key];
  }

  template <typename T>
  T Scalar(const YAML::Node& n, const std::string& key, const char* expected) const {
    try {
      if (!n.IsScalar()) throw YAML::Exception(n.Mark(), "not a scalar");
      return n.as<T>();
    } catch (const YAML::Exception&) {
      Fail(n, key + ": expected " + expected);
    }
  }
  double Number(const std::string& key, double fallback, double lo, double hi) {
    if (!Has(key)) return fallback;
    const double v = Scalar<double>(node_[key], key, "a number");
    if (!std::isfinite(v) || v < lo || v > hi) {
      std::ostringstream range;
      range << "a number in [" << lo << ", " << hi << "], found " << v;
      FailKey(key, "expected " + range.str());
    }
    return v;
  }
  std::uint64_t Unsigned(const std::string& key, std::uint64_t fallback) {
    return Has(key) ? Scalar<std::uint64_t>(node_[key], key, "a non-negative integer") : fallback;
  }
  int Int(const std::string& key, int fallback, int lo, int hi) {
    if (!Has(key)) return fallback;
    const int v = Scalar<int>(node_[key], key, "an integer");
    if (v < lo || v > hi) {
      FailKey(key, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                       "], found " + std::to_string(v));
    }
    return v;
  }
  std::string String(const std::string& key, const std::string& fallback) {
    return Has(key) ? Scalar<std::string>(node_[key], key, "a string") : fallback;
  }
  std::vector<double> Numbers(const YAML::Node& n, const std::string& key, std::size_t count) const {
    if (!n.IsSequence() || (count > 0 && n.size() != count)) {
      Fail(n, key + ": expected a list of " + (count > 0 ? std::to_string(count) + " " : "") +
                  "numbers");
    }
    std::vector<double> out;
    for (const auto& v : n) {
      out.push_back(Scalar<double>(v, key, "a number"));
      if (!std::isfinite(out.back())) Fail(v, key + ": expected a finite number");
    }
    return out;
  }
  Box2 Box(const std::string& key) {
    const YAML::Node n = Node(key);
    const auto v = Numbers(n, key, 4);
    if (!(v[2] > v[0] && v[3] > v[1])) Fail(n, key + ": expected [x0, y0, x1, y1] with x0 < x1 and y0 < y1");
    return {v[0], v[1], v[2], v[3]};
  }
  std::vector<Eigen::Vector2d> Points(const std::string& key, std::size_t min_count) {
    const YAML::Node n = Node(key);
    if (!n.IsSequence() || n.size() < min_count) {
      Fail(n, key + ": expected a list of at least " + std::to_string(min_count) + " [x, y] points");
    }
    std::vector<Eigen::Vector2d> out;
    for (const auto& p : n) {
      const auto v = Numbers(p, key, 2);
      out.emplace_back(v[0], v[1]);
    }
    return out;
  }
  std::vector<int> Ints(const std::string& key) {
    const YAML::Node n = Node(key);
    if (!n.IsSequence()) Fail(n, key + ": expected a list of traversal ids");
    std::vector<int> out;
    for (const auto& v : n) {
      out.push_back(Scalar<int>(v, key, "an integer traversal id"));
      if (out.back() < 1) Fail(v, key + ": expected traversal ids >= 1");
    }
    return out;
  }

  // Every key of the mapping must have been read.
  void Finish() const {
    for (const auto& kv : node_) {
      // A key may be a list or a mapping in YAML (found by fuzzing).
      if (!kv.first.IsScalar()) Fail(kv.first, "expected a plain key, not a list or a mapping");
      const std::string key = kv.first.as<std::string>();
      if (!used_.count(key)) Fail(kv.first, "unknown key '" + key + "'");
    }
  }

 private:
  YAML::Node node_;
  const std::string& source_;
  std::string path_;
  std::set<std::string> used_;
};

YAML::Node LoadYaml(std::string_view text, const std::string& source) {
  return LoadYamlWithoutAliases(std::string(text), source);
}

FloorPlan ParseWorld(const YAML::Node& node, const std::string& source) {
  MapReader r(node, source, "world");
  FloorPlan plan;
  plan.building = r.Box("building");
  plan.ceiling_height_m = r.Number("ceiling_height_m", plan.ceiling_height_m, 1.5, 20.0);
  plan.texture_seed = r.Unsigned("texture_seed", plan.texture_seed);
  if (r.Has("blocks")) {
    const YAML::Node blocks = r.Node("blocks");
    if (!blocks.IsSequence()) r.Fail(blocks, "blocks: expected a list of [x0, y0, x1, y1] boxes");
    for (const auto& b : blocks) {
      const auto v = r.Numbers(b, "blocks", 4);
      if (!(v[2] > v[0] && v[3] > v[1])) r.Fail(b, "blocks: expected x0 < x1 and y0 < y1");
      plan.blocks.push_back({v[0], v[1], v[2], v[3]});
    }
  }
  r.Finish();
  return plan;
}

FloorPlan ResolveWorld(const YAML::Node& node, const std::string& source,
                       const std::filesystem::path& base_dir) {
  if (node.IsMap()) return ParseWorld(node, source);
  if (!node.IsScalar()) {
    throw FileError(source, node.Mark().line + 1,
                    "world: expected a built-in world name, a world file or a mapping");
  }
  const std::string name = node.as<std::string>();
  for (const auto& f : EmbeddedScenarioFiles()) {
    if (f.name == name + "-world") {
      const std::string world_source = "<built-in world " + name + ">";
      return ParseWorld(LoadYaml(f.text, world_source), world_source);
    }
  }
  const std::filesystem::path path = base_dir / name;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw FileError(source, node.Mark().line + 1,
                    "world: '" + name + "' is neither a built-in world (office) nor a file (" +
                        path.string() + ")");
  }
  const std::string world_source = path.string();
  return ParseWorld(LoadYaml(ReadWholeFile(path, kMaxScenarioBytes, "a world file"), world_source), world_source);
}

template <typename Fn>
void ForEachItem(MapReader& r, const std::string& key, Fn fn) {
  if (!r.Has(key)) return;
  const YAML::Node list = r.Node(key);
  if (!list.IsSequence()) r.Fail(list, key + ": expected a list");
  for (const auto& item : list) fn(item);
}

// Routes keep kRobotRadiusM from walls and from the furniture of their own
// traversal, checked every 5 cm.
void CheckRoutes(const Scenario& s, const YAML::Node& traversals, const std::string& source) {
  for (std::size_t i = 0; i < s.traversals.size(); ++i) {
    const TraversalPlan& t = s.traversals[i];
    const int line = traversals[i].Mark().line + 1;
    std::vector<Eigen::Vector2d> route;
    try {
      route = OffsetRoute(t.route, t.lateral_offset_m);
    } catch (const std::invalid_argument& e) {  // e.g. every waypoint the same
      throw FileError(source, line, "traversal " + std::to_string(t.id) + ": " + e.what());
    }
    for (std::size_t k = 1; k < route.size(); ++k) {
      const double length = (route[k] - route[k - 1]).norm();
      for (double d = 0.0; d <= length; d += 0.05) {
        const Eigen::Vector2d p = route[k - 1] + d / length * (route[k] - route[k - 1]);
        if (!IsFreeSpace(s.floor_plan, s.furniture, p, t.id, kRobotRadiusM)) {
          std::ostringstream where;
          where.precision(3);
          where << "traversal " << t.id << ": the route passes within " << kRobotRadiusM
                << " m of a wall or furniture at (" << p.x() << ", " << p.y()
                << "); expected a route through free space";
          throw FileError(source, line, where.str());
        }
      }
    }
  }
}

// What changes between traversals must lie inside a declared changed
// region, so that the per-frame `changed` flags are ground truth.
void CheckChangesDeclared(const Scenario& s, const std::vector<int>& marks, const std::string& source) {
  std::vector<int> ids;
  for (const auto& t : s.traversals) ids.push_back(t.id);
  // Every vertex, pulled 1 mm towards the centroid so that a region drawn
  // on the same outline counts, lies inside a changed region.
  auto covered = [&](const Polygon2& polygon) {
    Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
    for (const auto& p : polygon) centroid += p / static_cast<double>(polygon.size());
    return std::all_of(polygon.begin(), polygon.end(), [&](const Eigen::Vector2d& vertex) {
      const Eigen::Vector2d p = vertex + 1e-3 * (centroid - vertex).normalized();
      return std::any_of(s.changed_regions.begin(), s.changed_regions.end(),
                         [&](const ChangedRegion& r) { return PointInPolygon(r.polygon, p); });
    });
  };
  for (std::size_t i = 0; i < s.furniture.size(); ++i) {
    const Furniture& f = s.furniture[i];
    const bool everywhere = std::all_of(ids.begin(), ids.end(), [&](int id) { return f.StandsIn(id); });
    if (!everywhere && !covered(f.footprint.ToPolygon())) {
      throw FileError(source, marks[i],
                      "furniture '" + f.name + "' does not stand in every traversal, so it must "
                      "lie inside one of changed_regions");
    }
  }
  for (std::size_t i = 0; i < s.lighting.size(); ++i) {
    const LightingRegion& l = s.lighting[i];
    const bool constant = std::all_of(ids.begin(), ids.end(), [&](int id) {
      return l.GainIn(id) == l.GainIn(ids.front());
    });
    if (!constant && !covered(l.polygon)) {
      throw FileError(source, marks[s.furniture.size() + i],
                      "lighting '" + l.name + "' changes between traversals, so it must lie "
                      "inside one of changed_regions");
    }
  }
}

}  // namespace

std::vector<std::string> BuiltInScenarioNames() {
  std::vector<std::string> names;
  for (const auto& f : EmbeddedScenarioFiles()) {
    if (!f.name.ends_with("-world")) names.emplace_back(f.name);
  }
  return names;
}

std::string_view BuiltInScenarioText(std::string_view name) {
  std::string names;
  for (const auto& f : EmbeddedScenarioFiles()) {
    if (f.name == name) return f.text;
    names += (names.empty() ? "" : ", ") + std::string(f.name);
  }
  throw std::invalid_argument("no built-in scenario '" + std::string(name) + "'; expected one of " +
                              names);
}

Scenario LoadScenario(const std::string& name_or_path) {
  for (const auto& f : EmbeddedScenarioFiles()) {
    if (f.name == name_or_path && !f.name.ends_with("-world")) {
      return ParseScenario(f.text, "<built-in scenario " + name_or_path + ">", ".");
    }
  }
  const std::filesystem::path path(name_or_path);
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    std::string names;
    for (const auto& n : BuiltInScenarioNames()) names += (names.empty() ? "" : ", ") + n;
    throw FileError(name_or_path, 0, "is neither a built-in scenario (" + names +
                                         ") nor a scenario file");
  }
  return ParseScenario(ReadWholeFile(path, kMaxScenarioBytes, "a scenario file (YAML)"), path.string(),
                       path.parent_path());
}

Scenario ParseScenario(std::string_view yaml, const std::string& source,
                       const std::filesystem::path& base_dir) {
  const YAML::Node root = LoadYaml(yaml, source);
  MapReader r(root, source, "");
  Scenario s;
  s.name = r.String("name", "");
  if (s.name.empty()) r.Fail(root, "missing key 'name'");
  s.description = r.String("description", "");
  s.seed = r.Unsigned("seed", s.seed);
  s.floor_plan = ResolveWorld(r.Node("world"), source, base_dir);
  // The same building redecorated: every wall texture drawn from another seed.
  s.floor_plan.texture_seed = r.Unsigned("texture_seed", s.floor_plan.texture_seed);
  s.changed_pixel_fraction = r.Number("changed_pixel_fraction", s.changed_pixel_fraction, 1e-6, 1.0);

  if (r.Has("camera")) {
    MapReader c(r.Node("camera"), source, "camera");
    CameraOptions& cam = s.camera;
    cam.width_px = c.Int("width_px", cam.width_px, 2, 8192);
    cam.height_px = c.Int("height_px", cam.height_px, 2, 8192);
    cam.hfov_deg = c.Number("hfov_deg", cam.hfov_deg, 1.0, 359.0);
    cam.vfov_deg = c.Number("vfov_deg", cam.vfov_deg, 1.0, 169.0);
    cam.height_m = c.Number("height_m", cam.height_m, 0.05, s.floor_plan.ceiling_height_m - 0.05);
    cam.frame_rate_hz = c.Number("frame_rate_hz", cam.frame_rate_hz, 0.01, 1000.0);
    cam.noise_sigma = c.Number("noise_sigma", cam.noise_sigma, 0.0, 100.0);
    c.Finish();
  }
  if (r.Has("robot")) {
    MapReader c(r.Node("robot"), source, "robot");
    RobotOptions& robot = s.robot;
    robot.track_m = c.Number("track_m", robot.track_m, 0.05, 5.0);
    robot.lookahead_m = c.Number("lookahead_m", robot.lookahead_m, 0.05, 10.0);
    robot.max_turn_rate_rad_s = c.Number("max_turn_rate_rad_s", robot.max_turn_rate_rad_s, 0.01, 10.0);
    robot.min_speed_m_s = c.Number("min_speed_m_s", robot.min_speed_m_s, 0.01, 3.0);
    c.Finish();
  }
  if (r.Has("odometry")) {
    MapReader c(r.Node("odometry"), source, "odometry");
    OdometryOptions& o = s.odometry;
    o.rate_hz = c.Number("rate_hz", o.rate_hz, 0.1, 1000.0);
    o.noise_m_per_sqrt_m = c.Number("noise_m_per_sqrt_m", o.noise_m_per_sqrt_m, 0.0, 1.0);
    o.left_scale_error = c.Number("left_scale_error", o.left_scale_error, -0.49, 0.49);
    o.right_scale_error = c.Number("right_scale_error", o.right_scale_error, -0.49, 0.49);
    o.track_error = c.Number("track_error", o.track_error, -0.49, 0.49);
    c.Finish();
  }
  std::set<int> traversal_ids;
  const YAML::Node traversals = r.Node("traversals");
  ForEachItem(r, "traversals", [&](const YAML::Node& n) {
    MapReader t(n, source, "traversal");
    TraversalPlan plan;
    plan.id = t.Int("id", static_cast<int>(s.traversals.size()) + 1, 1, 1000000);
    if (!traversal_ids.insert(plan.id).second) t.Fail(n, "id " + std::to_string(plan.id) + " is used twice");
    if (!s.traversals.empty() && plan.id < s.traversals.back().id) {
      t.Fail(n, "expected traversal ids in increasing order");
    }
    plan.speed_m_s = t.Number("speed_m_s", plan.speed_m_s, s.robot.min_speed_m_s, 3.0);
    plan.lateral_offset_m = t.Number("lateral_offset_m", plan.lateral_offset_m, -5.0, 5.0);
    plan.route = t.Points("route", 2);
    t.Finish();
    s.traversals.push_back(std::move(plan));
  });
  if (s.traversals.empty()) r.Fail(traversals, "traversals: expected at least one traversal");

  std::vector<int> marks;  // line of every furniture item, then every lighting region
  ForEachItem(r, "furniture", [&](const YAML::Node& n) {
    MapReader f(n, source, "furniture");
    Furniture item;
    item.name = f.String("name", "");
    if (item.name.empty()) f.Fail(n, "missing key 'name'");
    try {
      item.style = FurnitureStyleFromString(f.String("style", "cabinet"));
    } catch (const std::invalid_argument& e) {
      f.FailKey("style", e.what());
    }
    item.footprint = f.Box("box");
    item.height_m = f.Number("height_m", item.height_m, 0.05, s.floor_plan.ceiling_height_m - 0.01);
    item.traversals = f.Ints("traversals");
    f.Finish();
    marks.push_back(n.Mark().line + 1);
    s.furniture.push_back(std::move(item));
  });
  ForEachItem(r, "lighting", [&](const YAML::Node& n) {
    MapReader l(n, source, "lighting");
    LightingRegion region;
    region.name = l.String("name", "lighting");
    region.polygon = l.Points("polygon", 3);
    const YAML::Node gains = l.Node("gain");
    if (!gains.IsMap()) l.Fail(gains, "gain: expected a mapping of traversal id to gain");
    for (const auto& kv : gains) {
      const int id = l.Scalar<int>(kv.first, "gain", "traversal ids as keys");
      const double g = l.Scalar<double>(kv.second, "gain", "a number");
      if (!(g >= 0.0 && g <= 4.0)) l.Fail(kv.second, "gain: expected a gain in [0, 4]");
      region.gain[id] = g;
    }
    if (l.Has("tint")) {
      const auto v = l.Numbers(l.Node("tint"), "tint", 3);
      region.tint = cv::Vec3d(v[2], v[1], v[0]);  // written RGB, stored BGR
    }
    l.Finish();
    marks.push_back(n.Mark().line + 1);
    s.lighting.push_back(std::move(region));
  });
  ForEachItem(r, "changed_regions", [&](const YAML::Node& n) {
    MapReader c(n, source, "changed region");
    ChangedRegion region;
    region.name = c.String("name", "changed region");
    region.kind = c.String("kind", "furniture");
    region.polygon = c.Points("polygon", 3);
    c.Finish();
    s.changed_regions.push_back(std::move(region));
  });
  r.Finish();
  for (const Furniture& f : s.furniture) {
    for (const int id : f.traversals) {
      if (!traversal_ids.count(id)) {
        throw FileError(source, 0, "furniture '" + f.name + "' names traversal " +
                                       std::to_string(id) + ", which the scenario does not drive");
      }
    }
  }
  CheckRoutes(s, traversals, source);
  CheckChangesDeclared(s, marks, source);
  return s;
}

}  // namespace catgraph
