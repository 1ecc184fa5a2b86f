// The motion table of the environment benchmark (motion_speed_error): certified motions through
// the public API and the planner's prepared scene, and fixed steps, against tolerance.
#include <algorithm>
#include <random>

#include "bench_util.h"
#include "environment_bench.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"
#include "checker_fixtures.h"

namespace bvh_collision::environment_bench {

using bench::Table;

// Motions against tolerance (report section 1): the demo arm against its pillar (the surface of a
// 12 x 12 x 80 cm box at 1 cm, in a 2 cm octree, as demo.launch shows it), self and environment,
// certified (the interval engine) and at a fixed 0.02 rad step: the demo's sweep (joint1
// from -0.6 to 1.6 rad, joint2 at 1.0) and random motions, per tolerance, with the states each
// checked. At a tolerance a proxy level fits, fixed-step self checks run in the SIMD lanes.
CollisionChecker demo_checker(const std::vector<double>& proxy_levels) {
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(test::source_dir() + "/urdf/demo_arm.urdf"),
                                           PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  CheckerOptions options;
  options.proxy_levels = proxy_levels;
  return CollisionChecker(std::move(model), std::move(acm), options);
}

void motion_table(const Sizes& sizes, const std::string& dir) {
  Table table("motion_speed_error", "Motions against tolerance: the demo arm and its pillar",
              {"motions", "kind", "tolerance_mm", "us_per_motion", "states_per_motion", "colliding motions"});
  const CollisionChecker checker = demo_checker(sizes.proxy_levels);
  Environment env(0.02);
  insert_points(env.octree(), demo_pillar());
  checker.prepare_distance_field(env);  // as the node keeps it
  const std::size_t n = checker.model().variable_count();
  std::vector<std::pair<std::vector<double>, std::vector<double>>> sweep(1, {std::vector<double>(n, 0.0), std::vector<double>(n, 0.0)});
  const auto index = [&](const char* joint) {
    const auto& names = checker.model().variable_names();
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), joint) - names.begin());
  };
  sweep[0].first[index("joint1")] = -0.6, sweep[0].first[index("joint2")] = 1.0;
  sweep[0].second[index("joint1")] = 1.6, sweep[0].second[index("joint2")] = 1.0;
  std::mt19937_64 rng(17);
  std::vector<std::pair<std::vector<double>, std::vector<double>>> random;
  for (std::size_t i = 0; i < sizes.motions; ++i) {
    random.emplace_back(random_configuration(checker.model(), rng), random_configuration(checker.model(), rng));
  }
  const auto shared_env = std::make_shared<const Environment>(env);
  for (const auto& [label, motions] : {std::pair{"demo sweep", &sweep}, std::pair{"random", &random}}) {
    // Certified through the public API (CollisionChecker::check_motion) and through the planner's
    // prepared scene (SceneChecker) in the same run: one engine, so the same answers and times.
    for (const int mode : {0, 1, 2}) {
      const double resolution = mode == 2 ? 0.02 : 0.0;
      for (const double mm : {0.0, 10.0, 20.0}) {
        MotionRequest request;
        request.resolution = resolution;
        request.tolerance = mm * 1e-3;
        SceneCheckOptions options;
        options.tolerance = request.tolerance;
        const SceneChecker scene(checker, shared_env, options);
        std::vector<double> times;
        std::size_t states = 0, colliding = 0;
        for (std::size_t r = 0; r < sizes.runs; ++r) {
          states = colliding = 0;
          // Each run's goals a nanoradian apart from the last run's: a motion asked again would be
          // answered from memory, and each run times first asks.
          std::vector<double> goal;
          times.push_back(bench::us_per_item(motions->size(), [&] {
            for (const auto& [a, b] : *motions) {
              goal = b;
              goal[0] += 1e-9 * static_cast<double>(r);
              const MotionResult result = mode == 1 ? scene.check_motion(a.data(), goal.data(), true)
                                                    : checker.check_motion(a.data(), goal.data(), env, request);
              states += result.states_checked;
              colliding += !result.valid;
            }
          }));
        }
        static const char* const kModes[] = {"certified (public check_motion)", "certified (planner's SceneChecker)", "fixed step 0.02 rad"};
        table.row({label, kModes[mode], mm, bench::spread(times).median, double(states) / motions->size(), double(colliding)});
      }
    }
  }
  table.note("Demo arm (proxy levels " + levels_mm(sizes.proxy_levels) + "), self and environment, root at the origin, the octree's distance "
             "field kept; " + std::to_string(sizes.motions) + " random motions between uniform states. Certified: intervals of "
             "the motion proven free whole by the interval engine (query/scene_checker.h), through the public "
             "CollisionChecker::check_motion (its prepared scene kept between motions; the first run prepares it) and "
             "through a SceneChecker a planner holds (prepared before the runs); each run's goals 1e-9 rad from the "
             "last's, so that no motion is answered from memory; states: one per interval and the two ends. Fixed step: every 0.02 rad; at 10 "
             "and 20 mm the self checks run several states at a time in SIMD lanes on the proxies and the environment "
             "checks on the proxies and the field.");
  table.write(dir);
}

}  // namespace bvh_collision::environment_bench
