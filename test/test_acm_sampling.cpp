// Sampled never/always pairs on a robot built so that the answer is known, and the cache.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bvh_collision/query/acm_sampling.h"
#include "bvh_collision/robot/robot_description.h"

namespace bvh_collision {
namespace {

// a --(revolute, +-0.1 rad)--> b (a box 1 m away) --fixed--> c (a box back over a): a and c
// always overlap; d sits 10 m away on a and never meets b or c.
const char* kUrdf = R"(<robot name="sampled">
  <link name="a"><collision><geometry><box size="0.4 0.4 0.4"/></geometry></collision></link>
  <link name="b"><collision><origin xyz="1 0 0"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="c"><collision><origin xyz="-1 0 0"/><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
  <link name="d"><collision><geometry><sphere radius="0.1"/></geometry></collision></link>
  <joint name="ab" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>
    <limit lower="-0.1" upper="0.1" effort="1" velocity="1"/></joint>
  <joint name="bc" type="fixed"><parent link="b"/><child link="c"/><origin xyz="1 0 0"/></joint>
  <joint name="ad" type="fixed"><parent link="a"/><child link="d"/><origin xyz="10 0 0"/></joint>
</robot>)";

CollisionChecker make_checker() {
  RobotModel m = RobotModel::from_urdf(*parse_robot_description(kUrdf), PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(m);
  return CollisionChecker(std::move(m), std::move(acm));
}

TEST(AcmSampling, FindsAlwaysAndNeverPairs) {
  const CollisionChecker checker = make_checker();
  const RobotModel& m = checker.model();
  SamplingOptions options;
  options.samples = 500;
  const SampledPairs pairs = sample_collision_pairs(checker, options);
  const std::pair<int, int> ac = std::minmax(m.link_index("a"), m.link_index("c"));
  const std::pair<int, int> bd = std::minmax(m.link_index("b"), m.link_index("d"));
  const std::pair<int, int> cd = std::minmax(m.link_index("c"), m.link_index("d"));
  EXPECT_EQ(pairs.always, (std::vector<std::pair<int, int>>{ac}));
  EXPECT_NE(std::find(pairs.never.begin(), pairs.never.end(), bd), pairs.never.end());
  EXPECT_NE(std::find(pairs.never.begin(), pairs.never.end(), cd), pairs.never.end());
  AllowedCollisionMatrix acm = checker.acm();
  apply_sampled_pairs(pairs, acm);
  EXPECT_EQ(acm.reason(ac.first, ac.second), AcmReason::kAlwaysCollide);
  EXPECT_EQ(acm.reason(bd.first, bd.second), AcmReason::kNeverCollide);
}

TEST(AcmSampling, CacheRoundTripAndStaleKeys) {
  const CollisionChecker checker = make_checker();
  SamplingOptions options;
  options.samples = 200;
  const SampledPairs pairs = sample_collision_pairs(checker, options);
  const std::string path = (std::filesystem::temp_directory_path() / "bvh_acm_cache_test.txt").string();
  const std::string key = sampling_cache_key(kUrdf, "", options);
  ASSERT_TRUE(write_sampling_cache(path, key, checker.model(), pairs));
  SampledPairs read;
  ASSERT_TRUE(read_sampling_cache(path, key, checker.model(), read));
  EXPECT_EQ(read.never, pairs.never);
  EXPECT_EQ(read.always, pairs.always);
  EXPECT_EQ(read.samples, 200u);
  // Another URDF, SRDF or sample count is another key: the cache is not used.
  EXPECT_NE(sampling_cache_key(std::string(kUrdf) + " ", "", options), key);
  EXPECT_NE(sampling_cache_key(kUrdf, "<robot/>", options), key);
  options.samples = 201;
  EXPECT_NE(sampling_cache_key(kUrdf, "", options), key);
  EXPECT_FALSE(read_sampling_cache(path, "0000000000000000", checker.model(), read));
  // A damaged file is ignored, not trusted.
  std::ofstream(path) << "bvh_collision_acm_cache 1\nkey " << key << "\nsamples 200\nnever a nosuchlink\n";
  EXPECT_FALSE(read_sampling_cache(path, key, checker.model(), read));
  EXPECT_FALSE(read_sampling_cache("/nonexistent/cache", key, checker.model(), read));
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace bvh_collision
