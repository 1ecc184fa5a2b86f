// The shapes of the grids PairClearance::build fills (src/model/pair_clearance.cpp), for the
// grid cache (model/pair_clearance_cache.h) to check a stored grid against what the build gives
// its pair. Not API.
#pragma once

#include <cstddef>
#include <vector>

#include "bvh_collision/model/pair_clearance.h"

namespace bvh_collision {
namespace detail {

// One empty grid (no cells filled) for every checked pair of `model` the build considers: its
// variables, range and cells at the budget `max_cells`, in pair order.
std::vector<PairClearanceGrid> clearance_grid_shapes(const RobotCollisionModel& model, std::size_t max_cells);

// The finer shape `coarse` is refined to (PairClearance::kRefinedCells times the budget); dims 0
// when there is none.
PairClearanceGrid refined_grid_shape(const RobotCollisionModel& model, const PairClearanceGrid& coarse,
                                     std::size_t max_cells);

// Fills g.pyramid from g.bound.
void build_pyramid(PairClearanceGrid& g);

}  // namespace detail
}  // namespace bvh_collision
