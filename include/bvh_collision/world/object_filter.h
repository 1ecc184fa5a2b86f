// Known objects are not voxels: a scan's points on the environment's collision objects are taken
// out before insertion, as the self filter takes out the robot's own.
#pragma once

#include <vector>

#include "bvh_collision/world/environment.h"
#include "bvh_collision/world/filtered_scan.h"

namespace bvh_collision {

// Moves the points of `scan.obstacles` that lie on a collision object or within `padding` of one
// (inside a closed mesh or a primitive counts) to `scan.clear_only`, counted in on_objects; the
// rest keep their order. The sensor saw through the space in front of the object, so such a
// point's ray still clears it, up to `padding` before the ray first meets an object (an object
// that holds the sensor within padding cuts no ray). A point behind an object is kept: the map of
// objects may be out of date, and what the camera saw there is real. Objects are in the scan's
// frame (the world). Uses every core. Throws std::invalid_argument for a padding that is not
// finite and >= 0 or a sensor origin that is not finite.
void filter_objects(const ObjectList& objects, const ScanPoint& sensor, double padding,
                    FilteredScan& scan);

}  // namespace bvh_collision
