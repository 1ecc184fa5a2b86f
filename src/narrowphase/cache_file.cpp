#include "bvh_collision/narrowphase/cache_file.h"

#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <unistd.h>

namespace bvh_collision {

void ContentHash::shapes(const std::vector<BodyShape>& shapes) {
  for (const BodyShape& s : shapes) {
    transform(s.origin);
    value(s.shape.mesh != nullptr);
    if (s.shape.mesh != nullptr) {
      const Bvh<Obb>& mesh = *s.shape.mesh;
      value(mesh.closed());
      value(mesh.triangles().size());
      for (const Triangle& t : mesh.triangles()) {
        for (int k = 0; k < 3; ++k) vec(t[k]);
      }
    } else {
      value(static_cast<std::uint8_t>(s.shape.primitive.kind));
      vec(s.shape.primitive.half);
      value(s.shape.primitive.radius);
      value(s.shape.primitive.half_length);
    }
  }
}

void seal(std::string& bytes) {
  ContentHash sum;
  sum.bytes(bytes.data(), bytes.size());
  put_value(bytes, sum.h);
}

bool sealed(const std::string& bytes) {
  std::uint64_t stored = 0;
  if (bytes.size() < sizeof stored) return false;
  std::size_t at = bytes.size() - sizeof stored;
  ContentHash sum;
  sum.bytes(bytes.data(), at);
  return take_value(bytes, at, stored) && stored == sum.h;
}

std::string cache_file(const std::string& folder, std::uint64_t key, const char* extension) {
  char name[24];
  std::snprintf(name, sizeof name, "%016llx", static_cast<unsigned long long>(key));
  return (std::filesystem::path(folder) / (std::string(name) + extension)).string();
}

std::optional<std::string> read_cache_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

bool replace_cache_file(const std::string& path, const std::string& bytes) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  // A name of this process and this write: two threads or processes writing one file never share it.
  static std::atomic<unsigned> writes{0};
  const std::string temporary = path + ".tmp" + std::to_string(::getpid()) + "." + std::to_string(writes++);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()))) return false;
  }
  std::error_code renamed;
  std::filesystem::rename(temporary, path, renamed);  // readers see the old file or the whole new one
  if (renamed) std::filesystem::remove(temporary, ec);
  return !renamed;
}

}  // namespace bvh_collision
