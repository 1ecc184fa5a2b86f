#include "bvh_collision/world/environment.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {
namespace {

// Objects lie within this of the origin and are at most this large (m): a world of kilometres
// fits many times over, and the geometry, which squares coordinates (hull volumes, areas, a grid's
// cell counts), keeps its millimetres. Beyond it a box 1e150 m wide overran the convex hull's
// memory (make fuzz).
constexpr double kLargest = 1e6;

// Positive, finite and at most kLargest.
bool positive(double v) { return std::isfinite(v) && v > 0.0 && v <= kLargest; }

void require_rigid(const Transform& pose, const std::string& id) {
  if (!is_rigid(pose)) {
    throw std::invalid_argument("object '" + id + "': the pose must be finite with a rotation matrix");
  }
  if (!(pose.t.cwiseAbs().maxCoeff() <= kLargest)) {
    throw std::invalid_argument("object '" + id + "': the pose must lie within 1e6 m of the origin");
  }
}

TriangleMesh object_mesh(const ObjectShape& shape, const std::string& id) {
  const std::string what = "object '" + id + "': ";
  switch (shape.kind) {
    case ObjectShape::Kind::kBox:
      if (!(positive(shape.size.x()) && positive(shape.size.y()) && positive(shape.size.z()))) {
        throw std::invalid_argument(what + "box sizes must be positive, finite and at most 1e6 m");
      }
      return box_mesh(shape.size);
    case ObjectShape::Kind::kMesh: {
      if (!shape.mesh || shape.mesh->empty()) throw std::invalid_argument(what + "the mesh has no triangles");
      for (const Vec3& v : shape.mesh->vertices) {
        if (!v.allFinite()) throw std::invalid_argument(what + "the mesh has a non-finite vertex");
        if (!(v.cwiseAbs().maxCoeff() <= kLargest)) throw std::invalid_argument(what + "the mesh has a vertex beyond 1e6 m");
      }
      for (const auto& t : shape.mesh->triangles) {
        for (const std::int32_t i : t) {
          if (i < 0 || i >= static_cast<std::int32_t>(shape.mesh->vertices.size())) {
            throw std::invalid_argument(what + "a mesh triangle indexes a missing vertex");
          }
        }
      }
      return *shape.mesh;
    }
    case ObjectShape::Kind::kSphere:
    case ObjectShape::Kind::kCylinder:
    case ObjectShape::Kind::kCapsule:
    case ObjectShape::Kind::kCone: break;
  }
  return {};
}

}  // namespace

ShapeRef exact_shape_of(const CollisionObject& o) {
  if (o.shape.kind == ObjectShape::Kind::kBox) return ShapeRef{nullptr, nullptr, Primitive::box(o.shape.size)};
  return shape_of(o);
}

CollisionObject make_collision_object(const std::string& id, const ObjectShape& shape, const Transform& pose) {
  if (id.empty()) throw std::invalid_argument("a collision object needs a non-empty id");
  // The object's name part (before any '#k') by the rule for ids; the whole for control characters.
  std::string problem = object_id_problem(object_name(id));
  if (problem.empty() && printable_id(id) != id) problem = "id '" + printable_id(id) + "' holds a control character";
  if (!problem.empty()) throw std::invalid_argument("collision object " + problem);
  require_rigid(pose, id);
  CollisionObject o{id, shape, pose, nullptr, nullptr, Primitive{}, Vec3::Zero(), 0.0};
  if (shape.kind == ObjectShape::Kind::kSphere) {
    if (!positive(shape.radius)) throw std::invalid_argument("object '" + id + "': sphere radius must be positive, finite and at most 1e6 m");
    o.primitive = Primitive::sphere(shape.radius);
  }
  if (shape.kind == ObjectShape::Kind::kCylinder) {
    if (!(positive(shape.radius) && positive(shape.length))) {
      throw std::invalid_argument("object '" + id + "': cylinder radius and length must be positive, finite and at most 1e6 m");
    }
    o.primitive = Primitive::cylinder(shape.radius, shape.length);
  }
  if (shape.kind == ObjectShape::Kind::kCapsule) {
    if (!(positive(shape.radius) && shape.length >= 0.0 && shape.length <= kLargest)) {
      throw std::invalid_argument("object '" + id + "': capsule radius must be positive and its length non-negative, both finite and at most 1e6 m");
    }
    o.primitive = Primitive::capsule(shape.radius, shape.length);
  }
  if (shape.kind == ObjectShape::Kind::kCone) {
    if (!(positive(shape.radius) && positive(shape.length))) {
      throw std::invalid_argument("object '" + id + "': cone radius and length must be positive, finite and at most 1e6 m");
    }
    o.primitive = Primitive::cone(shape.radius, shape.length);
  }
  if (o.primitive.radius > 0.0) {  // a sphere, cylinder, capsule or cone: exact, no mesh
    o.bound_radius = bounding_radius(o.primitive);
    return o;
  }
  const TriangleMesh mesh = object_mesh(shape, id);
  BuildOptions build{BuildMethod::kSah, 2};
  build.sampled_slack = shape.kind != ObjectShape::Kind::kBox;  // a box answers states as the exact primitive
  o.mesh = std::make_shared<const Bvh<Obb>>(Bvh<Obb>::build(mesh, build));
  o.hull = std::make_shared<const ConvexHull>(convex_hull(used_vertices(mesh)));
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& v : used_vertices(mesh)) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  o.bound_center = 0.5 * (lo + hi);
  for (const Vec3& v : used_vertices(mesh)) o.bound_radius = std::max(o.bound_radius, (v - o.bound_center).norm());
  o.bound_radius = grown_radius(o.bound_radius);
  return o;
}

Environment::Environment(double octree_resolution, const OccupancyModel& model) : octree_(octree_resolution, model) {}

Environment::Environment(const Environment& other)
    : octree_(other.octree_),
      objects_(other.objects_),
      allowed_(other.allowed_),
      attached_(other.attached_),
      field_(std::atomic_load(&other.field_)),
      pool_(other.pool_),
      changes_(other.changes_) {}

Environment& Environment::operator=(const Environment& other) {
  if (this == &other) return *this;
  octree_ = other.octree_;
  objects_ = other.objects_;
  allowed_ = other.allowed_;
  attached_ = other.attached_;
  std::atomic_store(&field_, std::atomic_load(&other.field_));
  pool_ = other.pool_;
  changes_ = other.changes_;
  return *this;
}

// Two notes are enough for a field to be made from the one before the kept one (the kept one is
// held by the current snapshot); the others cover a snapshot held a little longer.
constexpr std::size_t kNotesKept = 4;
constexpr std::size_t kFieldsPooled = 2;

void Environment::note_octree_changes(std::uint64_t from, std::vector<OctreeKey> flipped) {
  if (!changes_.empty() && changes_.back()->to != from) changes_.clear();  // a change no note covers
  if (changes_.size() >= kNotesKept) changes_.erase(changes_.begin());
  changes_.push_back(std::make_shared<const OctreeChanges>(OctreeChanges{from, octree_.revision(), std::move(flipped)}));
}

// The flipped lists that take the tree of `revision` to the current one, from the notes (none when
// it is the current one); false when the notes do not reach back to it.
bool Environment::changes_since(std::uint64_t revision, std::vector<const std::vector<OctreeKey>*>& steps) const {
  steps.clear();
  if (revision == octree_.revision()) return true;
  if (changes_.empty() || changes_.back()->to != octree_.revision()) return false;
  for (std::size_t i = changes_.size(); i-- > 0;) {
    if (changes_[i]->from == revision) {
      for (std::size_t j = i; j < changes_.size(); ++j) steps.push_back(&changes_[j]->flipped);
      return true;
    }
  }
  return false;
}

bool Environment::covers(const FieldCache& f, const Vec3& lo, const Vec3& hi, double cap) const {
  return f.cap >= cap && (f.lo.array() <= lo.array()).all() && (f.hi.array() >= hi.array()).all();
}

// The field to make the next one from, taken out of the pool when it is to be written over: the
// newest pooled field nobody else holds (written over in place), else the newest on another grid
// than the newest field's (a new version on that grid, in place), else the newest or this
// environment's own, copied into a grid of its own (so the pool's two fields are on two grids and
// the current snapshot's field never has pages copied into it); each must cover the box, with
// notes from its revision to the current.
Environment::FieldSource Environment::field_to_follow(const Vec3& lo, const Vec3& hi, double cap,
                                                      std::vector<const std::vector<OctreeKey>*>& steps) const {
  std::lock_guard<std::mutex> lock(pool_->mutex);
  std::vector<std::shared_ptr<FieldCache>>& recent = pool_->recent;
  auto usable = [&](const FieldCache& f) { return covers(f, lo, hi, cap) && changes_since(f.revision, steps); };
  for (std::size_t i = recent.size(); i-- > 0;) {
    // use_count 1: no snapshot, checker or query holds it, and none can take it but from here
    if (recent[i].use_count() != 1 || !usable(*recent[i])) continue;
    std::atomic_thread_fence(std::memory_order_acquire);  // after the last holder's reads of it
    FieldSource out{std::move(recent[i]), true, true};
    recent.erase(recent.begin() + std::ptrdiff_t(i));
    return out;
  }
  for (std::size_t i = recent.size(); i-- > 1;) {  // (recent.back() is the newest)
    if (!recent[i - 1]->field.same_grid(recent.back()->field) && usable(*recent[i - 1])) return {recent[i - 1], false, true};
  }
  if (!recent.empty() && usable(*recent.back())) return {recent.back(), false, false};
  const std::shared_ptr<const FieldCache> kept = std::atomic_load(&field_);
  if (kept && usable(*kept)) return {std::const_pointer_cast<FieldCache>(kept), false, false};
  return {};
}

std::shared_ptr<const OctreeDistanceField> Environment::octree_distance_field(const Vec3& lo, const Vec3& hi, double cap,
                                                                              std::size_t max_cells, bool build) const {
  const std::shared_ptr<const FieldCache> kept = std::atomic_load(&field_);
  if (kept && kept->revision == octree_.revision() && covers(*kept, lo, hi, cap)) {
    return std::shared_ptr<const OctreeDistanceField>(kept, &kept->field);
  }
  if (!build) return nullptr;
  std::vector<const std::vector<OctreeKey>*> steps;
  FieldSource source = field_to_follow(lo, hi, cap, steps);
  std::shared_ptr<FieldCache> fresh;
  if (source.field && source.nobody_holds) {  // written over: the voxels changed since its revision
    fresh = std::move(source.field);
    fresh->work = {};
    fresh->field.follow(octree_, steps, &fresh->work);
  } else if (source.field) {  // a new version: in place on its grid (held ones keeping their pages) or copied
    fresh = std::make_shared<FieldCache>();
    fresh->lo = source.field->lo, fresh->hi = source.field->hi, fresh->cap = source.field->cap;
    fresh->field = source.field->field.updated(octree_, steps, &fresh->work, source.in_place);
  } else {
    fresh = std::make_shared<FieldCache>();
    fresh->lo = lo, fresh->hi = hi, fresh->cap = cap;
    try {
      fresh->field = OctreeDistanceField::build(octree_, lo, hi, cap, max_cells);
    } catch (const std::invalid_argument&) {
      return nullptr;  // too large a box at this resolution (or not finite): no field
    }
    fresh->work.rebuilt = true;
    fresh->work.cells = fresh->field.cells();
  }
  fresh->revision = octree_.revision();
  {
    std::lock_guard<std::mutex> lock(pool_->mutex);
    pool_->recent.push_back(fresh);
    if (pool_->recent.size() > kFieldsPooled) pool_->recent.erase(pool_->recent.begin());
  }
  std::shared_ptr<const FieldCache> out = std::move(fresh);
  std::atomic_store(&field_, out);
  return std::shared_ptr<const OctreeDistanceField>(out, &out->field);
}

std::vector<std::shared_ptr<const OctreeDistanceField>> Environment::pooled_octree_fields() const {
  std::lock_guard<std::mutex> lock(pool_->mutex);
  std::vector<std::shared_ptr<const OctreeDistanceField>> out;
  for (const std::shared_ptr<FieldCache>& f : pool_->recent) out.emplace_back(f, &f->field);
  return out;
}

std::optional<OctreeDistanceField::UpdateWork> Environment::octree_field_work() const {
  const std::shared_ptr<const FieldCache> kept = std::atomic_load(&field_);
  if (!kept || kept->revision != octree_.revision()) return std::nullopt;
  return kept->work;
}

void Environment::add_object(const std::string& id, const ObjectShape& shape, const Transform& pose) {
  add_object(make_collision_object(id, shape, pose));  // throws before anything changes
}

void Environment::add_object(CollisionObject o) {
  objects_.add(std::make_shared<const CollisionObject>(std::move(o)));
}

bool Environment::move_object(const std::string& id, const Transform& pose) {
  const std::ptrdiff_t i = objects_.find(id);
  if (i < 0) return false;
  require_rigid(pose, id);
  auto moved = std::make_shared<CollisionObject>(objects_[static_cast<std::size_t>(i)]);
  moved->pose = pose;
  objects_.add(std::move(moved));
  return true;
}

bool Environment::remove_object(const std::string& id) { return objects_.remove(id); }

const AttachedBody* Environment::find_attached(const std::string& id) const {
  const auto it = std::find_if(attached_->begin(), attached_->end(), [&](const AttachedBody& b) { return b.id == id; });
  return it == attached_->end() ? nullptr : &*it;
}

void Environment::attach(AttachedBody body) {
  if (const std::string problem = object_id_problem(body.id); !problem.empty()) {
    throw std::invalid_argument("attached object " + problem);
  }
  if (body.link.empty()) throw std::invalid_argument("attached object '" + body.id + "': no link named");
  if (body.shapes.empty()) throw std::invalid_argument("attached object '" + body.id + "' has no shapes");
  auto next = std::make_shared<std::vector<AttachedBody>>(*attached_);
  const auto it = std::find_if(next->begin(), next->end(), [&](const AttachedBody& b) { return b.id == body.id; });
  if (it != next->end()) {
    *it = std::move(body);
  } else {
    next->push_back(std::move(body));
  }
  attached_ = std::move(next);
}

bool Environment::detach(const std::string& id) {
  auto next = std::make_shared<std::vector<AttachedBody>>(*attached_);
  const auto it = std::find_if(next->begin(), next->end(), [&](const AttachedBody& b) { return b.id == id; });
  if (it == next->end()) return false;
  next->erase(it);
  attached_ = std::move(next);
  return true;
}

const CollisionObject* Environment::find_object(const std::string& id) const {
  const std::ptrdiff_t i = objects_.find(id);
  return i < 0 ? nullptr : &objects_[static_cast<std::size_t>(i)];
}

std::string printable_id(const std::string& id) {
  static const char* const kHex = "0123456789ABCDEF";
  std::string out;
  for (const char ch : id) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7F) {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    } else {
      out += ch;
    }
  }
  return out;
}

std::string object_id_problem(const std::string& id) {
  if (id.empty()) return "id is empty";
  for (std::size_t i = 0; i < id.size(); ++i) {
    const auto c = static_cast<unsigned char>(id[i]);
    if (c < 0x20 || c == 0x7F) {
      static const char* const kHex = "0123456789ABCDEF";
      return std::string("id '") + printable_id(id) + "' holds a control character (0x" + kHex[c >> 4] + kHex[c & 15] +
             " at byte " + std::to_string(i) + ")";
    }
  }
  if (id.find('#') != std::string::npos) return "id '" + id + "' contains '#' (it names an object's shapes: id#k)";
  return "";
}

}  // namespace bvh_collision
