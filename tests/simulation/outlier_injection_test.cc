// Outlier injection: the protocol of robust-backend-notes.md §2, checked on
// simulated graphs whose structure is known.
#include <set>
#include <sstream>

#include "tests/catch.h"

#include "backend/io/graph_io.h"
#include "simulation/manhattan_world.h"
#include "simulation/outlier_injection.h"
#include "tests/test_support.h"

namespace catgraph {
namespace {

PoseGraph2 Manhattan(int poses = 300) {
  ManhattanWorldOptions options;
  options.num_poses = poses;
  options.seed = 4;
  return SimulateManhattanWorld(options).graph;
}

// A 3D chain of `n` poses along x with a few loop closures.
PoseGraph3 Chain3(int n) {
  PoseGraph3 g;
  std::mt19937_64 rng(2);
  for (int i = 0; i < n; ++i) g.vertices[PoseId(i)] = {PoseId(i), testing::RandomPose3(rng), false};
  InformationMatrix<Pose3> info = InformationMatrix<Pose3>::Identity() * 7.0;
  info(0, 4) = info(4, 0) = 0.5;  // non-diagonal: copied as a whole
  auto add = [&g](int id, int from, int to, const Pose3& z, const InformationMatrix<Pose3>& i,
                   ClosureKind kind) {
    Constraint<Pose3> c;
    c.id = ClosureId(id);
    c.from = PoseId(from);
    c.to = PoseId(to);
    c.measurement = {z, i};
    c.kind = kind;
    g.constraints.push_back(c);
  };
  for (int i = 0; i + 1 < n; ++i) {
    add(i, i, i + 1, testing::RandomPose3(rng, 1.0), InformationMatrix<Pose3>::Identity(),
        ClosureKind::kOdometry);
  }
  add(n, 0, n / 2, Pose3(), info, ClosureKind::kUnknown);
  return g;
}

OutlierOptions Options(OutlierPolicy policy, int count, std::uint64_t seed = 1) {
  OutlierOptions o;
  o.policy = policy;
  o.count = count;
  o.seed = seed;
  return o;
}

std::vector<const Constraint<Pose2>*> Added(const PoseGraph2& g,
                                            const std::vector<InjectedClosure>& injected) {
  std::set<ClosureId> ids;
  for (const auto& c : injected) ids.insert(c.id);
  std::vector<const Constraint<Pose2>*> added;
  for (const auto& c : g.constraints) {
    if (ids.contains(c.id)) added.push_back(&c);
  }
  return added;
}

TEST_CASE("every policy injects exactly the requested number of edges in ceil(N/g) groups",
          "[simulation][outliers]") {
  for (OutlierPolicy policy : {OutlierPolicy::kRandom, OutlierPolicy::kLocal,
                               OutlierPolicy::kRandomGrouped, OutlierPolicy::kLocalGrouped,
                               OutlierPolicy::kHierarchical}) {
    for (int count : {0, 1, 7, 100}) {
      PoseGraph2 g = Manhattan();
      const std::size_t before = g.constraints.size();
      const auto injected = InjectOutliers(g, Options(policy, count));
      CAPTURE(ToString(policy), count);
      CHECK(injected.size() == static_cast<std::size_t>(count));
      CHECK(g.constraints.size() == before + static_cast<std::size_t>(count));
      const int group_size = GroupSize(Options(policy, count));
      const int groups = count == 0 ? 0 : injected.back().group + 1;
      CHECK(groups == (count + group_size - 1) / group_size);
      std::set<ClosureId> ids;
      for (const auto& c : injected) ids.insert(c.id);
      CHECK(ids.size() == injected.size());  // fresh, distinct ids
    }
  }
}

TEST_CASE("pairs are never consecutive, grouped edges shift by one id, local pairs stay "
          "within the window",
          "[simulation][outliers]") {
  for (OutlierPolicy policy : {OutlierPolicy::kRandom, OutlierPolicy::kLocal,
                               OutlierPolicy::kRandomGrouped, OutlierPolicy::kLocalGrouped}) {
    PoseGraph2 g = Manhattan();
    OutlierOptions o = Options(policy, 500, 11);
    o.local_window = 12;
    const auto injected = InjectOutliers(g, o);
    const auto added = Added(g, injected);
    const bool local = policy == OutlierPolicy::kLocal || policy == OutlierPolicy::kLocalGrouped;
    std::size_t far = 0;
    for (std::size_t k = 0; k < injected.size(); ++k) {
      const auto& c = injected[k];
      const std::int64_t gap = c.to.value() - c.from.value();
      CAPTURE(ToString(policy), k, c.from.value(), c.to.value());
      CHECK(gap >= 2);
      CHECK(c.to.value() < 300);
      if (local) CHECK(gap <= o.local_window);
      far += gap > o.local_window;
      if (k > 0 && injected[k - 1].group == c.group) {
        CHECK(c.from.value() == injected[k - 1].from.value() + 1);
        CHECK(c.to.value() == injected[k - 1].to.value() + 1);
        // One measurement per group.
        CHECK(testing::ApproxEqual(added[k]->measurement.mean, added[k - 1]->measurement.mean, 0.0));
      }
    }
    if (!local) CHECK(far > injected.size() / 2);  // random pairs spread over the graph
  }
}

TEST_CASE("the measurement follows N(0, 0.3 m) and N(0, 10 deg)", "[simulation][outliers]") {
  PoseGraph2 g = Manhattan(3000);
  const auto added = Added(g, InjectOutliers(g, Options(OutlierPolicy::kRandom, 2000, 5)));
  double sx = 0, sy = 0, st = 0;
  for (const auto* c : added) {
    sx += c->measurement.mean.x() * c->measurement.mean.x();
    sy += c->measurement.mean.y() * c->measurement.mean.y();
    st += c->measurement.mean.theta() * c->measurement.mean.theta();
  }
  const double n = static_cast<double>(added.size());
  // Standard error of a sample standard deviation over 2000 draws: ~1.6%.
  CHECK(std::sqrt(sx / n) == Approx(0.3).epsilon(0.06));
  CHECK(std::sqrt(sy / n) == Approx(0.3).epsilon(0.06));
  CHECK(std::sqrt(st / n) == Approx(10.0 * std::numbers::pi / 180.0).epsilon(0.06));
}

TEST_CASE("3D outliers are small rotations in g2o quaternion order, information copied whole",
          "[simulation][outliers]") {
  PoseGraph3 g = Chain3(200);
  const InformationMatrix<Pose3> first_closure = g.constraints.back().measurement.information;
  const auto injected = InjectOutliers(g, Options(OutlierPolicy::kRandom, 300, 3));
  // Write and read back: the file carries qx qy qz qw.
  std::ostringstream text;
  WriteG2o(g, text);
  std::istringstream in(text.str());
  const PoseGraph3 back = std::get<PoseGraph3>(ReadGraph(in, "injected.g2o").graph);
  double sum_angle = 0.0, max_angle = 0.0;
  for (std::size_t k = back.constraints.size() - injected.size(); k < back.constraints.size(); ++k) {
    const auto& c = back.constraints[k];
    const double angle = RotationAngle(c.measurement.mean.rotation());
    sum_angle += angle;
    max_angle = std::max(max_angle, angle);
    CHECK(c.measurement.information.isApprox(first_closure));
    CHECK(c.kind == ClosureKind::kInjected);
  }
  // Three independent N(0, 10 deg) angles: mean rotation ~ 15.9 deg; Vertigo's
  // scalar-first bug would give rotations near 180 deg.
  const double mean_deg = sum_angle / 300.0 * 180.0 / std::numbers::pi;
  CHECK(mean_deg > 12.0);
  CHECK(mean_deg < 20.0);
  CHECK(max_angle < 70.0 * std::numbers::pi / 180.0);
}

TEST_CASE("information given explicitly replaces the copied one", "[simulation][outliers]") {
  PoseGraph2 g = Manhattan();
  OutlierOptions o = Options(OutlierPolicy::kRandom, 20);
  Eigen::MatrixXd info(3, 3);
  info << 4, 1, 0, 1, 5, 0, 0, 0, 9;
  o.information = info;
  for (const auto* c : Added(g, InjectOutliers(g, o))) {
    CHECK(c->measurement.information.isApprox(info));
  }
  o.information = Eigen::MatrixXd::Identity(6, 6);
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("expected a 3x3 matrix"));
  o.information = -Eigen::MatrixXd::Identity(3, 3);
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("positive definite"));
}

TEST_CASE("the same seed gives byte-identical files, another seed another file",
          "[simulation][outliers]") {
  auto spoil = [](OutlierPolicy policy, std::uint64_t seed) {
    AnyPoseGraph g = Manhattan();
    InjectOutliers(g, Options(policy, 50, seed));
    std::ostringstream out;
    WriteG2o(g, out);
    return out.str();
  };
  for (OutlierPolicy policy : {OutlierPolicy::kRandom, OutlierPolicy::kLocalGrouped,
                               OutlierPolicy::kHierarchical}) {
    CHECK(spoil(policy, 7) == spoil(policy, 7));
    CHECK(spoil(policy, 7) != spoil(policy, 8));
  }
}

TEST_CASE("hierarchical children are the false visual match carried along both traversals' "
          "odometry",
          "[simulation][outliers][hierarchy]") {
  ManhattanWorldOptions world;
  world.num_poses = 400;
  world.seed = 8;
  PoseGraph2 truth = SimulateManhattanWorld(world).truth;  // exact odometry
  OutlierOptions o = Options(OutlierPolicy::kHierarchical, 40, 2);
  o.group_size = 8;
  const auto injected = InjectOutliers(truth, o);
  const auto added = Added(truth, injected);
  for (std::size_t k = 0; k < injected.size(); ++k) {
    const std::size_t first = k - static_cast<std::size_t>(k % 8);  // the group's visual closure
    const auto* parent = added[first];
    const auto* child = added[k];
    if (k == first) {
      CHECK(child->kind == ClosureKind::kVisual);
      CHECK(!injected[k].parent);
      CHECK(child->provenance.parents.empty());
      continue;
    }
    CHECK(child->kind == ClosureKind::kOdometryInferred);
    REQUIRE(injected[k].parent);
    CHECK(*injected[k].parent == parent->id);
    CHECK(child->provenance.parents == std::vector<ClosureId>{parent->id});
    // With exact odometry, odo(a -> a+j) = T_a^-1 T_a+j, so the child must be
    // T_{v1+j}^-1 T_{v1} z T_{v2}^-1 T_{v2+j}.
    const auto pose = [&](PoseId id) { return *truth.vertices.at(id).pose; };
    const Pose2 expected = pose(child->from).Inverse() * pose(parent->from) *
                           parent->measurement.mean * pose(parent->to).Inverse() *
                           pose(child->to);
    CHECK(testing::ApproxEqual(child->measurement.mean, expected, 1e-9));
  }
}

TEST_CASE("labels mark exactly the injected closures and keep their parents",
          "[simulation][outliers]") {
  AnyPoseGraph g = Manhattan();
  const std::size_t true_closures = [&] {
    std::size_t n = 0;
    for (const auto& c : std::get<PoseGraph2>(g).constraints) n += !c.IsBetweenConsecutivePoses();
    return n;
  }();
  OutlierOptions o = Options(OutlierPolicy::kHierarchical, 12, 3);
  o.group_size = 4;
  const auto injected = InjectOutliers(g, o);
  const auto labels = LabelClosures(g, injected);
  REQUIRE(labels.size() == true_closures + 12);
  std::size_t outliers = 0, with_parent = 0;
  for (const auto& l : labels) {
    outliers += l.outlier;
    with_parent += l.parent.has_value();
    if (!l.outlier) CHECK(!l.group);
  }
  CHECK(outliers == 12);
  CHECK(with_parent == 9);
  CHECK(labels.back().parent == labels[labels.size() - 4].id);
}

TEST_CASE("injection rejects bad options with the offending value", "[simulation][outliers]") {
  PoseGraph2 g = Manhattan(50);
  OutlierOptions o = Options(OutlierPolicy::kRandom, 5);
  o.group_size = 3;
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("random-grouped"));
  o = Options(OutlierPolicy::kHierarchical, 5);
  o.group_size = 1;
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("group size >= 2"));
  o = Options(OutlierPolicy::kLocal, -1);
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("count must be in [0, 100000], got -1"));
  o = Options(OutlierPolicy::kLocal, kMaxOutliers + 1);
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("count must be in [0, 100000], got 100001"));
  o = Options(OutlierPolicy::kRandomGrouped, 5);
  o.group_size = 48;
  CHECK_THROWS_WITH(InjectOutliers(g, o), Catch::Contains("needs at least 51 poses"));
  // Hierarchical children need the odometry between consecutive poses.
  PoseGraph2 gap = Manhattan(50);
  std::erase_if(gap.constraints, [](const auto& c) { return c.from.value() == 20 && c.to.value() == 21; });
  o = Options(OutlierPolicy::kHierarchical, 200);
  o.group_size = 10;
  CHECK_THROWS_WITH(InjectOutliers(gap, o), Catch::Contains("between poses 20 and 21"));
}

}  // namespace
}  // namespace catgraph
