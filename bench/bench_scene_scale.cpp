// Scenes of many objects (table `scene_scale`): a MoveIt .scene of n boxes and spheres read and
// built as the CLI and load_scene build it, the same objects set one at a time as
// set_collision_object sets them, one state check among them, and the memory they take; beside
// FCL's DynamicAABBTree manager registering the same objects in the same run.
//
// Usage: bench_scene_scale OUTPUT_DIR [--quick]
#include <fcl/broadphase/broadphase_dynamic_AABB_tree.h>
#include <fcl/broadphase/default_broadphase_callbacks.h>
#include <fcl/narrowphase/collision.h>
#include <malloc.h>
#include <unistd.h>

#include <fstream>
#include <random>

#include "bench_util.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "checker_fixtures.h"
#include "fcl_oracle.h"

namespace bvh_collision::bench {
namespace {

// Bytes the heap holds now (what a structure built between two readings takes).
double heap_bytes() { return static_cast<double>(mallinfo2().uordblks); }

// n boxes and spheres of 2 to 20 cm at one density (one per 0.05 m^3, as a map converted to
// boxes holds them) around the robot's base, none within 0.6 m of its shoulder: the objects near
// a link are as many at every n.
SceneFile many_objects(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double side = std::cbrt(0.05 * static_cast<double>(n));
  std::uniform_real_distribution<double> at(-side / 2, side / 2), size(0.02, 0.2), turn(-M_PI, M_PI);
  SceneFile scene;
  scene.name = std::to_string(n) + " objects";
  for (std::size_t i = 0; i < n; ++i) {
    SceneObject o;
    o.id = "o" + std::to_string(i);
    o.pose.R = Eigen::AngleAxisd(turn(rng), Vec3::UnitZ()).toRotationMatrix();
    do {  // none within 0.6 m of the robot's shoulder: its states meet some objects, not all
      o.pose.t = Vec3(at(rng), at(rng), 0.5 + 0.5 * at(rng));
    } while ((o.pose.t - Vec3(0, 0, 0.5)).norm() < 0.6);
    const ObjectShape shape = i % 2 ? ObjectShape::sphere(0.5 * size(rng)) : ObjectShape::box({size(rng), size(rng), size(rng)});
    o.shapes.push_back({shape, Transform()});
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

struct FclWorld {
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  fcl::DynamicAABBTreeCollisionManagerd manager;
};

std::shared_ptr<fcl::CollisionGeometryd> fcl_geometry(const ObjectShape& s) {
  if (s.kind == ObjectShape::Kind::kBox) return std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
  return std::make_shared<fcl::Sphered>(s.radius);
}

void register_in_fcl(const SceneFile& scene, FclWorld& world) {
  for (const SceneObject& o : scene.objects) {
    world.objects.push_back(std::make_unique<fcl::CollisionObjectd>(fcl_geometry(o.shapes[0].shape), test::fcl_transform(o.pose)));
    world.objects.back()->computeAABB();
    world.manager.registerObject(world.objects.back().get());
  }
  world.manager.setup();
}

// The robot's links as FCL objects (OBBRSS models of their meshes), moved to a state and collided
// with the manager one at a time, stopping at the first contact: MoveIt's world check.
class FclRobot {
 public:
  explicit FclRobot(const RobotModel& model) : model_(model) {
    for (std::size_t l = 0; l < model.links().size(); ++l) {
      for (const CollisionElement& e : model.links()[l].collision) {
        links_.push_back({static_cast<int>(l), e.origin, std::make_unique<fcl::CollisionObjectd>(test::fcl_model<fcl::OBBRSSd>(*e.mesh))});
      }
    }
  }
  bool collides(const double* state, fcl::DynamicAABBTreeCollisionManagerd& world) {
    forward_kinematics(model_, state, poses_);
    for (Link& l : links_) {
      l.object->setTransform(test::fcl_transform(poses_[l.link] * l.origin));
      l.object->computeAABB();
      fcl::DefaultCollisionData<double> data;
      world.collide(l.object.get(), &data, fcl::DefaultCollisionFunction<double>);
      if (data.result.isCollision()) return true;
    }
    return false;
  }

 private:
  struct Link {
    int link;
    Transform origin;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  const RobotModel& model_;
  std::vector<Link> links_;
  std::vector<Transform> poses_;
};

struct Row {
  Spread load, per_add, fcl_register, check, fcl_check;
  double memory_mb = 0.0, fcl_memory_mb = 0.0, colliding = 0.0, disagree = 0.0;
};

Row measure(std::size_t n, int runs, const CollisionChecker& checker, const std::string& dir) {
  const SceneFile scene = many_objects(n, 7 + n);
  const std::string path = dir + "/scene_scale_" + std::to_string(n) + "_" + std::to_string(::getpid()) + ".scene";
  write_scene_file(scene, path);
  Row row;
  std::vector<double> load, per_add, fcl_register;
  std::optional<Environment> world;
  std::optional<FclWorld> fcl_world;
  for (int r = 0; r < runs; ++r) {
    world.reset();
    const double before = heap_bytes();
    load.push_back(time_us([&] { world = read_scene_file(path).environment(); }) / 1e6);
    row.memory_mb = (heap_bytes() - before) / 1e6;
    // One at a time, each change a new snapshot the way the node's store makes one.
    Environment one_by_one(0.05);
    per_add.push_back(time_us([&] {
      for (const SceneObject& o : scene.objects) {
        Environment next = one_by_one;
        next.add_object(o.id, o.shapes[0].shape, o.pose);
        one_by_one = std::move(next);
      }
    }) / static_cast<double>(n));
    fcl_world.reset();
    const double fcl_before = heap_bytes();
    fcl_register.push_back(time_us([&] { register_in_fcl(scene, fcl_world.emplace()); }) / 1e6);
    row.fcl_memory_mb = (heap_bytes() - fcl_before) / 1e6;
  }
  std::filesystem::remove(path);
  row.load = spread(load), row.per_add = spread(per_add), row.fcl_register = spread(fcl_register);
  // One state check (the environment only: boolean, first contact) at 400 random states.
  std::mt19937_64 rng(3);
  FclRobot fcl_robot(checker.model());
  std::vector<double> ours, theirs;
  std::size_t hits = 0, disagree = 0;
  for (int i = 0; i < 400; ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    bool a = false, b = false;
    ours.push_back(time_us([&] { a = checker.check_environment(q.data(), *world).collision; }));
    theirs.push_back(time_us([&] { b = fcl_robot.collides(q.data(), fcl_world->manager); }));
    hits += a;
    disagree += a != b;
  }
  row.check = spread(ours), row.fcl_check = spread(theirs);
  row.colliding = static_cast<double>(hits) / 400.0;
  row.disagree = static_cast<double>(disagree);
  return row;
}

}  // namespace
}  // namespace bvh_collision::bench

int main(int argc, char** argv) {
  using namespace bvh_collision;
  using namespace bvh_collision::bench;
  const std::string dir = output_dir(argc, argv);
  std::filesystem::create_directories(dir);
  const bool quick = quick_mode(argc, argv);
  const bool panda = std::filesystem::exists(test::robots_dir() + "/panda");
  const CollisionChecker checker = panda ? test::panda_as_moveit() : test::demo_arm_checker();
  Table table("scene_scale", "Scenes of many objects: load, one state check, memory (against FCL's DynamicAABBTree manager)",
              {"objects", "load s", "load low", "load high", "FCL register s", "per add us", "check us", "check low", "check high",
               "FCL check us", "check ratio", "MB", "FCL MB", "colliding", "answers differing"});
  const std::vector<std::pair<std::size_t, int>> sizes = quick ? std::vector<std::pair<std::size_t, int>>{{1000, 1}}
                                                              : std::vector<std::pair<std::size_t, int>>{{1000, 5}, {10000, 3}, {100000, 1}};
  for (const auto& [n, runs] : sizes) {
    const Row r = measure(n, runs, checker, dir);
    table.row({double(n), r.load.median, r.load.low, r.load.high, r.fcl_register.median, r.per_add.median, r.check.median, r.check.low,
               r.check.high, r.fcl_check.median, r.fcl_check.median / r.check.median, r.memory_mb, r.fcl_memory_mb, r.colliding, r.disagree});
  }
  table.note(std::string("Robot: ") + (panda ? "panda" : "the demo arm") +
             "; n boxes and spheres of 2-20 cm at one object per 0.05 m^3 around its base, none within 0.6 m of its shoulder. 'load': the .scene file read and "
             "built (hierarchies, hulls, the object list) as the CLI and load_scene build it; 'FCL register': the same "
             "objects as FCL primitives registered in a DynamicAABBTree manager and set up; 'per add': one object set on "
             "a new snapshot of the world, as set_collision_object sets it. 'check': one environment check of a random "
             "state (boolean, first contact), median over 400 states; 'answers differing': states where FCL's answer is not ours "
             "(FCL's meshes and primitives meet ours only to its own rounding); 'check ratio' FCL's time over ours. MB: heap bytes the built world takes (ours keeps a box as 12 triangles with its "
             "hierarchy and hull besides the exact primitive).");
  table.write(dir);
  return 0;
}
