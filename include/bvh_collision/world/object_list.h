// The collision objects of one world snapshot, kept so that a change costs log n, not n: every
// shape a record in slots 0..size()-1 (what queries walk), the shapes of each object by its name,
// and a loose octree of the shapes' world boxes (what a query near a link asks). All three are
// persistent (persistent_vector.h, persistent_map.h): a copy shares them, and a change copies the
// nodes on one path of each, so that a snapshot a reader holds never changes under it.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bvh_collision/world/persistent_map.h"
#include "bvh_collision/world/persistent_vector.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct CollisionObject;

// A world box that holds the shape whatever the rounding of its pose (a margin above it).
void object_world_box(const CollisionObject& o, Vec3& lo, Vec3& hi);

// The loose octree: a node's cell is a cube of half-size h around its centre; it keeps the boxes
// no larger than its cell whose centre lies in the cell (so they lie within the cell grown by h on
// every side), each as deep as its size allows. A box reaching beyond the root's cube stays at
// the root. Persistent as the others: an insert copies the nodes from the root to its node.
class ObjectBoxTree {
 public:
  struct Entry {
    Vec3 lo, hi;
    std::uint32_t slot;
  };
  // Half the root cube's edge (m): boxes farther out than 1.3e5 m sit at the root.
  static constexpr double kRootHalf = 131072.0;
  static constexpr int kMaxDepth = 30;

  void insert(const Entry& e, PersistentWork* work = nullptr);
  // Removes the entry of `slot` whose box is [lo, hi] (as inserted); false when absent.
  bool erase(std::uint32_t slot, const Vec3& lo, const Vec3& hi, PersistentWork* work = nullptr);
  void clear() { root_ = nullptr; }
  bool same_as(const ObjectBoxTree& o) const { return root_ == o.root_; }

  // Calls f(entry) for every entry whose box meets [lo, hi].
  template <class F>
  void for_each_meeting(const Vec3& lo, const Vec3& hi, F&& f) const {
    if (root_) visit(*root_, Vec3::Zero(), kRootHalf, lo, hi, f);
  }

 private:
  struct Node {
    std::array<std::shared_ptr<const Node>, 8> child;
    std::vector<Entry> items;
  };
  using NodePtr = std::shared_ptr<const Node>;

  static bool meets(const Vec3& alo, const Vec3& ahi, const Vec3& blo, const Vec3& bhi) {
    return (alo.array() <= bhi.array()).all() && (blo.array() <= ahi.array()).all();
  }
  template <class F>
  static void visit(const Node& n, const Vec3& centre, double half, const Vec3& lo, const Vec3& hi, F& f) {
    for (const Entry& e : n.items) {
      if (meets(e.lo, e.hi, lo, hi)) f(e);
    }
    const double h = 0.5 * half;
    for (int k = 0; k < 8; ++k) {
      if (!n.child[k]) continue;
      const Vec3 c = child_centre(centre, h, k);
      // A child's boxes lie within its cell grown by its half-size on every side.
      if (meets(c - Vec3::Constant(2.0 * h), c + Vec3::Constant(2.0 * h), lo, hi)) visit(*n.child[k], c, h, lo, hi, f);
    }
  }
  static Vec3 child_centre(const Vec3& centre, double h, int k) {
    return Vec3(centre.x() + ((k & 4) ? h : -h), centre.y() + ((k & 2) ? h : -h), centre.z() + ((k & 1) ? h : -h));
  }
  static int depth_for(const Vec3& lo, const Vec3& hi);
  static NodePtr inserted(const NodePtr& node, const Vec3& centre, double half, int depth, const Entry& e, PersistentWork* work);
  static NodePtr erased(const NodePtr& node, const Vec3& centre, double half, int depth, std::uint32_t slot, const Vec3& mid,
                        bool& found, PersistentWork* work);

  NodePtr root_;
};

// The shapes of a snapshot's collision objects.
class ObjectList {
  using Records = PersistentVector<std::shared_ptr<const CollisionObject>>;

 public:
  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = CollisionObject;
    using difference_type = std::ptrdiff_t;
    using pointer = const CollisionObject*;
    using reference = const CollisionObject&;
    explicit const_iterator(Records::const_iterator it) : it_(it) {}
    reference operator*() const { return **it_; }
    pointer operator->() const { return it_->get(); }
    const_iterator& operator++() {
      ++it_;
      return *this;
    }
    bool operator==(const const_iterator& o) const { return it_ == o.it_; }
    bool operator!=(const const_iterator& o) const { return it_ != o.it_; }

   private:
    Records::const_iterator it_;
  };

  ObjectList() = default;
  // The objects in this order (test fixtures and lists built whole).
  explicit ObjectList(const std::vector<CollisionObject>& objects);

  std::size_t size() const { return records_.size(); }
  bool empty() const { return records_.empty(); }
  const CollisionObject& operator[](std::size_t slot) const { return *records_[slot]; }
  const_iterator begin() const { return const_iterator(records_.begin()); }
  const_iterator end() const { return const_iterator(records_.end()); }

  // The slot of the shape with this id ("id", or "id#k" of an object of several), or -1.
  std::ptrdiff_t find(const std::string& shape_id) const;
  // The slots of every shape of the object `name` (its shapes "name" or "name#k"), ascending.
  std::vector<std::uint32_t> shapes_of(const std::string& name) const;
  bool has_object(const std::string& name) const { return by_name_.find(name) != nullptr; }
  // This list or an unchanged copy of it (the same nodes): the same objects in the same slots.
  bool same_as(const ObjectList& o) const { return records_.same_as(o.records_) && by_name_.same_as(o.by_name_) && boxes_.same_as(o.boxes_); }

  // Calls f(slot) for every shape whose world box (object_world_box) meets [lo, hi], in no order.
  template <class F>
  void for_each_meeting(const Vec3& lo, const Vec3& hi, F&& f) const {
    boxes_.for_each_meeting(lo, hi, [&](const ObjectBoxTree::Entry& e) { f(e.slot); });
  }
  // The same, with each shape's box: f(entry) (a query for a whole robot, then per link).
  template <class F>
  void for_each_box_meeting(const Vec3& lo, const Vec3& hi, F&& f) const {
    boxes_.for_each_meeting(lo, hi, f);
  }

  // Adds the shape, or replaces the one of its id (keeping its slot).
  void add(std::shared_ptr<const CollisionObject> o);
  // Removes the shape of this id (the last slot's shape takes its slot); false when absent.
  bool remove(const std::string& shape_id);
  // Removes every shape of the object `name`; how many there were.
  std::size_t remove_object(const std::string& name);
  void clear();

  // What the last change copied, summed over the three structures.
  const PersistentWork& last_work() const { return work_; }

 private:
  void index_slot(const std::string& id, std::uint32_t slot, bool add);
  void remove_slot(std::uint32_t slot);

  Records records_;
  PersistentMap<std::string, std::vector<std::uint32_t>> by_name_;  // object name -> its shapes' slots
  ObjectBoxTree boxes_;
  PersistentWork work_;
};

}  // namespace bvh_collision
