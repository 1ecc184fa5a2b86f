// Work over a scan's points in contiguous chunks, one per core: shared by the filters that split
// a scan before insertion (the self filter, the known-object filter).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "bvh_collision/geometry/thread_pool.h"

namespace bvh_collision::detail {

// fn(begin, end, part) over contiguous chunks of [0, n), one per core (a thread pays for itself
// only with a few thousand points); the parts come back in order.
template <class Part, class Fn>
std::vector<Part> in_chunks(std::size_t n, Fn&& fn) {
  ThreadPool& pool = ThreadPool::shared();
  const std::size_t chunks = std::clamp<std::size_t>(n / 4096, 1, pool.capacity());
  std::vector<Part> parts(chunks);
  const std::size_t chunk = (n + chunks - 1) / chunks;
  pool.for_each(chunks, 1, [&](std::size_t c) {
    const std::size_t begin = std::min(n, c * chunk), end = std::min(n, begin + chunk);
    fn(begin, end, parts[c]);
  });
  return parts;
}

}  // namespace bvh_collision::detail
