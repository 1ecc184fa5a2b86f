#include "bvh_collision/query/acm_sampling.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <fstream>
#include <iomanip>
#include <random>
#include <sstream>
#include <mutex>

#include "bvh_collision/geometry/thread_pool.h"

namespace bvh_collision {

SampledPairs sample_collision_pairs(const CollisionChecker& checker, const SamplingOptions& options) {
  const auto& pairs = checker.checked_pairs();
  std::map<std::pair<int, int>, std::size_t> index;
  for (std::size_t p = 0; p < pairs.size(); ++p) index[pairs[p]] = p;
  // Samples in blocks, each drawn from its own generator seeded by the block: the answer depends
  // on the seed only, not on how many threads took part.
  constexpr std::size_t kBlock = 64;
  const std::size_t blocks = (options.samples + kBlock - 1) / kBlock;
  std::vector<std::size_t> total(pairs.size(), 0);
  std::mutex merge;
  ThreadPool::shared().for_each(blocks, 1, [&](std::size_t b) {
    std::mt19937_64 rng(options.seed * 1000003 + b);
    std::vector<std::size_t> counts(pairs.size(), 0);
    SelfCollisionRequest request;
    request.all_pairs = true;
    for (std::size_t s = b * kBlock; s < std::min(options.samples, (b + 1) * kBlock); ++s) {
      const std::vector<double> state = random_configuration(checker.model(), rng);
      for (const auto& pair : checker.check_self(state.data(), request).colliding_pairs) ++counts[index.at(pair)];
    }
    const std::lock_guard<std::mutex> lock(merge);
    for (std::size_t p = 0; p < pairs.size(); ++p) total[p] += counts[p];
  });
  SampledPairs out;
  out.samples = options.samples;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const std::size_t n = total[p];
    if (n == 0) out.never.push_back(pairs[p]);
    if (n > options.always_fraction * options.samples) out.always.push_back(pairs[p]);
  }
  return out;
}

void apply_sampled_pairs(const SampledPairs& pairs, AllowedCollisionMatrix& acm) {
  for (const auto& [a, b] : pairs.never) acm.allow(a, b, AcmReason::kNeverCollide);
  for (const auto& [a, b] : pairs.always) acm.allow(a, b, AcmReason::kAlwaysCollide);
}

std::string sampling_cache_key(const std::string& urdf_xml, const std::string& srdf_xml, const SamplingOptions& o) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](const std::string& s) {
    for (unsigned char c : s) {
      h ^= c;
      h *= 1099511628211ull;
    }
    h ^= 0xff;  // separator
    h *= 1099511628211ull;
  };
  mix(urdf_xml);
  mix(srdf_xml);
  std::ostringstream settings;
  settings << std::setprecision(17) << o.samples << " " << o.always_fraction << " " << o.seed;
  mix(settings.str());
  std::ostringstream out;
  out << std::hex << std::setw(16) << std::setfill('0') << h;
  return out.str();
}

bool read_sampling_cache(const std::string& path, const std::string& key, const RobotModel& model, SampledPairs& out) {
  std::ifstream in(path);
  std::string magic, version, word, cached_key;
  if (!(in >> magic >> version) || magic != "bvh_collision_acm_cache" || version != "1") return false;
  if (!(in >> word >> cached_key) || word != "key" || cached_key != key) return false;
  SampledPairs pairs;
  if (!(in >> word >> pairs.samples) || word != "samples") return false;
  std::string kind, a, b;
  while (in >> kind >> a >> b) {
    const int ia = model.link_index(a), ib = model.link_index(b);
    if (ia < 0 || ib < 0 || (kind != "never" && kind != "always")) return false;
    (kind == "never" ? pairs.never : pairs.always).emplace_back(std::min(ia, ib), std::max(ia, ib));
  }
  if (!in.eof()) return false;
  out = std::move(pairs);
  return true;
}

bool write_sampling_cache(const std::string& path, const std::string& key, const RobotModel& model, const SampledPairs& pairs) {
  std::ofstream out(path);
  out << "bvh_collision_acm_cache 1\nkey " << key << "\nsamples " << pairs.samples << "\n";
  for (const auto& [a, b] : pairs.never) out << "never " << model.links()[a].name << " " << model.links()[b].name << "\n";
  for (const auto& [a, b] : pairs.always) out << "always " << model.links()[a].name << " " << model.links()[b].name << "\n";
  return static_cast<bool>(out);
}

}  // namespace bvh_collision
