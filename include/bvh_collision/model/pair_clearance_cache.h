// Clearance grids kept on disk by content, beside the link proxies (narrowphase/cache_file.h).
// A robot's grids take most of its start-up (pr2: 5-6 s of a 6 s construction on one core; under
// the sanitizers ten times that) and depend only on what the key covers, so a later start reads
// them in milliseconds. The key is a 64-bit FNV-1a hash of every number the build reads: each
// link's shapes, padding and motion rates, every joint (type, links, origin, axis, limits,
// variable, mimic), the checked pairs, the cell budget and the builder's version. A file is used
// only when its key, format and checksum agree and every grid has the shape the build gives its
// pair (coarse or refined); the pyramids are rebuilt from the cells. Any other file is rebuilt
// and replaced.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "bvh_collision/model/pair_clearance.h"

namespace bvh_collision {

// Bump when PairClearance::build changes what it builds: files of another version are rebuilt.
constexpr std::uint32_t kPairClearanceBuildVersion = 1;

std::uint64_t pair_clearance_key(const RobotCollisionModel& model, std::size_t max_cells);

// The file that holds the grids of `key` in `folder`.
std::string pair_clearance_file(const std::string& folder, std::uint64_t key);

// The grids stored under `key` for `model`, or nothing (no file, or one that does not check out).
std::optional<PairClearance> read_cached_pair_clearance(const std::string& folder, std::uint64_t key,
                                                        const RobotCollisionModel& model, std::size_t max_cells);

// Stores `grids` under `key` (creating the folder); false when they cannot be written.
bool write_cached_pair_clearance(const std::string& folder, std::uint64_t key, const PairClearance& grids);

// PairClearance::build(model, max_cells), read from `folder` when it holds the grids and stored
// there when built (an empty folder: built, nothing stored).
PairClearance cached_or_built_pair_clearance(const RobotCollisionModel& model, std::size_t max_cells,
                                             const std::string& folder);

}  // namespace bvh_collision
