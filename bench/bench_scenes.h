// The scenes the benchmarks' sensors see: a depth camera's view of a table (the environment
// benchmark's insertion and octree tables, the service benchmark's panda camera) and the demo's
// pillar (its motion and live-world tables, the service benchmark's demo camera).
#pragma once

#include <functional>
#include <random>
#include <vector>

#include "bvh_collision/octree/scan.h"

namespace bvh_collision::environment_bench {

// The distance along a ray (unit direction) to something more in the scene than the boxes, if
// nearer than `best`: the robot, for the self-filter figures.
using ExtraHit = std::function<double(const Vec3& origin, const Vec3& direction, double best)>;

// A depth camera (600 x 500 rays unless told, 70 x 58 degrees) above and behind a robot, looking
// at a table with boxes on it, a floor and a wall; 2 mm depth noise drawn from `seed`; rays that
// hit nothing return NaN.
std::vector<ScanPoint> table_scene(const Vec3& camera, const ExtraHit& extra = nullptr, int width = 600, int height = 500,
                                   unsigned seed = 7);
// The demo's pillar: the surface of a 12 x 12 x 80 cm box at 1 cm (in the demo arm's root frame).
std::vector<ScanPoint> demo_pillar();
// The points with Gaussian noise of `sigma` on each axis, a new draw each call: a camera's clouds
// of a still scene, whose voxels at the surface flip from cloud to cloud as a real camera's do.
std::vector<ScanPoint> noisy_copy(const std::vector<ScanPoint>& points, float sigma, std::mt19937_64& rng);

}  // namespace bvh_collision::environment_bench
