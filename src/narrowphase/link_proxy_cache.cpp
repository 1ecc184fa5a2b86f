#include "bvh_collision/narrowphase/link_proxy_cache.h"

#include <cmath>
#include <cstring>

#include "bvh_collision/narrowphase/cache_file.h"

namespace bvh_collision {
namespace {

constexpr char kMagic[8] = {'B', 'V', 'H', 'P', 'R', 'O', 'X', 'Y'};
constexpr std::uint64_t kMostSpheres = std::uint64_t(1) << 26;  // far beyond any link (pr2: 105,893 at 10 mm)

}  // namespace

// The file: magic, version, key, level, Hausdorff bound, leaf count, sphere count, the spheres
// (centre, radius, skip), then a checksum of everything before it.
struct LinkProxyFile {
  static std::string encode(const LinkProxy& p, std::uint64_t key) {
    std::string out(kMagic, sizeof kMagic);
    put_value(out, kLinkProxyBuildVersion);
    put_value(out, key);
    put_value(out, p.level_);
    put_value(out, p.hausdorff_);
    put_value(out, static_cast<std::uint64_t>(p.leaves_));
    put_value(out, static_cast<std::uint64_t>(p.spheres_.size()));
    for (const ProxySphere& s : p.spheres_) {
      for (int k = 0; k < 3; ++k) put_value(out, s.center[k]);
      put_value(out, s.radius);
      put_value(out, s.skip);
    }
    seal(out);
    return out;
  }

  // The proxy, when the bytes are one written for `key` and hang together: every sphere finite
  // and its subtree within the array, the leaves counted as stored, the bound within the level.
  static std::optional<LinkProxy> decode(const std::string& in, std::uint64_t key) {
    if (in.size() < sizeof kMagic + sizeof(std::uint64_t) || std::memcmp(in.data(), kMagic, sizeof kMagic) != 0 ||
        !sealed(in)) {
      return std::nullopt;
    }
    std::size_t at = sizeof kMagic;
    std::uint32_t version = 0;
    std::uint64_t stored_key = 0, leaves = 0, count = 0;
    LinkProxy p;
    if (!take_value(in, at, version) || version != kLinkProxyBuildVersion || !take_value(in, at, stored_key) || stored_key != key ||
        !take_value(in, at, p.level_) || !take_value(in, at, p.hausdorff_) || !take_value(in, at, leaves) || !take_value(in, at, count) ||
        count == 0 || count > kMostSpheres) {
      return std::nullopt;
    }
    if (in.size() != at + count * (4 * sizeof(double) + sizeof(std::int32_t)) + sizeof(std::uint64_t)) return std::nullopt;
    p.spheres_.resize(count);
    std::size_t leaf_count = 0;
    for (std::size_t i = 0; i < count; ++i) {
      ProxySphere& s = p.spheres_[i];
      for (int k = 0; k < 3; ++k) take_value(in, at, s.center[k]);
      take_value(in, at, s.radius);
      take_value(in, at, s.skip);
      const bool subtree_fits = s.skip > static_cast<std::int64_t>(i) && static_cast<std::uint64_t>(s.skip) <= count;
      if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius < 0.0 || !subtree_fits) return std::nullopt;
      leaf_count += s.skip == static_cast<std::int32_t>(i + 1);
    }
    const bool bound_fits = std::isfinite(p.level_) && p.level_ > 0.0 && p.hausdorff_ >= 0.0 && p.hausdorff_ <= 0.5 * p.level_;
    if (leaf_count != leaves || !bound_fits ||
        static_cast<std::uint64_t>(p.spheres_.front().skip) != count) {
      return std::nullopt;
    }
    p.leaves_ = leaf_count;
    return p;
  }
};

std::uint64_t link_proxy_key(const std::vector<BodyShape>& shapes, double level) {
  ContentHash h;
  h.value(kLinkProxyBuildVersion);
  h.value(level);
  h.shapes(shapes);
  return h.h;
}

std::string link_proxy_file(const std::string& folder, std::uint64_t key) { return cache_file(folder, key, ".proxy"); }

std::optional<LinkProxy> read_cached_link_proxy(const std::string& folder, std::uint64_t key) {
  const std::optional<std::string> bytes = read_cache_file(link_proxy_file(folder, key));
  if (!bytes) return std::nullopt;
  return LinkProxyFile::decode(*bytes, key);
}

bool write_cached_link_proxy(const std::string& folder, std::uint64_t key, const LinkProxy& proxy) {
  return !proxy.empty() && replace_cache_file(link_proxy_file(folder, key), LinkProxyFile::encode(proxy, key));
}

}  // namespace bvh_collision
