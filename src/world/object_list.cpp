// The persistent object list and its loose octree of boxes (world/object_list.h).
#include "bvh_collision/world/object_list.h"

#include <algorithm>
#include <cmath>

#include "bvh_collision/world/environment.h"
#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

void object_world_box(const CollisionObject& o, Vec3& lo, Vec3& hi) {
  const ShapeRef exact = exact_shape_of(o);
  const bool primitive = exact_primitive(exact) != nullptr;
  const Vec3 centre = o.pose * (primitive ? Vec3::Zero() : o.bound_center);
  const Vec3 half = primitive ? Vec3(o.pose.R.cwiseAbs() * half_extents(exact.primitive)) : Vec3::Constant(o.bound_radius);
  const double m = pose_margin(centre.norm() + half.norm());
  lo = centre - half - Vec3::Constant(m);
  hi = centre + half + Vec3::Constant(m);
}

// The deepest level whose cells are at least as large as the box (it then lies within its cell
// grown by the cell's half-size); the root for a box beyond the root's cube.
int ObjectBoxTree::depth_for(const Vec3& lo, const Vec3& hi) {
  const Vec3 mid = 0.5 * (lo + hi);
  if (!(mid.cwiseAbs().maxCoeff() < kRootHalf)) return 0;
  const double extent = (hi - lo).maxCoeff();
  int depth = 0;
  double half = kRootHalf;
  while (depth < kMaxDepth && half >= extent) {  // the child's cell, of edge `half`, still holds it
    half *= 0.5;
    ++depth;
  }
  return depth;
}

ObjectBoxTree::NodePtr ObjectBoxTree::inserted(const NodePtr& node, const Vec3& centre, double half, int depth,
                                               const Entry& e, PersistentWork* work) {
  auto copy = node ? std::make_shared<Node>(*node) : std::make_shared<Node>();
  if (work != nullptr) {
    ++work->nodes;
    work->entries += 8 + copy->items.size();
  }
  if (depth == 0) {
    copy->items.push_back(e);
    return copy;
  }
  const Vec3 mid = 0.5 * (e.lo + e.hi);
  const int k = (mid.x() >= centre.x() ? 4 : 0) | (mid.y() >= centre.y() ? 2 : 0) | (mid.z() >= centre.z() ? 1 : 0);
  copy->child[k] = inserted(copy->child[k], child_centre(centre, 0.5 * half, k), 0.5 * half, depth - 1, e, work);
  return copy;
}

ObjectBoxTree::NodePtr ObjectBoxTree::erased(const NodePtr& node, const Vec3& centre, double half, int depth,
                                             std::uint32_t slot, const Vec3& mid, bool& found, PersistentWork* work) {
  if (node == nullptr) return nullptr;
  auto copy = std::make_shared<Node>(*node);
  if (work != nullptr) {
    ++work->nodes;
    work->entries += 8 + copy->items.size();
  }
  if (depth == 0) {
    const auto it = std::find_if(copy->items.begin(), copy->items.end(), [&](const Entry& x) { return x.slot == slot; });
    if (it == copy->items.end()) return node;
    found = true;
    copy->items.erase(it);
  } else {
    const int k = (mid.x() >= centre.x() ? 4 : 0) | (mid.y() >= centre.y() ? 2 : 0) | (mid.z() >= centre.z() ? 1 : 0);
    copy->child[k] = erased(copy->child[k], child_centre(centre, 0.5 * half, k), 0.5 * half, depth - 1, slot, mid, found, work);
    if (!found) return node;
  }
  // A node left with nothing is dropped, so that an emptied region costs a walk nothing.
  const bool empty = copy->items.empty() && std::all_of(copy->child.begin(), copy->child.end(), [](const NodePtr& c) { return !c; });
  return empty ? nullptr : NodePtr(std::move(copy));
}

void ObjectBoxTree::insert(const Entry& e, PersistentWork* work) {
  root_ = inserted(root_, Vec3::Zero(), kRootHalf, depth_for(e.lo, e.hi), e, work);
}

bool ObjectBoxTree::erase(std::uint32_t slot, const Vec3& lo, const Vec3& hi, PersistentWork* work) {
  bool found = false;
  NodePtr next = erased(root_, Vec3::Zero(), kRootHalf, depth_for(lo, hi), slot, 0.5 * (lo + hi), found, work);
  if (found) root_ = std::move(next);
  return found;
}

ObjectList::ObjectList(const std::vector<CollisionObject>& objects) {
  for (const CollisionObject& o : objects) add(std::make_shared<const CollisionObject>(o));
}

std::ptrdiff_t ObjectList::find(const std::string& shape_id) const {
  const std::vector<std::uint32_t>* slots = by_name_.find(object_name(shape_id));
  if (slots == nullptr) return -1;
  for (const std::uint32_t s : *slots) {
    if (records_[s]->id == shape_id) return static_cast<std::ptrdiff_t>(s);
  }
  return -1;
}

std::vector<std::uint32_t> ObjectList::shapes_of(const std::string& name) const {
  const std::vector<std::uint32_t>* slots = by_name_.find(name);
  if (slots == nullptr) return {};
  std::vector<std::uint32_t> out = *slots;
  std::sort(out.begin(), out.end());
  return out;
}

// The object's list of slots with `slot` added or taken out.
void ObjectList::index_slot(const std::string& id, std::uint32_t slot, bool add) {
  const std::string name = object_name(id);
  const std::vector<std::uint32_t>* now = by_name_.find(name);
  std::vector<std::uint32_t> next = now ? *now : std::vector<std::uint32_t>{};
  if (add) {
    next.push_back(slot);
  } else {
    next.erase(std::remove(next.begin(), next.end(), slot), next.end());
  }
  if (next.empty()) {
    by_name_.erase(name, &work_);
  } else {
    work_.entries += next.size();
    by_name_.set(name, std::move(next), &work_);
  }
}

void ObjectList::add(std::shared_ptr<const CollisionObject> o) {
  work_ = PersistentWork{};
  Vec3 lo, hi;
  object_world_box(*o, lo, hi);
  const std::ptrdiff_t same = find(o->id);
  if (same >= 0) {
    const auto slot = static_cast<std::uint32_t>(same);
    Vec3 old_lo, old_hi;
    object_world_box(*records_[slot], old_lo, old_hi);
    boxes_.erase(slot, old_lo, old_hi, &work_);
    boxes_.insert({lo, hi, slot}, &work_);
    records_.set(slot, std::move(o), &work_);
    return;
  }
  const auto slot = static_cast<std::uint32_t>(records_.size());
  index_slot(o->id, slot, true);
  boxes_.insert({lo, hi, slot}, &work_);
  records_.push_back(std::move(o), &work_);
}

// The shape of `slot` out; the last slot's shape moves into it (its index and box entry follow).
void ObjectList::remove_slot(std::uint32_t slot) {
  Vec3 lo, hi;
  object_world_box(*records_[slot], lo, hi);
  boxes_.erase(slot, lo, hi, &work_);
  index_slot(records_[slot]->id, slot, false);
  const auto last = static_cast<std::uint32_t>(records_.size() - 1);
  if (slot != last) {
    std::shared_ptr<const CollisionObject> moved = records_[last];
    object_world_box(*moved, lo, hi);
    boxes_.erase(last, lo, hi, &work_);
    boxes_.insert({lo, hi, slot}, &work_);
    index_slot(moved->id, last, false);
    index_slot(moved->id, slot, true);
    records_.set(slot, std::move(moved), &work_);
  }
  records_.pop_back(&work_);
}

bool ObjectList::remove(const std::string& shape_id) {
  work_ = PersistentWork{};
  const std::ptrdiff_t slot = find(shape_id);
  if (slot < 0) return false;
  remove_slot(static_cast<std::uint32_t>(slot));
  return true;
}

std::size_t ObjectList::remove_object(const std::string& name) {
  work_ = PersistentWork{};
  std::size_t removed = 0;
  // One at a time from the end: a removal moves only the last slot, never one still to remove
  // unless it is that one (then it is found again by id).
  for (std::vector<std::uint32_t> slots = shapes_of(name); !slots.empty(); slots = shapes_of(name)) {
    remove_slot(slots.back());
    ++removed;
  }
  return removed;
}

void ObjectList::clear() {
  records_.clear();
  by_name_.clear();
  boxes_.clear();
  work_ = PersistentWork{};
}

}  // namespace bvh_collision
