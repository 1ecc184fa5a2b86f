// The file mechanics of what is built from a robot and kept on disk by content (link proxies:
// narrowphase/link_proxy_cache.h; clearance grids: model/pair_clearance_cache.h): a 64-bit FNV-1a
// hash for keys and checksums, values in the machine's byte order (a key names one machine's
// files only), a file sealed by the checksum of its bytes, and a replacement that readers see
// whole or not at all.
#pragma once

#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/narrowphase/shape.h"

namespace bvh_collision {

// FNV-1a, 64 bits, over bytes.
struct ContentHash {
  std::uint64_t h = 1469598103934665603ull;
  void bytes(const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  }
  template <class T>
  void value(const T& v) {
    bytes(&v, sizeof v);
  }
  void vec(const Vec3& v) {
    for (int k = 0; k < 3; ++k) value(v[k]);
  }
  void transform(const Transform& t) {
    for (int r = 0; r < 3; ++r) vec(t.R.row(r).transpose());
    vec(t.t);
  }
  // Every number that describes the shapes: origins, primitives, each mesh's triangles and
  // whether it is closed.
  void shapes(const std::vector<BodyShape>& shapes);
};

// Appends `v`'s bytes to `out`.
template <class T>
void put_value(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

// Reads the next value from `in` at `at`; false (and `at` unchanged) when too few bytes are left.
template <class T>
bool take_value(const std::string& in, std::size_t& at, T& v) {
  if (at > in.size() || in.size() - at < sizeof v) return false;
  std::memcpy(&v, in.data() + at, sizeof v);
  at += sizeof v;
  return true;
}

// Appends the checksum of `bytes` to it.
void seal(std::string& bytes);
// Whether `bytes` ends in the checksum of what comes before it.
bool sealed(const std::string& bytes);

// `folder`/`key` in 16 hex digits + `extension` (".proxy", ".grids").
std::string cache_file(const std::string& folder, std::uint64_t key, const char* extension);
// The whole file, or nothing when it cannot be read.
std::optional<std::string> read_cache_file(const std::string& path);
// Writes `bytes` to `path` (creating its folder) under a temporary name, then renames it over
// `path`; false when it cannot be written (a cache that cannot be written only costs time).
bool replace_cache_file(const std::string& path, const std::string& bytes);

}  // namespace bvh_collision
