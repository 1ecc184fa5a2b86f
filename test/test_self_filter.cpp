// The self filter against brute force over every link triangle (on or within padding, inside a
// closed link, ray through a link), and its purpose: a depth camera's scan of the robot, filtered
// and inserted, leaves no occupied voxel on the robot while the table stays (the object filter:
// test_self_filter_objects.cpp, one binary).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/object_filter.h"
#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/robot/robot_model.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(17);
  return r;
}

// The robot's collision geometry in the scan frame, element by element, for the oracle.
struct WorldElement {
  int link = -1;
  std::vector<Triangle> triangles;  // empty for a sphere or a cylinder
  bool closed = false;
  bool cylinder = false;            // radius `cylinder_radius`, length 2 `half_length` along z of `pose`
  double cylinder_radius = 0.0, half_length = 0.0;
  Transform pose;
  Vec3 centre = Vec3::Zero();  // bounding ball (the sphere itself for a sphere)
  double radius = 0.0;
};

std::vector<WorldElement> world_elements(const RobotModel& model, const std::vector<double>& state) {
  std::vector<Transform> poses;
  forward_kinematics(model, state.data(), poses);
  std::vector<WorldElement> out;
  for (std::size_t l = 0; l < poses.size(); ++l) {
    for (const CollisionElement& e : model.links()[l].collision) {
      WorldElement w;
      w.link = static_cast<int>(l);
      const Transform pose = poses[l] * e.origin;
      if (e.shape == CollisionElement::Shape::kSphere) {
        w.centre = pose.t;
        w.radius = e.radius;
      } else if (e.shape == CollisionElement::Shape::kCylinder) {
        w.cylinder = true;
        w.cylinder_radius = e.radius;
        w.half_length = 0.5 * e.length;
        w.pose = pose;
        w.centre = pose.t;
        w.radius = std::hypot(e.radius, 0.5 * e.length);
      } else {
        w.closed = is_closed(*e.mesh);
        for (const auto& f : e.mesh->triangles) {
          const auto& v = e.mesh->vertices;
          w.triangles.push_back({pose * v[f[0]], pose * v[f[1]], pose * v[f[2]]});
          for (int k = 0; k < 3; ++k) w.centre += w.triangles.back()[k] / (3.0 * e.mesh->triangles.size());
        }
        for (const Triangle& t : w.triangles) {
          for (int k = 0; k < 3; ++k) w.radius = std::max(w.radius, (t[k] - w.centre).norm());
        }
      }
      out.push_back(std::move(w));
    }
  }
  return out;
}

double segment_ball_distance(const Vec3& a, const Vec3& b, const Vec3& c) {
  return (closest_point_on_segment(c, a, b) - c).norm();
}

// A solid cylinder is a disc times an interval: the distance is the hypotenuse of how far p is
// outside each.
double cylinder_distance(const WorldElement& e, const Vec3& p) {
  const Vec3 q = e.pose.inverse() * p;
  const double radial = std::max(0.0, std::hypot(q.x(), q.y()) - e.cylinder_radius);
  const double axial = std::max(0.0, std::abs(q.z()) - e.half_length);
  return std::hypot(radial, axial);
}

// Brute force: the distance from p to the element (0 inside a closed one, by ray parity).
double element_distance(const WorldElement& e, const Vec3& p) {
  if (e.cylinder) return cylinder_distance(e, p);
  if (e.triangles.empty()) return std::max(0.0, (p - e.centre).norm() - e.radius);
  double d = std::numeric_limits<double>::infinity();
  for (const Triangle& t : e.triangles) d = std::min(d, (closest_point_on_triangle(p, t[0], t[1], t[2]) - p).norm());
  if (!e.closed || d == 0.0) return d;
  const Vec3 far = p + Vec3(0.5377, 0.8313, 0.1407).normalized() * 100.0;
  int crossings = 0;
  for (const Triangle& t : e.triangles) crossings += segment_intersects_triangle(p, far, t[0], t[1], t[2]);
  return crossings % 2 ? 0.0 : d;
}

// The distance to a convex set along a segment is convex in the segment parameter: a ternary
// search finds its minimum (a ray grazing the cylinder within 1e-10 m counts as meeting it).
bool segment_meets_cylinder(const WorldElement& e, const Vec3& a, const Vec3& b) {
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 200; ++i) {
    const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (cylinder_distance(e, a + m1 * (b - a)) <= cylinder_distance(e, a + m2 * (b - a))) {
      hi = m2;
    } else {
      lo = m1;
    }
  }
  return cylinder_distance(e, a + 0.5 * (lo + hi) * (b - a)) <= 1e-10;
}

bool segment_meets_element(const WorldElement& e, const Vec3& a, const Vec3& b) {
  if (segment_ball_distance(a, b, e.centre) > e.radius) return false;
  if (e.cylinder) return segment_meets_cylinder(e, a, b);
  if (e.triangles.empty()) return true;
  for (const Triangle& t : e.triangles) {
    if (segment_intersects_triangle(a, b, t[0], t[1], t[2])) return true;
  }
  return false;
}

struct OracleScan {
  std::vector<ScanPoint> obstacles;
  std::size_t on_robot = 0, shadowed = 0, ambiguous = 0;
};

// Points outside the robot within 1e-9 of the padding are counted as ambiguous (rounding decides).
OracleScan oracle_filter(const std::vector<WorldElement>& elements, const std::vector<ScanPoint>& points,
                         const Vec3& sensor, double padding) {
  std::vector<bool> holds_sensor(elements.size());
  for (std::size_t i = 0; i < elements.size(); ++i) {
    for (std::size_t j = 0; j < elements.size(); ++j) {
      const bool same_link = elements[j].link == elements[i].link;
      if (same_link && element_distance(elements[j], sensor) <= padding) holds_sensor[i] = true;
    }
  }
  OracleScan out;
  for (const ScanPoint& point : points) {
    const Vec3 p = point.cast<double>();
    if (!p.allFinite()) {
      out.obstacles.push_back(point);
      continue;
    }
    double nearest = std::numeric_limits<double>::infinity();
    for (const WorldElement& e : elements) {
      if ((p - e.centre).norm() - e.radius <= padding + 1e-6) nearest = std::min(nearest, element_distance(e, p));
    }
    out.ambiguous += nearest > 0.0 && std::abs(nearest - padding) < 1e-9;  // inside is never ambiguous
    if (nearest <= padding) {
      ++out.on_robot;
      continue;
    }
    bool shadow = false;
    for (std::size_t i = 0; i < elements.size() && !shadow; ++i) {
      shadow = !holds_sensor[i] && segment_meets_element(elements[i], sensor, p);
    }
    if (shadow) {
      ++out.shadowed;
    } else {
      out.obstacles.push_back(point);
    }
  }
  return out;
}

std::vector<double> named_state(const RobotModel& model, const std::map<std::string, double>& values) {
  std::vector<double> state(model.variable_count(), 0.0);
  for (std::size_t i = 0; i < state.size(); ++i) {
    if (const auto it = values.find(model.variable_names()[i]); it != values.end()) state[i] = it->second;
  }
  return state;
}

const std::map<std::string, double> kPandaReady = {{"panda_joint2", -0.785}, {"panda_joint4", -2.356},
                                                   {"panda_joint6", 1.571}, {"panda_joint7", 0.785},
                                                   {"panda_finger_joint1", 0.03}};

// A depth camera at `sensor` looking at `target`: each ray ends on the robot, the floor (z = 0) or a
// wall (x = -0.7), with range noise; plus points scattered around the robot and some NaN points.
std::vector<ScanPoint> camera_scan(const std::vector<WorldElement>& elements, const Vec3& sensor, const Vec3& target,
                                   int columns, int rows, int scattered) {
  std::normal_distribution<double> noise(0.0, 0.004);
  const Vec3 forward = (target - sensor).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  std::vector<ScanPoint> scan;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < columns; ++c) {
      const double u = (c + 0.5) / columns - 0.5, v = (r + 0.5) / rows - 0.5;
      const Vec3 dir = (forward + 1.2 * u * right + 0.9 * v * up).normalized();
      double t = std::numeric_limits<double>::infinity();
      if (dir.z() < 0) t = -sensor.z() / dir.z();
      if (dir.x() < 0) t = std::min(t, (-0.7 - sensor.x()) / dir.x());
      for (const WorldElement& e : elements) {
        if (segment_ball_distance(sensor, sensor + dir * 5.0, e.centre) > e.radius) continue;
        if (e.cylinder) {
          // The ray's nearest point to the cylinder (ternary search: the distance is convex along
          // the ray); when that point is inside, the entry is bisected between it and the sensor.
          double a = 0.0, b = 5.0;
          for (int k = 0; k < 200; ++k) {
            const double m1 = a + (b - a) / 3, m2 = b - (b - a) / 3;
            if (cylinder_distance(e, sensor + dir * m1) <= cylinder_distance(e, sensor + dir * m2)) {
              b = m2;
            } else {
              a = m1;
            }
          }
          double lo = 0.0, hi = 0.5 * (a + b);
          if (cylinder_distance(e, sensor + dir * hi) == 0.0 && cylinder_distance(e, sensor) > 0.0) {
            for (int i = 0; i < 100; ++i) {
              const double mid = 0.5 * (lo + hi);
              (cylinder_distance(e, sensor + dir * mid) > 0.0 ? lo : hi) = mid;
            }
            t = std::min(t, hi);
          }
        }
        for (const Triangle& tri : e.triangles) {
          if (!segment_intersects_triangle(sensor, sensor + dir * t, tri[0], tri[1], tri[2])) continue;
          // The hit's distance along the ray: the triangle's plane.
          const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
          if (std::abs(n.dot(dir)) > 1e-12) t = std::min(t, n.dot(tri[0] - sensor) / n.dot(dir));
        }
      }
      if (std::isfinite(t)) scan.push_back((sensor + dir * (t + noise(rng()))).cast<float>());
    }
  }
  std::uniform_real_distribution<float> x(-0.3f, 0.9f), y(-0.6f, 0.6f), z(0.0f, 1.2f);
  for (int i = 0; i < scattered; ++i) scan.emplace_back(x(rng()), y(rng()), z(rng()));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  scan.emplace_back(nan, 0.0f, 0.0f);
  scan.emplace_back(0.0f, std::numeric_limits<float>::infinity(), 0.0f);
  return scan;
}

struct Camera {
  Vec3 sensor, target;
  int hidden_link = -1;  // a link the camera cannot see (it sits in it)
};

// The filter's answer, checked point by point against the oracle's.
FilteredScan expect_filter_matches_oracle(const CollisionChecker& checker, const std::vector<double>& state,
                                          const Camera& camera, double padding, int scattered = 4000) {
  SCOPED_TRACE("padding " + std::to_string(padding));
  std::vector<WorldElement> elements = world_elements(checker.model(), state), visible;
  for (const WorldElement& e : elements) {
    if (e.link != camera.hidden_link) visible.push_back(e);
  }
  const auto scan = camera_scan(visible, camera.sensor, camera.target, 100, 75, scattered);
  const ScanPoint sensor = camera.sensor.cast<float>();
  const FilteredScan got = checker.filter_scan(state.data(), scan, sensor, padding);
  const OracleScan want = oracle_filter(elements, scan, sensor.cast<double>(), padding);
  EXPECT_EQ(want.ambiguous, 0u);
  EXPECT_EQ(got.on_robot, want.on_robot);
  EXPECT_EQ(got.shadowed, want.shadowed);
  EXPECT_EQ(got.obstacles.size(), want.obstacles.size());
  std::size_t first_difference = 0;
  while (first_difference < std::min(got.obstacles.size(), want.obstacles.size()) &&
         (got.obstacles[first_difference] == want.obstacles[first_difference] ||
          !got.obstacles[first_difference].allFinite())) {
    ++first_difference;
  }
  EXPECT_EQ(first_difference, want.obstacles.size()) << "the obstacle lists differ from here";
  EXPECT_EQ(got.on_robot + got.shadowed + got.obstacles.size(), scan.size());
  EXPECT_LE(got.clear_only.size(), got.on_robot + got.shadowed);
  return got;
}

// panda's meshes; panda_capsules' spheres and cylinders (exact primitives).
TEST(SelfFilter, AgainstBruteForce) {
  BVH_REQUIRE_ROBOTS();
  struct Case {
    std::string robot;
    Camera camera;
    std::vector<double> paddings;
  };
  const std::vector<Case> cases = {{"panda", {{1.3, 0.6, 0.9}, {0.3, 0.0, 0.4}}, {0.0, 0.02, 0.05}},
                                   {"panda_capsules", {{1.2, -0.5, 1.0}, {0.3, 0.0, 0.4}}, {0.02}}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.robot);
    const CollisionChecker checker = test::load_checker(c.robot);
    const auto state = named_state(checker.model(), kPandaReady);
    for (const double padding : c.paddings) {
      const FilteredScan got = expect_filter_matches_oracle(checker, state, c.camera, padding);
      // Not a trivial agreement: every class is well populated (with no padding, "on the robot"
      // means inside a closed link).
      EXPECT_GT(got.on_robot, padding > 0 ? 500u : 100u);
      EXPECT_GT(got.shadowed, 100u);
      EXPECT_GT(got.obstacles.size(), 2000u);
    }
  }
}

// A camera on the hand, its origin on the hand's mesh: the hand casts no shadow (else the camera
// would see nothing), the fingers below it still do.
TEST(SelfFilter, SensorInsideItsMount) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const auto state = named_state(checker.model(), kPandaReady);
  const int hand = checker.model().link_index("panda_hand");
  Vec3 sensor = Vec3::Zero();
  for (const WorldElement& e : world_elements(checker.model(), state)) {
    if (e.link == hand) sensor = e.triangles.front()[0];
  }
  const FilteredScan got =
      expect_filter_matches_oracle(checker, state, {sensor, sensor - Vec3(0.1, 0.0, 1.0), hand}, 0.02, 0);
  EXPECT_GT(got.obstacles.size(), 5000u);
  EXPECT_GT(got.on_robot + got.shadowed, 50u);
}

// Brute force: the distance from p to the robot.
double robot_distance(const std::vector<WorldElement>& elements, const Vec3& p, double upper_bound) {
  double d = std::numeric_limits<double>::infinity();
  for (const WorldElement& e : elements) {
    if ((p - e.centre).norm() - e.radius <= upper_bound) d = std::min(d, element_distance(e, p));
  }
  return d;
}

// The test: a depth camera's scan of the robot standing on the floor, filtered and inserted,
// leaves no occupied voxel on the robot (no occupied cube meets a link); unfiltered it leaves many.
// The floor stays, and stale voxels in front of the robot are cleared by the rays to the robot.
TEST(SelfFilter, ScanOfTheRobotLeavesNoVoxelOnIt) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const auto state = named_state(checker.model(), kPandaReady);
  const std::vector<WorldElement> elements = world_elements(checker.model(), state);
  const Vec3 sensor(1.3, 0.6, 0.9);
  const auto scan = camera_scan(elements, sensor, Vec3(0.3, 0.0, 0.4), 160, 120, 0);
  const double padding = 0.02, resolution = 0.01;  // padding > the voxel's diagonal: no cube reaches a link
  const FilteredScan filtered = checker.filter_scan(state.data(), scan, sensor.cast<float>(), padding);
  ASSERT_GT(filtered.clear_only.size(), 1000u);
  Octree raw(resolution), clean(resolution);
  insert_scan(raw, scan, sensor.cast<float>());
  // Stale obstacles in front of the robot, half way along rays that end on it.
  std::vector<ScanPoint> stale;
  for (std::size_t i = 0; i < filtered.clear_only.size(); i += 40) {
    stale.push_back((0.5f * (sensor.cast<float>() + filtered.clear_only[i])).eval());
  }
  insert_points(clean, stale);
  for (int i = 0; i < 3; ++i) insert_scan(clean, filtered.obstacles, filtered.clear_only, sensor.cast<float>());
  auto count = [&](const Octree& tree, auto&& keep) {
    int n = 0;
    for (const Octree::Leaf& l : tree.leaves()) {
      const double size = tree.cube_size(l.depth);
      const Vec3 centre = tree.cube_min(l.key) + Vec3::Constant(size / 2);
      n += tree.occupied(l.log_odds) && keep(centre, size);
    }
    return n;
  };
  // A cube meets the robot if its centre is within half its side of it; misses it if farther than half its diagonal.
  const int raw_on_robot =
      count(raw, [&](const Vec3& c, double size) { return robot_distance(elements, c, size / 2) <= size / 2; });
  const int clean_near_robot = count(clean, [&](const Vec3& c, double size) {
    return robot_distance(elements, c, size) <= size * std::sqrt(3.0) / 2;
  });
  EXPECT_GT(raw_on_robot, 1000);
  EXPECT_EQ(clean_near_robot, 0);
  auto on_floor = [](const Vec3& c, double) { return c.z() < 0.01; };
  EXPECT_GT(count(clean, on_floor), 0.8 * count(raw, on_floor));
  int stale_left = 0;
  for (const ScanPoint& p : stale) {
    const auto key = clean.grid().key(Vec3(p.cast<double>()));
    const auto found = clean.find(*key);
    stale_left += found && clean.occupied(found->log_odds);
  }
  EXPECT_EQ(stale_left, 0) << "of " << stale.size() << " stale voxels in front of the robot";
}

TEST(SelfFilter, BadInput) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const auto state = named_state(checker.model(), kPandaReady);
  const ScanPoint sensor(1.0f, 0.0f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(checker.filter_scan(state.data(), {}, sensor, 0.02).obstacles.empty());
  EXPECT_THROW(checker.filter_scan(state.data(), {}, sensor, -0.01), std::invalid_argument);
  EXPECT_THROW(checker.filter_scan(state.data(), {}, sensor, std::nan("")), std::invalid_argument);
  EXPECT_THROW(checker.filter_scan(state.data(), {}, ScanPoint(nan, 0, 0), 0.02), std::invalid_argument);
  // Invalid points and a point at the sensor pass through for insert_scan to count; nothing lost.
  const std::vector<ScanPoint> odd = {ScanPoint(nan, 0, 0), sensor, ScanPoint(1e9f, -1e9f, 0),
                                      ScanPoint(0.3f, 0, 0.5f)};
  const FilteredScan out = checker.filter_scan(state.data(), odd, sensor, 0.02);
  EXPECT_EQ(out.obstacles.size() + out.on_robot + out.shadowed, odd.size());
  Octree tree(0.05);
  const ScanStats stats = insert_scan(tree, out.obstacles, out.clear_only, sensor);
  EXPECT_EQ(stats.skipped_invalid, 1u);
  EXPECT_EQ(stats.skipped_outside, 1u);
}

}  // namespace
}  // namespace bvh_collision
