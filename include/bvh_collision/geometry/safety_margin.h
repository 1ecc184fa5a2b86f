// The one safety-margin policy of the library: where a conservative test compares computed
// floating-point quantities, it adds one of these margins, so that rounding can never turn
// "touching" into "apart" (a false negative). Every margin in the code is one of these names.
//
// Why they hold. A double operation rounds with relative error at most u = 2^-53 ~ 1.1e-16.
// The bounding-volume tests (bvh/volumes/) evaluate sums of at most ~40 products whose terms are
// each bounded by a `scale` the test computes (sum of the absolute centres, extents and
// distances involved); the rounding error of such an expression is at most 40 u scale (1 + 40 u)
// < 5e-15 scale. kVolumeMargin * scale = 1e-12 scale is 200 times that, so a test that rejects
// only beyond `padding + kVolumeMargin * scale` never rejects a pair that touches in exact
// arithmetic. (Such tests only prune: a false "overlap" costs time, never an answer.)
//
// kPoseMargin covers quantities carried through a chain of poses (a world box from a link pose,
// a bounding sphere carried to the world): the kinematic chain composes up to ~100 rotations,
// each adding a few u of relative error to every coordinate, so 1e-9 of the coordinates'
// magnitude (plus 1e-9 m absolute) is again orders above the error it covers.
//
// Margins never enter the exact answers: the triangle and predicate tests decide with exact
// arithmetic (geometry/predicates.h); margins only make the pruning in front of them safe.
#pragma once

#include <cmath>

namespace bvh_collision {

// Relative margin of the bounding-volume tests (see above).
constexpr double kVolumeMargin = 1e-12;

// Added to |R| in the separating-axis tests: near-parallel axes make the cross axes degenerate,
// and this keeps their projection radii from collapsing below the rounding of the products.
constexpr double kAxisEpsilon = 1e-12;

// Relative (and absolute, in metres) margin of bounds carried through poses.
constexpr double kPoseMargin = 1e-9;

// A radius (or any non-negative bound) grown by the volume margin: the result still bounds the
// exact quantity the rounded `r` was computed for.
inline double grown_radius(double r) { return r * (1 + kVolumeMargin) + kVolumeMargin; }

// The margin of a bound whose coordinates have magnitude up to `magnitude` after a pose chain.
inline double pose_margin(double magnitude) { return kPoseMargin * (1.0 + std::abs(magnitude)); }

// A motion's growth bound (how far a link moves over an interval, computed from rounded speeds)
// grown by the relative error of that computation and the pose margin of its magnitude.
inline double grown_growth(double g) { return g * (1.0 + kPoseMargin) + pose_margin(g); }

// An upper bound for a distance query that must not miss a distance equal to `limit`: above it by
// the pose margin's relative part and the volume margin's absolute one (the query may stop early
// at its bound; a distance at `limit` exactly is then still found).
inline double query_limit_above(double limit) { return limit * (1.0 + kPoseMargin) + kVolumeMargin; }

}  // namespace bvh_collision
