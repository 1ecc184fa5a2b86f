#include "bvh_collision/narrowphase/link_proxy_cache.h"

#include <cmath>
#include <cstring>
#include <unordered_map>

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

bool same_shapes(const std::vector<BodyShape>& a, const std::vector<BodyShape>& b) {
  if (a.size() != b.size()) return false;
  // Bit for bit, as the key hashes them (a -0.0 is not 0.0 there either).
  const auto same = [](const auto& x, const auto& y) { return std::memcmp(&x, &y, sizeof x) == 0; };
  const auto same_vec = [&](const Vec3& x, const Vec3& y) { return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]); };
  for (std::size_t i = 0; i < a.size(); ++i) {
    const BodyShape &s = a[i], &t = b[i];
    for (int r = 0; r < 3; ++r) {
      if (!same_vec(s.origin.R.row(r).transpose(), t.origin.R.row(r).transpose())) return false;
    }
    if (!same_vec(s.origin.t, t.origin.t) || (s.shape.mesh == nullptr) != (t.shape.mesh == nullptr)) return false;
    if (s.shape.mesh == nullptr) {
      const Primitive &p = s.shape.primitive, &q = t.shape.primitive;
      if (p.kind != q.kind || !same_vec(p.half, q.half) || !same(p.radius, q.radius) || !same(p.half_length, q.half_length)) return false;
      continue;
    }
    if (s.shape.mesh == t.shape.mesh) continue;
    const auto& x = s.shape.mesh->triangles();
    const auto& y = t.shape.mesh->triangles();
    if (s.shape.mesh->closed() != t.shape.mesh->closed() || x.size() != y.size()) return false;
    for (std::size_t k = 0; k < x.size(); ++k) {
      for (int v = 0; v < 3; ++v) {
        if (!same_vec(x[k][v], y[k][v])) return false;
      }
    }
  }
  return true;
}

std::vector<std::size_t> first_alike(const std::vector<std::vector<BodyShape>>& links) {
  std::vector<std::size_t> first(links.size());
  std::unordered_multimap<std::uint64_t, std::size_t> by_key;  // links with shapes, by their content's hash
  for (std::size_t l = 0; l < links.size(); ++l) {
    first[l] = l;
    if (links[l].empty()) continue;
    const std::uint64_t key = link_proxy_key(links[l], 0.0);
    const auto [from, to] = by_key.equal_range(key);
    for (auto it = from; it != to; ++it) {
      if (same_shapes(links[it->second], links[l])) {
        first[l] = it->second;
        break;
      }
    }
    if (first[l] == l) by_key.emplace(key, l);
  }
  return first;
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
