// Known objects are not voxels (world/object_filter.h): the filter against brute force (each
// object's distance and ray entry written out here by hand: a box's slabs, a sphere's quadratic,
// a cylinder's disc times interval, a mesh's triangles), the carried objects' own padding, and its
// purpose: a box moved across a table under a camera leaves no voxel behind. One binary with
// test_self_filter.cpp.
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

namespace object_filter {

constexpr double kInf = std::numeric_limits<double>::infinity();

// An object as the oracle knows it: what it is, where, and its triangles when it is a mesh.
struct Known {
  ObjectShape shape;
  Transform pose;
  std::vector<Triangle> triangles;  // world frame (mesh objects)
};

Transform pose_of(const Vec3& t, double yaw, double pitch) {
  Transform x;
  x.R = (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY())).toRotationMatrix();
  x.t = t;
  return x;
}

// An octahedron of half-diagonal r (a closed mesh).
TriangleMesh octahedron(double r) {
  TriangleMesh m;
  m.vertices = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

double distance_to(const Known& k, const Vec3& p) {
  const Vec3 q = k.pose.inverse() * p;
  switch (k.shape.kind) {
    case ObjectShape::Kind::kBox:
      return (q.cwiseAbs() - 0.5 * k.shape.size).cwiseMax(0.0).norm();
    case ObjectShape::Kind::kSphere:
      return std::max(0.0, q.norm() - k.shape.radius);
    case ObjectShape::Kind::kCylinder:
      return std::hypot(std::max(0.0, std::hypot(q.x(), q.y()) - k.shape.radius),
                        std::max(0.0, std::abs(q.z()) - 0.5 * k.shape.length));
    default: {
      double d = kInf;
      for (const Triangle& t : k.triangles) d = std::min(d, (closest_point_on_triangle(p, t[0], t[1], t[2]) - p).norm());
      const Vec3 far = p + Vec3(0.5377, 0.8313, 0.1407).normalized() * 100.0;
      int crossings = 0;
      for (const Triangle& t : k.triangles) crossings += segment_intersects_triangle(p, far, t[0], t[1], t[2]);
      return crossings % 2 ? 0.0 : d;
    }
  }
}

// Where origin + s * unit first meets the object for s in [0, length] (infinity: never).
double entry_of(const Known& k, const Vec3& origin, const Vec3& unit, double length) {
  const Vec3 o = k.pose.inverse() * origin, u = k.pose.R.transpose() * unit;
  if (k.shape.kind == ObjectShape::Kind::kBox) {  // slabs
    double lo = 0.0, hi = length;
    for (int a = 0; a < 3; ++a) {
      const double h = 0.5 * k.shape.size[a];
      if (std::abs(u[a]) < 1e-15) {
        if (std::abs(o[a]) > h) return kInf;
        continue;
      }
      const double t1 = (-h - o[a]) / u[a], t2 = (h - o[a]) / u[a];
      lo = std::max(lo, std::min(t1, t2));
      hi = std::min(hi, std::max(t1, t2));
    }
    return lo <= hi ? lo : kInf;
  }
  if (k.shape.kind == ObjectShape::Kind::kSphere) {  // |o + s u|^2 = r^2
    const double b = o.dot(u), c = o.squaredNorm() - k.shape.radius * k.shape.radius;
    if (c <= 0.0) return 0.0;
    const double disc = b * b - c;
    if (disc < 0.0) return kInf;
    const double s = -b - std::sqrt(disc);
    return s >= 0.0 && s <= length ? s : kInf;
  }
  if (k.shape.kind == ObjectShape::Kind::kCylinder) {
    // The interval where x^2 + y^2 <= r^2 (a quadratic in s) meets the slab |z| <= length / 2.
    double lo = 0.0, hi = length;
    const double a = u.x() * u.x() + u.y() * u.y(), b = o.x() * u.x() + o.y() * u.y();
    const double c = o.x() * o.x() + o.y() * o.y() - k.shape.radius * k.shape.radius;
    if (a < 1e-15) {
      if (c > 0.0) return kInf;
    } else {
      const double disc = b * b - a * c;
      if (disc < 0.0) return kInf;
      lo = std::max(lo, (-b - std::sqrt(disc)) / a);
      hi = std::min(hi, (-b + std::sqrt(disc)) / a);
    }
    const double h = 0.5 * k.shape.length;
    if (std::abs(u.z()) < 1e-15) {
      if (std::abs(o.z()) > h) return kInf;
    } else {
      const double t1 = (-h - o.z()) / u.z(), t2 = (h - o.z()) / u.z();
      lo = std::max(lo, std::min(t1, t2));
      hi = std::min(hi, std::max(t1, t2));
    }
    return lo <= hi ? lo : kInf;
  }
  double first = kInf;
  for (const Triangle& t : k.triangles) {
    if (!segment_intersects_triangle(origin, origin + unit * length, t[0], t[1], t[2])) continue;
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (std::abs(n.dot(unit)) > 1e-12) first = std::min(first, n.dot(t[0] - origin) / n.dot(unit));
  }
  return first;
}

std::vector<Known> known_objects() {
  std::vector<Known> out = {{ObjectShape::box({0.3, 0.2, 0.15}), pose_of({0.6, 0.1, 0.3}, 0.4, 0.2), {}},
                            {ObjectShape::sphere(0.12), pose_of({0.4, -0.35, 0.25}, 0.0, 0.0), {}},
                            {ObjectShape::cylinder(0.06, 0.35), pose_of({0.9, -0.1, 0.35}, 0.3, 1.1), {}},
                            {ObjectShape::triangles(octahedron(0.15)), pose_of({0.3, 0.45, 0.35}, 0.7, 0.3), {}}};
  const TriangleMesh& mesh = *out.back().shape.mesh;
  for (const auto& f : mesh.triangles) {
    out.back().triangles.push_back({out.back().pose * mesh.vertices[f[0]], out.back().pose * mesh.vertices[f[1]],
                                    out.back().pose * mesh.vertices[f[2]]});
  }
  return out;
}

std::vector<CollisionObject> collision_objects(const std::vector<Known>& known) {
  std::vector<CollisionObject> out;
  for (std::size_t i = 0; i < known.size(); ++i) {
    out.push_back(make_collision_object("object" + std::to_string(i), known[i].shape, known[i].pose));
  }
  return out;
}

// A camera's rays ending on the objects or the floor (z = 0), and points scattered around the
// objects (many within a few centimetres of a surface), and two invalid ones.
std::vector<ScanPoint> scan_of(const std::vector<Known>& known, const Vec3& sensor, std::mt19937_64& rng) {
  std::vector<ScanPoint> scan;
  const Vec3 forward = (Vec3(0.6, 0.0, 0.2) - sensor).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  for (int r = 0; r < 90; ++r) {
    for (int c = 0; c < 120; ++c) {
      const Vec3 dir = (forward + 1.2 * ((c + 0.5) / 120 - 0.5) * right + 0.9 * ((r + 0.5) / 90 - 0.5) * up).normalized();
      double t = dir.z() < 0.0 ? -sensor.z() / dir.z() : 5.0;
      for (const Known& k : known) t = std::min(t, entry_of(k, sensor, dir, t));
      scan.push_back((sensor + dir * (t + 0.001)).cast<float>());  // 1 mm in: no point sits on a surface
    }
  }
  std::uniform_real_distribution<double> x(0.1, 1.1), y(-0.6, 0.7), z(0.05, 0.65);
  for (int i = 0; i < 6000; ++i) scan.push_back(Vec3(x(rng), y(rng), z(rng)).cast<float>());
  scan.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f);
  scan.push_back(sensor.cast<float>());  // a point at the sensor: no ray
  return scan;
}

TEST(ObjectFilter, AgainstBruteForce) {
  std::mt19937_64 rng(5);
  const std::vector<Known> known = known_objects();
  const std::vector<CollisionObject> objects = collision_objects(known);
  const Vec3 sensor(1.6, 0.9, 1.1);
  const std::vector<ScanPoint> scan = scan_of(known, sensor, rng);
  for (const double padding : {0.0, 0.02, 0.05}) {
    SCOPED_TRACE("padding " + std::to_string(padding));
    FilteredScan got;
    got.obstacles = scan;
    got.clear_only = {ScanPoint(0.1f, 0.2f, 0.3f)};  // a self-filter ray already there stays first
    filter_objects(ObjectList(objects), sensor.cast<float>(), padding, got);
    std::vector<ScanPoint> kept, ends;
    std::size_t on = 0, ambiguous = 0;
    for (const ScanPoint& point : scan) {
      const Vec3 p = point.cast<double>();
      const double length = (p - sensor).norm();
      double nearest = kInf;
      for (const Known& k : known) nearest = std::min(nearest, distance_to(k, p));
      ambiguous += p.allFinite() && nearest > 0.0 && std::abs(nearest - padding) < 1e-7;
      if (!p.allFinite() || length == 0.0 || nearest > padding) {
        kept.push_back(point);
        continue;
      }
      ++on;
      const Vec3 unit = (p - sensor) / length;
      double first = length;
      for (const Known& k : known) first = std::min(first, entry_of(k, sensor, unit, first));
      if (first - padding > 0.0) ends.push_back((sensor + unit * (first - padding)).cast<float>());
    }
    EXPECT_EQ(ambiguous, 0u);
    EXPECT_GT(on, 500u) << "the objects are seen";
    EXPECT_GT(kept.size(), 5000u) << "and so is the floor";
    EXPECT_EQ(got.on_objects, on);
    ASSERT_EQ(got.obstacles.size(), kept.size());
    std::size_t differ = 0;
    for (std::size_t i = 0; i < kept.size(); ++i) differ += !(got.obstacles[i] == kept[i]) && kept[i].allFinite();
    EXPECT_EQ(differ, 0u) << "kept points, in scan order";
    ASSERT_EQ(got.clear_only.size(), ends.size() + 1);
    EXPECT_EQ(got.clear_only.front(), ScanPoint(0.1f, 0.2f, 0.3f));
    double worst = 0.0;
    for (std::size_t i = 0; i < ends.size(); ++i) worst = std::max(worst, double((got.clear_only[i + 1] - ends[i]).norm()));
    EXPECT_LT(worst, 1e-5) << "each ray cut `padding` before the first object it meets";
  }
}

TEST(ObjectFilter, BadInputAndNoObjects) {
  FilteredScan scan;
  scan.obstacles = {ScanPoint(1, 0, 0)};
  filter_objects({}, ScanPoint(0, 0, 0), 0.02, scan);
  EXPECT_EQ(scan.obstacles.size(), 1u);
  const std::vector<CollisionObject> objects = {make_collision_object("box", ObjectShape::box({1, 1, 1}), Transform::Identity())};
  EXPECT_THROW(filter_objects(ObjectList(objects), ScanPoint(0, 0, 0), -0.01, scan), std::invalid_argument);
  EXPECT_THROW(filter_objects(ObjectList(objects), ScanPoint(0, 0, 0), std::nan(""), scan), std::invalid_argument);
  EXPECT_THROW(filter_objects(ObjectList(objects), ScanPoint(std::nanf(""), 0, 0), 0.0, scan), std::invalid_argument);
  EXPECT_EQ(scan.obstacles.size(), 1u) << "a refused call changes nothing";
  // The sensor inside an object: its points there are the object's; the object cuts no ray (a
  // camera in its housing would see nothing), so the ray clears up to the point.
  scan.obstacles = {ScanPoint(0.2f, 0, 0), ScanPoint(3, 0, 0)};
  filter_objects(ObjectList(objects), ScanPoint(0, 0, 0), 0.0, scan);
  EXPECT_EQ(scan.on_objects, 1u);
  EXPECT_EQ(scan.obstacles, std::vector<ScanPoint>{ScanPoint(3, 0, 0)});
  EXPECT_EQ(scan.clear_only, std::vector<ScanPoint>{ScanPoint(0.2f, 0, 0)});
}

// The scenario: a camera over a table sees a box that a planner moves across it, the
// scene updated before each scan. Filtered, no voxel is left anywhere the box has been; unfiltered,
// the box leaves a trail of them. The table stays.
TEST(ObjectFilter, BoxMovedAcrossATableLeavesNoVoxels) {
  const Vec3 sensor(0.5, 0.0, 1.5), box_size(0.12, 0.12, 0.12);
  const double table = 0.4, padding = 0.02;
  Octree filtered(0.02), unfiltered(0.02);
  for (int step = 0; step <= 20; ++step) {
    const Known box{ObjectShape::box(box_size), pose_of({0.3 + 0.02 * step, -0.2 + 0.02 * step, table + 0.06}, 0.1 * step, 0.0), {}};
    std::vector<ScanPoint> scan;
    for (double x = 0.0; x <= 1.0; x += 0.01) {
      for (double y = -0.5; y <= 0.5; y += 0.01) {
        const Vec3 dir = (Vec3(x, y, table) - sensor).normalized();
        const double t = std::min(entry_of(box, sensor, dir, 5.0), (table - sensor.z()) / dir.z());
        scan.push_back((sensor + dir * t).cast<float>());
      }
    }
    FilteredScan split;
    split.obstacles = scan;
    filter_objects(ObjectList(collision_objects({box})), sensor.cast<float>(), padding, split);
    EXPECT_GT(split.on_objects, 100u);
    insert_scan(filtered, split.obstacles, split.clear_only, sensor.cast<float>());
    insert_scan(unfiltered, scan, sensor.cast<float>());
  }
  auto count = [](const Octree& tree, auto&& where) {
    int n = 0;
    for (const Octree::Leaf& l : tree.leaves()) {
      const Vec3 centre = tree.cube_min(l.key) + Vec3::Constant(tree.cube_size(l.depth) / 2);
      n += tree.occupied(l.log_odds) && where(centre);
    }
    return n;
  };
  const auto above_table = [&](const Vec3& c) { return c.z() > table + 0.02; };
  const auto table_top = [&](const Vec3& c) { return c.z() < table + 0.02; };
  EXPECT_EQ(count(filtered, above_table), 0) << "voxels left where the box has been";
  EXPECT_GT(count(unfiltered, above_table), 20) << "without the filter the box leaves a trail";
  EXPECT_GT(count(filtered, table_top), 0.95 * count(unfiltered, table_top));
}

// Carried objects are links of a carrying checker: the self filter gives them their own padding.
TEST(ObjectFilter, CarriedObjectsTakeTheirOwnPadding) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker panda = test::load_checker("panda");
  AttachedBody body;
  body.id = "carried";
  body.link = "panda_hand";
  body.shapes.push_back(make_collision_object("carried", ObjectShape::box({0.05, 0.05, 0.05}), pose_of({0, 0, 0.3}, 0, 0)));
  const CollisionChecker carrying = panda.carrying({body}, {});
  // Ready: the hand points down over the table, the box 30 cm below it and clear of every link.
  std::vector<double> q(panda.model().variable_count(), 0.0);
  for (const auto& [joint, value] : std::map<std::string, double>{{"panda_joint2", -0.785}, {"panda_joint4", -2.356},
                                                                  {"panda_joint6", 1.571}, {"panda_joint7", 0.785}}) {
    const auto& names = panda.model().variable_names();
    q[std::find(names.begin(), names.end(), joint) - names.begin()] = value;
  }
  std::vector<Transform> poses;
  forward_kinematics(carrying.model(), q.data(), poses);
  const Transform box = poses[carrying.model().link_index("carried")] * body.shapes.front().pose;
  // Points 3 cm off the box's faces, seen from far above.
  std::vector<ScanPoint> points;
  for (int a = 0; a < 3; ++a) {
    for (const double s : {-1.0, 1.0}) points.push_back((box * Vec3(s * Vec3::Unit(a) * 0.055)).cast<float>());
  }
  const ScanPoint sensor = (box.t + Vec3(0, 0, 2)).cast<float>();
  EXPECT_EQ(carrying.filter_scan(q.data(), points, sensor, 0.01).on_robot, 0u);
  EXPECT_EQ(carrying.filter_scan(q.data(), points, sensor, 0.01, Transform::Identity(), 0.04).on_robot, points.size());
  EXPECT_EQ(carrying.filter_scan(q.data(), points, sensor, 0.04, Transform::Identity(), 0.01).on_robot, 0u)
      << "the robot's padding does not reach the carried box";
}

}  // namespace object_filter

}  // namespace
}  // namespace bvh_collision
