#include "bvh_collision/geometry/simd_path.h"

#include <stdexcept>
#include <string>

namespace bvh_collision {

bool avx2_available() {
#if defined(__x86_64__) || defined(__i386__)
  static const bool available = __builtin_cpu_supports("avx2");
  return available;
#else
  return false;
#endif
}

SimdPath resolve_simd_path(SimdPath path, const char* what) {
  if (path == SimdPath::kAuto) return avx2_available() ? SimdPath::kAvx2 : SimdPath::kGeneric;
  if (path == SimdPath::kAvx2 && !avx2_available()) throw std::runtime_error(std::string(what) + ": this CPU has no AVX2");
  return path;
}

}  // namespace bvh_collision
