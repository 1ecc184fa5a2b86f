// Which SIMD path a kernel built more than once takes: the best the CPU runs, chosen at run
// time, or one named (tests and benchmarks compare them). The default build is plain x86-64 (SSE2);
// a kernel's AVX2 build is taken only where the CPU has AVX2, and both give the same answers.
#pragma once

namespace bvh_collision {

enum class SimdPath { kAuto, kGeneric, kAvx2 };

// Does this CPU run AVX2 code?
bool avx2_available();

// kAuto as the path this CPU takes; kAvx2 on a CPU without it throws std::runtime_error naming
// `what`.
SimdPath resolve_simd_path(SimdPath path, const char* what);

}  // namespace bvh_collision
