// A scan into the world: filters, insertion, distance field (session/scan_update.h).
#include "bvh_collision/session/scan_update.h"

#include "bvh_collision/world/object_filter.h"

namespace bvh_collision {

ScanUpdateResult update_scan(EnvironmentStore& store, const RobotCheckers& checkers, const std::vector<ScanPoint>& points,
                             const std::vector<ScanPoint>& no_return, const ScanPoint& origin, const double* state,
                             const Transform& root, const ScanUpdateOptions& options) {
  // The robot with what it carries, and the world's objects: points on a known object are not
  // voxels (it would be counted twice, and leave debris when it moves).
  const std::shared_ptr<const Environment> scene = store.snapshot();
  const std::shared_ptr<const CollisionChecker> carrying = checkers.for_snapshot(scene);
  FilteredScan filtered = carrying->filter_scan(state, points, origin, options.self_filter_padding, root, options.object_padding);
  filter_objects(scene->objects(), origin, options.object_padding, filtered);
  if (!no_return.empty()) {
    // A dark pixel's ray clears up to the robot where it passes through it, as a shadow's does.
    FilteredScan rays = carrying->filter_scan(state, no_return, origin, options.self_filter_padding, root, options.object_padding);
    filtered.clear_only.insert(filtered.clear_only.end(), rays.obstacles.begin(), rays.obstacles.end());
    filtered.clear_only.insert(filtered.clear_only.end(), rays.clear_only.begin(), rays.clear_only.end());
  }
  ScanUpdateResult result;
  result.stats = store.modify([&](Environment& env) {
    const std::uint64_t from = env.octree().revision();
    ScanStats stats = insert_scan(env.octree(), filtered.obstacles, filtered.clear_only, origin, options.scan);
    env.note_octree_changes(from, std::move(stats.flipped));  // the kept distance field follows them
    // The new map's distance field, here rather than in the first query, and before the snapshot
    // is published: a query that meets the new snapshot finds it kept (the snapshot shares it).
    if (options.distance_field && checkers.current()->prepare_distance_field(env, root)) {
      const auto work = env.octree_field_work();
      result.field_made = work.has_value() && env.octree().revision() != from;  // (else the kept one)
      if (work) result.field = *work;
    }
    return stats;
  });
  result.on_robot = filtered.on_robot;
  result.shadowed = filtered.shadowed;
  result.on_objects = filtered.on_objects;
  return result;
}

}  // namespace bvh_collision
