// Link proxies kept on disk by content, and links alike sharing one proxy
// (narrowphase/link_proxy_cache.h): part of test_link_proxy.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>

#include <unistd.h>

#include "bvh_collision/narrowphase/link_proxy.h"
#include "bvh_collision/narrowphase/link_proxy_cache.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

// Issue 33, point 3: proxies kept on disk by content. The first build stores every link's proxy,
// a second reads every one back (the same spheres, bit for bit, and the same answers); a file that
// does not check out (a flipped byte, cut short, another link's file under this key) is rebuilt
// and replaced; another level or changed geometry has another key.
TEST(LinkProxyCache, ASecondBuildReadsWhatTheFirstStored) {
  namespace fs = std::filesystem;
  const fs::path folder = fs::temp_directory_path() / ("bvh_proxy_cache_" + std::to_string(::getpid()));
  fs::remove_all(folder);
  CheckerOptions options;
  options.proxy_levels = {0.02};
  options.proxy_cache = folder.string();
  // The level answers every pair in both checkers: calibrated, each times which pairs it answers
  // when it is built, and on a busy host two builds chose differently (a state within the level's
  // 2 cm answered colliding by one, free by the other: a CI replica failed so).
  options.calibrate_proxies = false;
  const CollisionChecker first = test::demo_arm_checker(options);
  const ProxyLevel& built = first.accelerators().proxy_levels().front();
  std::size_t with_geometry = 0;
  for (const LinkProxy& p : built.links) with_geometry += !p.empty();
  ASSERT_GT(with_geometry, 0u);
  EXPECT_EQ(built.links_from_cache, 0u);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(folder)) {
    if (e.path().extension() == ".proxy") files.push_back(e.path());  // the robot's grids are there too
  }
  std::sort(files.begin(), files.end());
  EXPECT_LE(files.size(), with_geometry) << "one file a distinct link";
  ASSERT_FALSE(files.empty());

  const CollisionChecker second = test::demo_arm_checker(options);
  const ProxyLevel& read = second.accelerators().proxy_levels().front();
  EXPECT_EQ(read.links_from_cache, with_geometry);
  ASSERT_EQ(read.links.size(), built.links.size());
  for (std::size_t l = 0; l < built.links.size(); ++l) {
    const auto& a = built.links[l].spheres();
    const auto& b = read.links[l].spheres();
    ASSERT_EQ(a.size(), b.size()) << "link " << l;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].center, b[i].center);
      EXPECT_EQ(a[i].radius, b[i].radius);
      EXPECT_EQ(a[i].skip, b[i].skip);
    }
    EXPECT_EQ(built.links[l].hausdorff_bound(), read.links[l].hausdorff_bound());
    EXPECT_EQ(built.links[l].leaf_count(), read.links[l].leaf_count());
  }
  std::mt19937_64 rng(3);
  SelfCollisionRequest at_level;
  at_level.tolerance = 0.02;
  for (int i = 0; i < 200; ++i) {
    const std::vector<double> q = random_configuration(first.model(), rng);
    EXPECT_EQ(first.check_self(q.data(), at_level).collision, second.check_self(q.data(), at_level).collision);
  }

  // Files that do not check out are rebuilt, and replaced by good ones.
  const auto bytes = [](const fs::path& f) {
    std::ifstream in(f, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  };
  const auto put = [](const fs::path& f, const std::string& b) { std::ofstream(f, std::ios::binary | std::ios::trunc) << b; };
  const std::string good = bytes(files[0]);
  std::string flipped = good;
  flipped[flipped.size() / 2] ^= 0x10;
  const std::vector<std::string> bad = {flipped, good.substr(0, good.size() - 9), good.substr(0, 20), "",
                                         files.size() > 1 ? bytes(files[1]) : std::string("x")};
  for (const std::string& b : bad) {
    put(files[0], b);
    const CollisionChecker again = test::demo_arm_checker(options);
    EXPECT_LT(again.accelerators().proxy_levels().front().links_from_cache, with_geometry);
    EXPECT_EQ(bytes(files[0]), good) << "a file that did not check out is replaced by the one built";
  }
  // Another level: other keys, nothing read.
  options.proxy_levels = {0.01};
  EXPECT_EQ(test::demo_arm_checker(options).accelerators().proxy_levels().front().links_from_cache, 0u);
  fs::remove_all(folder);
}

// A link whose shapes are an earlier link's, bit for bit, takes a copy of that link's proxy
// instead of a build (pr2's casters and its two arms): first_alike against brute force over every
// pair of links, the copies against builds of their own, and every number that tells shapes
// apart (a triangle's coordinate, an origin, a primitive's size, -0.0 against 0.0) telling them apart.
bool alike_by_brute_force(const std::vector<BodyShape>& a, const std::vector<BodyShape>& b) {
  if (a.size() != b.size()) return false;
  std::vector<double> x, y;
  const auto numbers = [](const std::vector<BodyShape>& shapes, std::vector<double>& out) {
    for (const BodyShape& s : shapes) {
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) out.push_back(s.origin.R(r, c));
      }
      for (int k = 0; k < 3; ++k) out.push_back(s.origin.t[k]);
      out.push_back(s.shape.mesh != nullptr ? 1.0 : 0.0);
      if (s.shape.mesh == nullptr) {
        out.push_back(static_cast<double>(s.shape.primitive.kind));
        for (int k = 0; k < 3; ++k) out.push_back(s.shape.primitive.half[k]);
        out.push_back(s.shape.primitive.radius), out.push_back(s.shape.primitive.half_length);
        continue;
      }
      out.push_back(s.shape.mesh->closed() ? 1.0 : 0.0), out.push_back(static_cast<double>(s.shape.mesh->triangles().size()));
      for (const Triangle& t : s.shape.mesh->triangles()) {
        for (int v = 0; v < 3; ++v) {
          for (int k = 0; k < 3; ++k) out.push_back(t[v][k]);
        }
      }
    }
  };
  numbers(a, x), numbers(b, y);
  return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(double)) == 0;
}

TEST(LinkProxyCache, LinksAlikeTakeOneProxy) {
  CheckerOptions options;
  options.proxy_levels = {0.02};
  options.calibrate_proxies = false;
  const CollisionChecker pr2 = test::load_checker("pr2", options);
  const RobotCollisionModel& m = pr2.collision_model();
  std::vector<std::vector<BodyShape>> placed(m.shapes().size());
  for (std::size_t l = 0; l < placed.size(); ++l) {
    if (!m.shapes()[l].empty()) placed[l] = m.placed_shapes(static_cast<int>(l));
  }
  const std::vector<std::size_t> alike = first_alike(placed);
  std::size_t shared = 0;
  for (std::size_t l = 0; l < placed.size(); ++l) {
    std::size_t first = l;
    for (std::size_t k = 0; k < l && first == l && !placed[l].empty(); ++k) {
      if (alike_by_brute_force(placed[k], placed[l])) first = k;
    }
    ASSERT_EQ(alike[l], first) << "link " << l;
    shared += first != l;
  }
  EXPECT_GE(shared, 8u) << "pr2's casters and its arms' links";
  const ProxyLevel& level = pr2.accelerators().proxy_levels().front();
  EXPECT_EQ(level.links_shared, shared);
  for (std::size_t l = 0; l < placed.size(); ++l) {
    if (alike[l] == l) continue;
    const LinkProxy own = LinkProxy::build(placed[l], 0.02);
    const auto& a = own.spheres();
    const auto& b = level.links[l].spheres();
    ASSERT_EQ(a.size(), b.size()) << "link " << l;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].center, b[i].center) << "link " << l;
      ASSERT_EQ(a[i].radius, b[i].radius) << "link " << l;
      ASSERT_EQ(a[i].skip, b[i].skip) << "link " << l;
    }
    EXPECT_EQ(own.hausdorff_bound(), level.links[l].hausdorff_bound());
  }

  // Numbers that tell shapes apart: a mesh built again from the same triangles is alike, one with
  // a coordinate moved by an ulp is not; nor an origin, a primitive, or a zero's sign.
  std::mt19937_64 rng(5);
  TriangleMesh mesh = test::bumpy_sphere(rng, 0.05, 8, 12, 0.002);
  const Bvh<Obb> one = Bvh<Obb>::build(mesh), again = Bvh<Obb>::build(mesh);
  mesh.vertices[3].x() = std::nextafter(mesh.vertices[3].x(), 1.0);
  const Bvh<Obb> moved = Bvh<Obb>::build(mesh);
  const auto link = [](const Bvh<Obb>* bvh, const Transform& origin) {
    BodyShape s;
    s.shape.mesh = bvh;
    s.origin = origin;
    return std::vector<BodyShape>{s};
  };
  Transform shifted;
  shifted.t.x() = std::nextafter(0.0, 1.0);
  Transform negative_zero;
  negative_zero.t.x() = -0.0;
  std::vector<BodyShape> box(1), wider(1);
  box[0].shape.primitive = wider[0].shape.primitive = Primitive::box(Vec3(0.1, 0.2, 0.3));
  wider[0].shape.primitive.half.y() = std::nextafter(wider[0].shape.primitive.half.y(), 1.0);
  const std::vector<std::vector<BodyShape>> links = {link(&one, Transform()), link(&again, Transform()), link(&moved, Transform()),
                                                     link(&one, shifted),     link(&one, negative_zero), box,
                                                     wider,                   box,                       {}};
  EXPECT_EQ(first_alike(links), (std::vector<std::size_t>{0, 0, 2, 3, 4, 5, 6, 5, 8}));
  for (std::size_t a = 0; a < links.size(); ++a) {
    for (std::size_t b = 0; b < links.size(); ++b) EXPECT_EQ(same_shapes(links[a], links[b]), alike_by_brute_force(links[a], links[b])) << a << " " << b;
  }
}

TEST(LinkProxyCache, KeysTellEveryNumberOfTheGeometryApart) {
  const CollisionChecker checker = test::demo_arm_checker();
  const RobotCollisionModel& m = checker.collision_model();
  std::size_t link = 0;
  while (m.shapes()[link].empty()) ++link;
  std::vector<BodyShape> shapes = m.placed_shapes(static_cast<int>(link));
  const std::uint64_t key = link_proxy_key(shapes, 0.01);
  EXPECT_EQ(link_proxy_key(shapes, 0.01), key);
  EXPECT_NE(link_proxy_key(shapes, 0.0100000001), key);
  shapes[0].origin.t.x() += 1e-12;
  EXPECT_NE(link_proxy_key(shapes, 0.01), key);
  shapes = m.placed_shapes(static_cast<int>(link));
  if (shapes[0].shape.mesh == nullptr) {
    shapes[0].shape.primitive.radius *= 1.000001;
    shapes[0].shape.primitive.half *= 1.000001;
    shapes[0].shape.primitive.half_length *= 1.000001;
    EXPECT_NE(link_proxy_key(shapes, 0.01), key);
  }
}

}  // namespace
}  // namespace bvh_collision
