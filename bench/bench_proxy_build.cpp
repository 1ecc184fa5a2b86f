// The proxy build benchmark (make bench, table proxy_build, section 1 of the report): what the link
// proxies cost to build at a first start (no cache), per robot and level, on one core: panda,
// ur5e, pr2, a generated two-arm robot and a 30 cm attached box at 5, 10 and 20 mm.
// Usage: bench_proxy_build [OUTPUT_DIR] [--quick]   (quick: 20 mm, panda, the two-arm robot, the box;
// BENCH_PROXY_BUILD_ROBOTS keeps some robots' rows, below)
#include <cmath>
#include <cstdlib>
#include <string>

#include "bench_util.h"
#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/narrowphase/link_proxy.h"
#include "bvh_collision/narrowphase/link_proxy_cache.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace bench {
namespace {

// A closed rounded box of the given half extents (a superellipsoid on a latitude-longitude grid,
// its corners rounded by the exponent): 2 * segments * (rings - 1) triangles, a torso-like mesh.
TriangleMesh rounded_box(const Vec3& half, int rings, int segments) {
  auto squash = [](double c) { return std::copysign(std::pow(std::abs(c), 0.4), c); };
  auto point = [&](double theta, double phi) {
    const Vec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta));
    return Vec3(half.x() * squash(d.x()), half.y() * squash(d.y()), half.z() * squash(d.z()));
  };
  TriangleMesh m;
  m.vertices.push_back(point(0.0, 0.0));
  for (int r = 1; r < rings; ++r) {
    for (int k = 0; k < segments; ++k) m.vertices.push_back(point(M_PI * r / rings, 2.0 * M_PI * k / segments));
  }
  m.vertices.push_back(point(M_PI, 0.0));
  const int south = static_cast<int>(m.vertices.size()) - 1;
  auto at = [&](int r, int k) { return 1 + (r - 1) * segments + (k % segments); };
  for (int k = 0; k < segments; ++k) {
    m.triangles.push_back({0, at(1, k), at(1, k + 1)});
    m.triangles.push_back({south, at(rings - 1, k + 1), at(rings - 1, k)});
  }
  for (int r = 1; r < rings - 1; ++r) {
    for (int k = 0; k < segments; ++k) {
      m.triangles.push_back({at(r, k), at(r + 1, k), at(r + 1, k + 1)});
      m.triangles.push_back({at(r, k), at(r + 1, k + 1), at(r, k + 1)});
    }
  }
  return m;
}

// A shared robot's checker, with no accelerator: only its links' shapes are wanted.
CollisionChecker robot_checker(const std::string& name) {
  const std::string dir = test::robots_dir() + "/" + name;
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  CheckerOptions options;
  options.pair_clearance_cells = 0;
  const std::size_t links = model.links().size();
  return CollisionChecker(std::move(model), AllowedCollisionMatrix(links), options);
}

// The shapes of every link (one entry per link with geometry).
std::vector<std::vector<BodyShape>> link_shapes(const CollisionChecker& checker) {
  std::vector<std::vector<BodyShape>> out;
  const RobotCollisionModel& m = checker.collision_model();
  for (std::size_t l = 0; l < m.shapes().size(); ++l) {
    if (!m.shapes()[l].empty()) out.push_back(m.placed_shapes(static_cast<int>(l)));
  }
  return out;
}

// Every link's proxy at every default level (5, 10, 20 mm: the node's), built as at a first start
// (no cache) on this thread: seconds (median of runs), leaves, the proxies' memory and the work.
void proxy_build_rows(const std::string& robot, const std::vector<std::vector<BodyShape>>& links, bool quick, Table& table) {
  std::size_t triangles = 0;
  for (const auto& link : links) {
    for (const BodyShape& s : link) triangles += s.shape.mesh ? s.shape.mesh->triangles().size() : 0;
  }
  for (const double level : quick ? std::vector<double>{0.02} : std::vector<double>{0.005, 0.01, 0.02}) {
    std::vector<double> seconds;
    ProxyBuildStats stats;
    std::size_t bytes = 0;
    for (int run = 0; run < (quick ? 1 : 3); ++run) {
      stats = {}, bytes = 0;
      // As the node builds a level (RobotAccelerators): a link alike an earlier one (first_alike)
      // takes a copy of its proxy; its leaves count, its work does not.
      seconds.push_back(1e-6 * bench::time_us([&] {
        const std::vector<std::size_t> alike = first_alike(links);
        std::vector<LinkProxy> built(links.size());
        for (std::size_t l = 0; l < links.size(); ++l) {
          built[l] = alike[l] == l ? LinkProxy::build(links[l], level, &stats) : built[alike[l]];
          if (alike[l] != l) stats.leaves += built[l].leaf_count();
          bytes += built[l].memory_bytes();
        }
      }));
    }
    const Spread time = bench::spread(seconds);
    table.row({robot, level * 1000, static_cast<double>(links.size()), static_cast<double>(triangles),
               static_cast<double>(stats.leaves), time.median, time.low, time.high, bytes / 1e6,
               static_cast<double>(stats.cubes + stats.surface_pieces),
               static_cast<double>(stats.distance_queries + stats.inside_queries),
               static_cast<double>(stats.sphere_tests) / static_cast<double>(std::max<std::size_t>(1, stats.cubes + stats.surface_pieces))});
  }
}

// BENCH_PROXY_BUILD_ROBOTS (a comma-separated list of the rows' robots, e.g. "pr2,two-arm") keeps
// those rows only: a profile of one robot's build.
bool wanted(const std::string& robot) {
  const char* only = std::getenv("BENCH_PROXY_BUILD_ROBOTS");
  if (only == nullptr || *only == '\0') return true;
  const std::string list = std::string(",") + only + ",";
  const std::string first = robot.substr(0, robot.find(' '));
  return list.find("," + robot + ",") != std::string::npos || list.find("," + first + ",") != std::string::npos;
}

void proxy_build_section(const std::string& dir, bool quick) {
  Table table("proxy_build", "Link proxies built at a first start (no cache), one core: every link of the robot, per level",
              {"robot", "level mm", "links", "triangles", "leaves", "seconds", "low", "high", "MB", "cubes and pieces",
               "surface queries", "sphere tests per cube or piece"});
  for (const char* name : quick ? std::vector<const char*>{"panda"} : std::vector<const char*>{"panda", "ur5e", "pr2"}) {
    if (!wanted(name)) continue;
    const CollisionChecker checker = robot_checker(name);
    proxy_build_rows(name, link_shapes(checker), quick, table);
  }
  // A two-arm robot: a torso mesh like a real one's (0.40 x 0.40 x 0.65 m) and two panda arms.
  const CollisionChecker panda = robot_checker("panda");
  const Bvh<Obb> torso = Bvh<Obb>::build(rounded_box(Vec3(0.20, 0.20, 0.325), 20, 19));
  std::vector<std::vector<BodyShape>> two_arms{{BodyShape{ShapeRef{&torso, nullptr, Primitive{}}, Transform()}}};
  for (int arm = 0; arm < 2; ++arm) {
    for (const auto& link : link_shapes(panda)) two_arms.push_back(link);
  }
  if (wanted("two-arm (generated)")) proxy_build_rows("two-arm (generated)", two_arms, quick, table);
  std::vector<BodyShape> box(1);
  box[0].shape.primitive = Primitive::box(Vec3(0.3, 0.3, 0.3));
  if (wanted("attached box 30 cm")) proxy_build_rows("attached box 30 cm", {box}, quick, table);
  table.note("What a first start pays for the levels the node builds (~proxy_levels 5, 10, 20 mm; later starts read "
             "them from ~proxy_cache in milliseconds). The bound of every sphere is proven as it is built "
             "(narrowphase/link_proxy.h); the work grows as n log n of the leaves (a cube or surface piece asks the "
             "spheres and triangles its parent kept, test_link_proxy bounds the counts). MB: the proxies as kept. "
             "A link whose shapes are an earlier link's, bit for bit (pr2's two arms and four casters, the two-arm robot's "
             "second arm), takes a copy of that proxy, as the node does (first_alike): its leaves and memory count, "
             "its build does not (the cube and query columns count the work done). The two-arm robot: a generated torso of " +
             std::to_string(torso.triangles().size()) + " triangles (0.40 x 0.40 x 0.65 m) and two panda arms.");
  table.write(dir);
}

}  // namespace
}  // namespace bench
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  std::cout << "# Link proxies built at a first start\n# Machine: " << bench::machine_description() << "\n";
  bench::proxy_build_section(bench::output_dir(argc, argv), bench::quick_mode(argc, argv));
  return 0;
}
