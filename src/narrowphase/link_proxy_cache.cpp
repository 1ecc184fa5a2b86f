#include "bvh_collision/narrowphase/link_proxy_cache.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>


namespace bvh_collision {
namespace {

constexpr char kMagic[8] = {'B', 'V', 'H', 'P', 'R', 'O', 'X', 'Y'};
constexpr std::uint64_t kMostSpheres = std::uint64_t(1) << 26;  // far beyond any link (pr2: 105,893 at 10 mm)

// FNV-1a, 64 bits, over bytes.
struct Fnv {
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
};

// Appends `v`'s bytes to `out` (the machine's byte order: the key names the machine's files only).
template <class T>
void put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
bool take(const std::string& in, std::size_t& at, T& v) {
  if (in.size() - at < sizeof v) return false;
  std::memcpy(&v, in.data() + at, sizeof v);
  at += sizeof v;
  return true;
}

}  // namespace

// The file: magic, version, key, level, Hausdorff bound, leaf count, sphere count, the spheres
// (centre, radius, skip), then a checksum of everything before it.
struct LinkProxyFile {
  static std::string encode(const LinkProxy& p, std::uint64_t key) {
    std::string out(kMagic, sizeof kMagic);
    put(out, kLinkProxyBuildVersion);
    put(out, key);
    put(out, p.level_);
    put(out, p.hausdorff_);
    put(out, static_cast<std::uint64_t>(p.leaves_));
    put(out, static_cast<std::uint64_t>(p.spheres_.size()));
    for (const ProxySphere& s : p.spheres_) {
      for (int k = 0; k < 3; ++k) put(out, s.center[k]);
      put(out, s.radius);
      put(out, s.skip);
    }
    Fnv sum;
    sum.bytes(out.data(), out.size());
    put(out, sum.h);
    return out;
  }

  // The proxy, when the bytes are one written for `key` and hang together: every sphere finite
  // and its subtree within the array, the leaves counted as stored, the bound within the level.
  static std::optional<LinkProxy> decode(const std::string& in, std::uint64_t key) {
    if (in.size() < sizeof kMagic + sizeof(std::uint64_t) || std::memcmp(in.data(), kMagic, sizeof kMagic) != 0) {
      return std::nullopt;
    }
    Fnv sum;
    sum.bytes(in.data(), in.size() - sizeof(std::uint64_t));
    std::size_t at = sizeof kMagic;
    std::uint32_t version = 0;
    std::uint64_t stored_key = 0, leaves = 0, count = 0, checksum = 0;
    LinkProxy p;
    if (!take(in, at, version) || version != kLinkProxyBuildVersion || !take(in, at, stored_key) || stored_key != key ||
        !take(in, at, p.level_) || !take(in, at, p.hausdorff_) || !take(in, at, leaves) || !take(in, at, count) ||
        count == 0 || count > kMostSpheres) {
      return std::nullopt;
    }
    if (in.size() != at + count * (4 * sizeof(double) + sizeof(std::int32_t)) + sizeof checksum) return std::nullopt;
    p.spheres_.resize(count);
    std::size_t leaf_count = 0;
    for (std::size_t i = 0; i < count; ++i) {
      ProxySphere& s = p.spheres_[i];
      for (int k = 0; k < 3; ++k) take(in, at, s.center[k]);
      take(in, at, s.radius);
      take(in, at, s.skip);
      const bool subtree_fits = s.skip > static_cast<std::int64_t>(i) && static_cast<std::uint64_t>(s.skip) <= count;
      if (!s.center.allFinite() || !std::isfinite(s.radius) || s.radius < 0.0 || !subtree_fits) return std::nullopt;
      leaf_count += s.skip == static_cast<std::int32_t>(i + 1);
    }
    take(in, at, checksum);
    const bool bound_fits = std::isfinite(p.level_) && p.level_ > 0.0 && p.hausdorff_ >= 0.0 && p.hausdorff_ <= 0.5 * p.level_;
    if (checksum != sum.h || leaf_count != leaves || !bound_fits ||
        static_cast<std::uint64_t>(p.spheres_.front().skip) != count) {
      return std::nullopt;
    }
    p.leaves_ = leaf_count;
    return p;
  }
};

std::uint64_t link_proxy_key(const std::vector<BodyShape>& shapes, double level) {
  Fnv h;
  h.value(kLinkProxyBuildVersion);
  h.value(level);
  for (const BodyShape& s : shapes) {
    for (int r = 0; r < 3; ++r) h.vec(s.origin.R.row(r).transpose());
    h.vec(s.origin.t);
    h.value(s.shape.mesh != nullptr);
    if (s.shape.mesh != nullptr) {
      const Bvh<Obb>& mesh = *s.shape.mesh;
      h.value(mesh.closed());
      h.value(mesh.triangles().size());
      for (const Triangle& t : mesh.triangles()) {
        for (int k = 0; k < 3; ++k) h.vec(t[k]);
      }
    } else {
      h.value(static_cast<std::uint8_t>(s.shape.primitive.kind));
      h.vec(s.shape.primitive.half);
      h.value(s.shape.primitive.radius);
      h.value(s.shape.primitive.half_length);
    }
  }
  return h.h;
}

std::string link_proxy_file(const std::string& folder, std::uint64_t key) {
  char name[32];
  std::snprintf(name, sizeof name, "%016llx.proxy", static_cast<unsigned long long>(key));
  return (std::filesystem::path(folder) / name).string();
}

std::optional<LinkProxy> read_cached_link_proxy(const std::string& folder, std::uint64_t key) {
  std::ifstream in(link_proxy_file(folder, key), std::ios::binary);
  if (!in) return std::nullopt;
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return LinkProxyFile::decode(bytes, key);
}

bool write_cached_link_proxy(const std::string& folder, std::uint64_t key, const LinkProxy& proxy) {
  if (proxy.empty()) return false;
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  const std::string path = link_proxy_file(folder, key), temporary = path + ".tmp" + std::to_string(::getpid());
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    const std::string bytes = LinkProxyFile::encode(proxy, key);
    if (!out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()))) return false;
  }
  std::error_code renamed;
  std::filesystem::rename(temporary, path, renamed);  // readers see the old file or the whole new one
  if (renamed) std::filesystem::remove(temporary, ec);
  return !renamed;
}

}  // namespace bvh_collision
