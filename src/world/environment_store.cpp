// EnvironmentStore's pinned versions (world/environment_store.h).
#include "bvh_collision/world/environment_store.h"

#include <algorithm>
#include <string>
#include <vector>

namespace bvh_collision {

void EnvironmentStore::drop_expired(Clock::time_point now) {
  for (auto it = pins_.begin(); it != pins_.end();) {
    it = it->second.expires < now ? pins_.erase(it) : std::next(it);
  }
}

EnvironmentStore::Pin EnvironmentStore::pin(Clock::duration timeout, Clock::time_point now) {
  if (timeout <= Clock::duration::zero()) throw std::invalid_argument("a pin's timeout must be positive");
  std::lock_guard<std::mutex> pins(pins_mutex_);
  drop_expired(now);
  Pin out;
  {
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    out = {version_, current_};
  }
  Held& held = pins_[out.version];  // pinned again: the same snapshot, the later expiry
  held.snapshot = out.snapshot;
  held.timeout = std::max(held.timeout, timeout);
  held.expires = std::max(held.expires, now + timeout);
  return out;
}

std::shared_ptr<const Environment> EnvironmentStore::pinned(std::uint64_t version, Clock::time_point now,
                                                            const std::string& parameter) {
  std::lock_guard<std::mutex> pins(pins_mutex_);
  const auto it = pins_.find(version);
  if (it == pins_.end() || it->second.expires < now) {
    if (it != pins_.end()) pins_.erase(it);
    throw PinError("world version " + std::to_string(version) + " is not pinned: it was never pinned, was released, or " +
                   "went unused for longer than " + parameter + " allows");
  }
  it->second.expires = now + it->second.timeout;
  return it->second.snapshot;
}

bool EnvironmentStore::release(std::uint64_t version) {
  std::lock_guard<std::mutex> pins(pins_mutex_);
  return pins_.erase(version) > 0;
}

std::size_t EnvironmentStore::pins(Clock::time_point now) {
  std::lock_guard<std::mutex> pins(pins_mutex_);
  drop_expired(now);
  return pins_.size();
}

std::size_t EnvironmentStore::pinned_extra_bytes() const {
  std::vector<const Octree*> trees;
  std::shared_ptr<const Environment> current = snapshot();
  std::lock_guard<std::mutex> pins(pins_mutex_);
  if (pins_.empty()) return 0;
  // (The snapshots stay alive while the lock is held: the map holds them. The fields are held
  // here: a query on a pinned snapshot may replace the field that snapshot keeps.)
  trees.push_back(&current->octree());
  // The fields the map keeps anyway: the current one and the pool the next is made from.
  std::vector<std::shared_ptr<const OctreeDistanceField>> held = current->pooled_octree_fields();
  held.push_back(current->held_octree_field());
  const std::size_t map_fields = held.size();
  for (const auto& [version, pinned] : pins_) {
    trees.push_back(&pinned.snapshot->octree());
    held.push_back(pinned.snapshot->held_octree_field());
  }
  // The octree pages and the field pages the pins hold that the current map does not (copy on
  // write both: what changed since).
  std::vector<const OctreeDistanceField*> fields;
  for (const auto& f : held) fields.push_back(f.get());
  const std::size_t all = OctreeDistanceField::distinct_memory_bytes(fields);
  fields.resize(map_fields);
  const std::size_t field_bytes = all - OctreeDistanceField::distinct_memory_bytes(fields);
  return Octree::distinct_memory_bytes(trees) - current->octree().memory_bytes() + field_bytes;
}

}  // namespace bvh_collision
