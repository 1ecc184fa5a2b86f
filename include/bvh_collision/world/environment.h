// The robot's surroundings: the obstacle octree built from sensor scans, and collision objects
// (boxes, spheres, cylinders, meshes) that a planner adds, moves and removes by id.
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/world/named_allowed_collisions.h"
#include "bvh_collision/world/object_list.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/narrowphase/shape.h"
#include "bvh_collision/octree/distance_field.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

struct ObjectShape {
  using Kind = ShapeKind;
  Kind kind = Kind::kBox;
  Vec3 size = Vec3::Zero();  // box: edge lengths
  double radius = 0.0;       // sphere, cylinder, capsule; cone: its base
  double length = 0.0;       // cylinder and cone, along their z axis; capsule: its axis segment (caps beyond)
  std::shared_ptr<const TriangleMesh> mesh;

  static ObjectShape box(const Vec3& size) { return {Kind::kBox, size, 0.0, 0.0, nullptr}; }
  static ObjectShape sphere(double radius) { return {Kind::kSphere, Vec3::Zero(), radius, 0.0, nullptr}; }
  static ObjectShape cylinder(double radius, double length) { return {Kind::kCylinder, Vec3::Zero(), radius, length, nullptr}; }
  // The points within `radius` of the segment of `length` along z through the origin.
  static ObjectShape capsule(double radius, double length) { return {Kind::kCapsule, Vec3::Zero(), radius, length, nullptr}; }
  // Base (radius) at z = -length/2, tip at +length/2 (shape_msgs/SolidPrimitive's cone).
  static ObjectShape cone(double radius, double length) { return {Kind::kCone, Vec3::Zero(), radius, length, nullptr}; }
  // The triangles it is given as (0 for a primitive): what the node's size limit counts.
  std::size_t triangle_count() const { return mesh != nullptr ? mesh->triangles.size() : 0; }
  static ObjectShape triangles(TriangleMesh m) {
    return {Kind::kMesh, Vec3::Zero(), 0.0, 0.0, std::make_shared<const TriangleMesh>(std::move(m))};
  }
};

struct CollisionObject {
  std::string id;
  ObjectShape shape;
  Transform pose;  // in the world frame
  // Geometry as the checker uses it: spheres, cylinders, capsules and cones stay exact primitives (no mesh);
  // boxes (exact as 12 triangles) and meshes get a BVH and a hull.
  std::shared_ptr<const Bvh<Obb>> mesh;
  std::shared_ptr<const ConvexHull> hull;
  Primitive primitive;  // when mesh is null
  Vec3 bound_center = Vec3::Zero();  // object frame
  double bound_radius = 0.0;
  // The pose of the object this is a shape of (MoveIt's object pose, in the frame `pose` is in):
  // the shape lies at frame^-1 * pose within it. Moving the object moves its frame and every
  // shape with it; a scene written out poses the object at its frame.
  Transform frame = Transform::Identity();
};

// The object as the narrowphase takes it (its mesh and hull, or its primitive) ...
inline ShapeRef shape_of(const CollisionObject& o) { return ShapeRef{o.mesh.get(), o.hull.get(), o.primitive}; }
// ... and as the single-state tests take it: a box as the exact primitive it is (kept as 12
// triangles too, which the general queries use; mesh against box primitive is the faster test).
ShapeRef exact_shape_of(const CollisionObject& o);

// Why `id` cannot name a collision object, or "" when it can: an id is not empty and holds no
// '#' (id#k names an object's shapes) and no control character (U+0000..U+001F, U+007F: a NUL
// would cut it short in C strings and log lines, an ESC rewrite the terminal that shows it).
std::string object_id_problem(const std::string& id);
// The id as a message may quote it: control characters written as \xHH.
std::string printable_id(const std::string& id);

// The object a shape belongs to: an object of several shapes keeps them as "id#k" (an id itself
// never holds '#'), and names such as allowed-collision entries name the object, "id".
inline std::string object_name(const std::string& shape_id) { return shape_id.substr(0, shape_id.find('#')); }

// An object the robot carries (MoveIt's AttachedCollisionObject): its shapes fixed in a link's
// frame, moving with the link in every query. A checker carries it as one more link, named `id`,
// hung from `link` (CollisionChecker::carrying): self checks test it against every link except
// `link` and `touch_links` (and pairs the environment's allowed collisions name), environment
// checks against the world, motions bound it by its link's motion, the self filter drops points
// on it, rays and contacts name it `id`.
struct AttachedBody {
  std::string id;    // as a world object's id (no '#'); differs from every link name
  std::string link;  // the link it hangs from
  std::vector<std::string> touch_links;  // links allowed to touch it besides `link`
  std::vector<CollisionObject> shapes;   // built, poses in the link's frame ("id", or "id#k" for several)
};

// An object as queries use it: its hierarchy and hull built (the costly part of adding one).
// Throws std::invalid_argument as Environment::add_object does.
CollisionObject make_collision_object(const std::string& id, const ObjectShape& shape, const Transform& pose);

// A copy shares the octree's pages (octree.h) and the object list; a change copies what it
// writes: the octree pages it touches, or the nodes of the object list on one path (object_list.h:
// log n of them; each object's hierarchy and hull stay shared). Snapshots that readers keep thus
// cost only what changed since, and adding the n-th object costs log n.
class Environment {
 public:
  // Throws std::invalid_argument for a resolution that is not a positive finite number.
  explicit Environment(double octree_resolution, const OccupancyModel& model = {});
  // Copies share the distance field already built (it belongs to the octree's revision).
  Environment(const Environment& other);
  Environment& operator=(const Environment& other);
  Environment(Environment&&) = default;
  Environment& operator=(Environment&&) = default;

  // This snapshot or an unchanged copy of it: the same octree revision and the same object list,
  // allowed collisions and attached bodies (shared, not compared). What is prepared from one
  // (a query's prepared scene) answers for the other.
  bool same_snapshot(const Environment& o) const {
    return octree_.revision() == o.octree_.revision() && objects_.same_as(o.objects_) && allowed_ == o.allowed_ &&
           attached_ == o.attached_;
  }

  Octree& octree() { return octree_; }
  const Octree& octree() const { return octree_; }

  // Adds the object, or replaces the one with the same id. Throws std::invalid_argument (and
  // changes nothing) for an empty id, a non-finite or non-rigid pose, dimensions that are not
  // positive and finite, or a mesh without triangles or with non-finite vertices.
  void add_object(const std::string& id, const ObjectShape& shape, const Transform& pose);
  // The same with the object already built (make_collision_object): a writer that holds a lock
  // builds the hierarchy and hull before taking it.
  void add_object(CollisionObject object);
  // False (and nothing changes) when no object has this id; move throws for a bad pose.
  bool move_object(const std::string& id, const Transform& pose);
  bool remove_object(const std::string& id);
  // Every shape of the object `name` ("name", or its shapes "name#k"); how many there were.
  std::size_t remove_object_shapes(const std::string& name) { return objects_.remove_object(name); }
  void clear_objects() { objects_.clear(); }
  const ObjectList& objects() const { return objects_; }
  const CollisionObject* find_object(const std::string& id) const;
  // Allowed collisions that name objects (a link with an object, an object's default entry):
  // the environment's checks skip the allowed (link, object) pairs. Kept by name, so an entry
  // holds for an object added later, as MoveIt's do.
  const NamedAllowedCollisions& allowed_collisions() const { return *allowed_; }
  // The same, shared: unchanged between snapshots until the allowances change.
  const std::shared_ptr<const NamedAllowedCollisions>& allowed_collisions_shared() const { return allowed_; }
  void set_allowed_collisions(NamedAllowedCollisions allowed) {
    allowed_ = std::make_shared<const NamedAllowedCollisions>(std::move(allowed));
  }
  // Is link `link_name` allowed to touch object `o` (an index into objects())? The entries name
  // whole objects: a shape "id#k" of a several-shape object answers as "id".
  bool object_allowed(const std::string& link_name, std::size_t o) const {
    if (allowed_->empty()) return false;
    return allowed_->allowed(link_name, object_name(objects_[o].id));
  }

  // Objects the robot carries (AttachedBody), in the order attached. A snapshot that holds one
  // does not hold a world object of that id: attaching and detaching move an object between the
  // two in one change (the node's attach_object, detach_object), so a query sees it in one place.
  const std::vector<AttachedBody>& attached() const { return *attached_; }
  // The list itself: unchanged between snapshots until an object is attached or detached (the
  // node keeps the checker that carries it by this pointer).
  const std::shared_ptr<const std::vector<AttachedBody>>& attached_list() const { return attached_; }
  const AttachedBody* find_attached(const std::string& id) const;
  // Adds the body, or replaces the one with the same id. Throws std::invalid_argument (and changes
  // nothing) for an empty id, one with '#', no link or no shapes.
  void attach(AttachedBody body);
  // False (and nothing changes) when no body has this id.
  bool detach(const std::string& id);

  // The octree's distance field (octree/distance_field.h) over at least [lo, hi] with at least
  // `cap`, built on the first call and kept until the octree changes (its revision) or a box or
  // cap it does not cover is asked for; null when that would take more than `max_cells` cells.
  // Safe to call from several threads on one environment (two may build it; one is kept).
  // With build = false, only a field already kept (else null).
  // A field kept for an earlier revision is updated, not rebuilt, when the octree changed from it
  // only by the voxels note_octree_changes was told of: the newest field this environment or a
  // copy made is updated with the voxels changed since, in place on its grid's file, the fields
  // still held (a query's snapshot, a pinned version) first keeping the pages that change
  // (OctreeDistanceField::updated): the work and the memory are those of the change, with no copy
  // of the grid. Only a field made from one that a newer field was already made from is copied
  // (octree_field_work says which).
  std::shared_ptr<const OctreeDistanceField> octree_distance_field(const Vec3& lo, const Vec3& hi, double cap,
                                                                   std::size_t max_cells = std::size_t(1) << 24,
                                                                   bool build = true) const;

  // The octree went from revision `from` to its current one by flipping the occupancy of `flipped`
  // (a scan's ScanStats::flipped) and nothing else: a distance field kept for `from` follows them.
  // The last few notes are kept while each starts where the one before ended.
  void note_octree_changes(std::uint64_t from, std::vector<OctreeKey> flipped);

  // How the field kept for the current octree came to be: built, or updated from an earlier one
  // (`copied_cells` 0: in place on that one's grid). Empty when none is kept.
  std::optional<OctreeDistanceField::UpdateWork> octree_field_work() const;
  // The distance fields this environment and its copies keep to make the next ones from (the
  // last two made): memory the map holds whoever else holds a field.
  std::vector<std::shared_ptr<const OctreeDistanceField>> pooled_octree_fields() const;
  // The distance field this environment holds (for any revision), or null: what it keeps in memory.
  std::shared_ptr<const OctreeDistanceField> held_octree_field() const {
    const std::shared_ptr<const FieldCache> kept = std::atomic_load(&field_);
    return kept ? std::shared_ptr<const OctreeDistanceField>(kept, &kept->field) : nullptr;
  }

 private:
  struct FieldCache {
    std::uint64_t revision = 0;
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    double cap = 0.0;
    OctreeDistanceField field;
    OctreeDistanceField::UpdateWork work;  // how it was made
  };
  // The fields this environment and its copies made last (the newest at the back): one nobody
  // else holds is written over to become the next; else the next is a new version made from one.
  struct FieldPool {
    std::mutex mutex;
    std::vector<std::shared_ptr<FieldCache>> recent;
  };
  struct FieldSource {
    std::shared_ptr<FieldCache> field;
    bool nobody_holds = false;  // taken out of the pool, to be written over
    bool in_place = false;      // a new version on its grid (else a copy)
  };
  FieldSource field_to_follow(const Vec3& lo, const Vec3& hi, double cap,
                              std::vector<const std::vector<OctreeKey>*>& steps) const;
  bool covers(const FieldCache& f, const Vec3& lo, const Vec3& hi, double cap) const;
  bool changes_since(std::uint64_t revision, std::vector<const std::vector<OctreeKey>*>& steps) const;
  Octree octree_;
  ObjectList objects_;
  std::shared_ptr<const NamedAllowedCollisions> allowed_ = std::make_shared<const NamedAllowedCollisions>();
  std::shared_ptr<const std::vector<AttachedBody>> attached_ = std::make_shared<const std::vector<AttachedBody>>();
  mutable std::shared_ptr<const FieldCache> field_;  // read and written with std::atomic_load/store
  std::shared_ptr<FieldPool> pool_ = std::make_shared<FieldPool>();  // copies share it
  struct OctreeChanges {
    std::uint64_t from = 0, to = 0;
    std::vector<OctreeKey> flipped;
  };
  // the last notes, oldest first, each starting where the one before ended (copies share them)
  std::vector<std::shared_ptr<const OctreeChanges>> changes_;
};

}  // namespace bvh_collision
