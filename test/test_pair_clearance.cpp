// Proven clearance grids of the self pairs one or two variables move (model/pair_clearance.h),
// checked against the exact routines: in random states, near-contact states, states on cell
// edges and continuous joints beyond one turn, no grid's bound exceeds the pair's exact distance
// (solids), and a pair the grid skips is free by the exact boolean check of that pair alone;
// boolean self checks answer the same with and without the grids.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>

#include <unistd.h>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/model/detail/pair_clearance_shape.h"
#include "bvh_collision/model/pair_clearance_cache.h"
#include "bvh_collision/narrowphase/shape_pairs.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

CheckerOptions without_grids() {
  CheckerOptions o;
  o.pair_clearance_cells = 0;
  return o;
}

// The exact distance of a pair's links (solids), by the shape-pair routine, when below `limit`
// (else `limit` or more: the query may stop once it shows that).
double exact_distance(const RobotCollisionModel& m, int a, int b, const double* state, double limit) {
  std::vector<Transform> poses;
  m.kinematics().compute(state, poses);
  double best = limit;
  QueryStats stats;
  for (const LinkShape& sa : m.shapes()[a]) {
    for (const LinkShape& sb : m.shapes()[b]) {
      Vec3 wa, wb;
      best = std::min(best, shapes_distance(m.ref(sa), poses[a] * sa.origin, m.ref(sb), poses[b] * sb.origin, best, true,
                                                    wa, wb, stats));
    }
  }
  return best;
}

// States that stress the grids: uniform ones, then per grid its variables on cell edges, and
// (continuous joints) a whole number of turns away from the grid.
std::vector<std::vector<double>> stress_states(const CollisionChecker& c, int count, std::mt19937_64& rng) {
  std::vector<std::vector<double>> out;
  for (int i = 0; i < count; ++i) out.push_back(random_configuration(c.model(), rng));
  const auto& grids = c.accelerators().pair_clearance().grids();
  for (int i = 0; i < count; ++i) {
    std::vector<double> s = random_configuration(c.model(), rng);
    const PairClearanceGrid& g = grids[static_cast<std::size_t>(i) % grids.size()];
    for (int k = 0; k < g.dims; ++k) {
      const int edge = std::uniform_int_distribution<int>(0, g.cells[k])(rng);
      s[g.variable[k]] = g.lower[k] + edge * g.cell[k];
      if (g.periodic[k]) s[g.variable[k]] += 2.0 * M_PI * std::uniform_int_distribution<int>(-3, 3)(rng);
    }
    out.push_back(s);
  }
  return out;
}

class PairClearanceOnRobot : public ::testing::TestWithParam<std::string> {};

// The claim itself: every bound is at most the exact distance, in every state tried.
TEST_P(PairClearanceOnRobot, BoundsNeverExceedTheExactDistance) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker(GetParam());
  const RobotCollisionModel& m = c.collision_model();
  const PairClearance& grids = c.accelerators().pair_clearance();
  ASSERT_FALSE(grids.grids().empty()) << GetParam() << ": no pair has a grid";
  std::mt19937_64 rng(41);
  std::size_t bounded = 0;
  for (const auto& s : stress_states(c, test::sized(1500), rng)) {
    for (const PairClearanceGrid& g : grids.grids()) {
      const double bound = grids.lower_bound(g.pair, s.data());
      if (!std::isfinite(bound)) continue;
      ++bounded;
      const auto [a, b] = m.checked_pairs()[g.pair];
      // Only whether d reaches the bound is asked: the distance query may stop there.
      const double d = exact_distance(m, a, b, s.data(), bound + 1e-6);
      ASSERT_LE(bound, d) << m.robot().links()[a].name << "-" << m.robot().links()[b].name;
    }
  }
  EXPECT_GT(bounded, 0u);
  RecordProperty("bounded", static_cast<int>(bounded));
}

// The proof over a segment (certified motions use it for a whole interval): along short random
// segments and long ones (a joint's whole range), at 40 states each, no pair the grid proves
// clear of its padding comes within it by the exact distance; a segment that leaves the grid gets
// no proof.
TEST_P(PairClearanceOnRobot, ProofOverASegmentHoldsAgainstTheExactDistance) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker(GetParam());
  const RobotCollisionModel& m = c.collision_model();
  const PairClearance& grids = c.accelerators().pair_clearance();
  std::mt19937_64 rng(43);
  std::size_t proven = 0;
  for (int i = 0; i < test::sized(150); ++i) {
    const std::vector<double> a = random_configuration(c.model(), rng);
    const std::vector<double> b = i % 2 == 0 ? random_configuration(c.model(), rng) : [&] {
      std::uniform_real_distribution<double> step(-0.15, 0.15);
      std::vector<double> near = a;
      for (double& v : near) v += step(rng);
      return near;
    }();
    // Eight grids a segment, taken in turn (pr2 without its SRDF has 187).
    const std::size_t n = grids.grids().size(), stride = std::max<std::size_t>(1, n / 8);
    for (std::size_t k = static_cast<std::size_t>(i) % stride; k < n; k += stride) {
      const PairClearanceGrid& g = grids.grids()[k];
      const auto [la, lb] = m.checked_pairs()[g.pair];
      const double padding = m.paddings()[la] + m.paddings()[lb];
      if (!grids.clear_over(g.pair, a.data(), b.data(), padding)) continue;
      ++proven;
      for (int k = 0; k <= 40; ++k) {
        std::vector<double> q(a.size());
        for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / 40.0;
        ASSERT_LT(padding, exact_distance(m, la, lb, q.data(), padding + 1e-6)) << m.robot().links()[la].name << "-" << m.robot().links()[lb].name;
      }
    }
  }
  EXPECT_GT(proven, 0u);
  const PairClearanceGrid& g = grids.grids().front();
  std::vector<double> a(c.model().variable_count(), 0.0), b = a;
  a[g.variable[0]] = g.lower[0];
  b[g.variable[0]] = g.lower[0] - 1.0;  // outside the grid
  EXPECT_FALSE(grids.clear_over(g.pair, a.data(), b.data(), -1.0));
}

// Does a dense walk of the segment a-b (every 1/16 of a cell, each sample with its neighbours
// across a nearby edge) touch only cells with a bound above 0? `longest`: its largest change in cells.
bool touches_settled_cells_only(const PairClearance& grids, const PairClearanceGrid& g, const std::vector<double>& a,
                                const std::vector<double>& b, double longest) {
  const int samples = static_cast<int>(std::ceil(longest * 16.0)) + 1;
  for (int n = 0; n <= samples; ++n) {
    std::vector<double> q(a.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * n / samples;
    for (int nudge = 0; nudge < (1 << g.dims); ++nudge) {
      std::vector<double> p = q;
      for (int k = 0; k < g.dims; ++k) p[g.variable[k]] = std::clamp(p[g.variable[k]] + ((nudge >> k) & 1 ? 1e-7 : -1e-7) * g.cell[k], g.lower[k], g.lower[k] + g.cell[k] * g.cells[k]);
      if (!(grids.lower_bound(g.pair, p.data()) > 0.0)) return false;
    }
  }
  return true;
}

// The proof walks the pyramid, not the cells: checked against the finest cells a dense walk of
// the segment touches (every 1/16 of a cell, each sample with its neighbours across a nearby
// edge). A proof needs every touched cell above the clearance (soundness); every segment whose
// touched cells (and the cells of its box, the old test) all are is proven unless the corner rule
// declines it, which the count bounds (completeness: a proof that always says no helps nobody).
TEST_P(PairClearanceOnRobot, ProofOverASegmentAgreesWithTheCellsItCrosses) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker(GetParam());
  const PairClearance& grids = c.accelerators().pair_clearance();
  std::mt19937_64 rng(61);
  int proven = 0, all_clear = 0;
  // Up to 16 grids, spread over the list (pr2 without its SRDF has 187), every one on ur5e and panda.
  const std::size_t n = grids.grids().size(), stride = std::max<std::size_t>(1, n / 16);
  for (std::size_t index = 0; index < n; index += stride) {
    const PairClearanceGrid& g = grids.grids()[index];
    if (g.periodic[0] || g.periodic[1] || g.periodic[2]) continue;
    for (int i = 0; i < test::sized(300); ++i) {
      std::vector<double> a(c.model().variable_count(), 0.0), b = a;
      const double reach = i % 3 == 0 ? 1.0 : i % 3 == 1 ? 0.1 : 0.01;  // of the grid's span
      double longest = 0.0;
      for (int k = 0; k < g.dims; ++k) {
        const double span = g.cell[k] * g.cells[k];
        std::uniform_real_distribution<double> at(0.0, span);
        a[g.variable[k]] = g.lower[k] + at(rng);
        b[g.variable[k]] = std::clamp(a[g.variable[k]] + reach * span * std::uniform_real_distribution<double>(-1.0, 1.0)(rng),
                                      g.lower[k], g.lower[k] + span);
        longest = std::max(longest, std::abs(b[g.variable[k]] - a[g.variable[k]]) / g.cell[k]);
      }
      const bool touched_clear = touches_settled_cells_only(grids, g, a, b, longest);
      const bool proof = grids.clear_over(g.pair, a.data(), b.data(), 0.0, 1 << 20);
      ASSERT_TRUE(!proof || touched_clear) << "pair " << g.pair << ": proven over a segment through a cell with no bound";
      all_clear += touched_clear;
      proven += proof;
    }
  }
  EXPECT_GT(all_clear, 0);
  EXPECT_GE(proven, all_clear * 95 / 100) << "proofs found for " << proven << " of " << all_clear << " segments through settled cells";
}

// A long segment needs more boxes than a short one: the proof's budget grows with the cells the
// segment crosses, so that a segment across the whole grid through settled cells is proven with
// the default budget too (a fixed 32 boxes proved 160 of ur5e's 192 such segments; in planning it
// gave up on many of panda's, which sphere walks and halved intervals then settled: docs/performance.md).
// And a planner's interval moves the pair across a few finest cells, where a grid's bound mostly
// holds a few levels below the pyramid's top: halving the segment at every level it went down
// doubled its boxes at each (15 a proof on panda's wrist grids in planning, one proof in ten given
// up; 87-91 % of ur5e's short segments here).
TEST_P(PairClearanceOnRobot, ASegmentThroughSettledCellsIsProvenWithTheDefaultBudget) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker(GetParam());
  const PairClearance& grids = c.accelerators().pair_clearance();
  std::mt19937_64 rng(67);
  const std::size_t n = grids.grids().size(), stride = std::max<std::size_t>(1, n / 16);
  for (const double cells : {0.0, 2.0, 6.0}) {  // across the grid, or across up to that many finest cells
    int proven = 0, all_clear = 0;
    for (std::size_t index = 0; index < n; index += stride) {
      const PairClearanceGrid& g = grids.grids()[index];
      if (g.periodic[0] || g.periodic[1] || g.periodic[2]) continue;
      for (int i = 0; i < test::sized(cells == 0.0 ? 100 : 150); ++i) {
        std::vector<double> a(c.model().variable_count(), 0.0), b = a;
        double longest = 0.0;
        for (int k = 0; k < g.dims; ++k) {
          const double span = g.cell[k] * g.cells[k];
          if (cells == 0.0) {  // from near one side of the grid to near the other
            std::uniform_real_distribution<double> side(0.0, 0.2 * span);
            const bool up = (rng() & 1) != 0;
            a[g.variable[k]] = g.lower[k] + (up ? side(rng) : span - side(rng));
            b[g.variable[k]] = g.lower[k] + (up ? span - side(rng) : side(rng));
          } else {
            a[g.variable[k]] = g.lower[k] + std::uniform_real_distribution<double>(0.0, span)(rng);
            b[g.variable[k]] = std::clamp(a[g.variable[k]] + cells * g.cell[k] * std::uniform_real_distribution<double>(-1.0, 1.0)(rng),
                                          g.lower[k], g.lower[k] + span);
          }
          longest = std::max(longest, std::abs(b[g.variable[k]] - a[g.variable[k]]) / g.cell[k]);
        }
        if (!touches_settled_cells_only(grids, g, a, b, longest)) continue;
        ++all_clear;
        proven += grids.clear_over(g.pair, a.data(), b.data(), 0.0);
      }
    }
    EXPECT_GT(all_clear, 0) << GetParam() << ": no grid settled along a whole segment (" << cells << " cells)";
    // Long segments: 95 %; short ones 99 % (the corner rule declines a few).
    EXPECT_GE(proven, all_clear * (cells == 0.0 ? 95 : 99) / 100)
        << "proofs found for " << proven << " of " << all_clear << " segments through settled cells (" << cells << " cells; 0: across)";
  }
}

// A skipped pair is free by the exact check of that pair alone, and whole boolean self checks
// (any tolerance) answer as without the grids.
TEST_P(PairClearanceOnRobot, SkippingChangesNoAnswer) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker with = test::load_checker(GetParam());
  const CollisionChecker without = test::load_checker(GetParam(), without_grids());
  const RobotCollisionModel& m = with.collision_model();
  const PairClearance& grids = with.accelerators().pair_clearance();
  std::mt19937_64 rng(43);
  std::size_t skipped = 0;
  for (const auto& s : stress_states(with, test::sized(1000), rng)) {
    for (const PairClearanceGrid& g : grids.grids()) {
      const auto [a, b] = m.checked_pairs()[g.pair];
      if (grids.lower_bound(g.pair, s.data()) <= m.paddings()[a] + m.paddings()[b]) continue;
      ++skipped;
      const std::vector<std::size_t> only{g.pair};
      SelfCollisionRequest one;
      one.only_pairs = &only;
      ASSERT_FALSE(without.check_self(s.data(), one).collision) << m.robot().links()[a].name << "-" << m.robot().links()[b].name;
    }
    for (const double tolerance : {0.0, 0.01}) {
      SelfCollisionRequest r{tolerance};
      ASSERT_EQ(with.check_self(s.data(), r).collision, without.check_self(s.data(), r).collision);
    }
  }
  EXPECT_GT(skipped, 0u);
}

// Grids equal in every number, pyramids included.
void expect_same_grids(const PairClearance& a, const PairClearance& b) {
  ASSERT_EQ(a.grids().size(), b.grids().size());
  for (std::size_t i = 0; i < a.grids().size(); ++i) {
    const PairClearanceGrid &x = a.grids()[i], &y = b.grids()[i];
    SCOPED_TRACE("grid " + std::to_string(i));
    EXPECT_EQ(x.pair, y.pair);
    EXPECT_EQ(x.dims, y.dims);
    EXPECT_EQ(x.variable, y.variable);
    EXPECT_EQ(x.lower, y.lower);
    EXPECT_EQ(x.cell, y.cell);
    EXPECT_EQ(x.cells, y.cells);
    EXPECT_EQ(x.periodic, y.periodic);
    ASSERT_EQ(x.bound.size(), y.bound.size());
    EXPECT_EQ(0, std::memcmp(x.bound.data(), y.bound.data(), x.bound.size() * sizeof(float)));
    EXPECT_EQ(x.pyramid, y.pyramid);
    EXPECT_EQ(a.has_grid(x.pair), b.has_grid(y.pair));
  }
}

std::filesystem::path fresh_folder(const std::string& name) {
  const auto folder = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(folder);
  return folder;
}

// The grids a checker reads from a folder are the ones the builder builds, number for number:
// every kind of grid (one, two and three variables, refined, periodic on pr2's continuous joints)
// on three robots; a second start reads them and builds nothing.
TEST_P(PairClearanceOnRobot, ASecondStartReadsTheGridsTheFirstStored) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker(GetParam());
  const RobotCollisionModel& m = c.collision_model();
  const std::size_t cells = CheckerOptions().pair_clearance_cells;
  const PairClearance built = PairClearance::build(m, cells);  // uncached, as the builder makes them
  EXPECT_FALSE(built.from_cache());
  expect_same_grids(built, c.accelerators().pair_clearance());

  // Stored as a first start stores them (cached_or_built_pair_clearance builds and stores in
  // AFileThatDoesNotCheckOutIsBuiltAgain; a second build here would cost pr2 a minute under the
  // sanitizers).
  const auto folder = fresh_folder("bvh_grid_cache");
  ASSERT_TRUE(write_cached_pair_clearance(folder.string(), pair_clearance_key(m, cells), built));
  const PairClearance second = cached_or_built_pair_clearance(m, cells, folder.string());
  EXPECT_TRUE(second.from_cache());
  expect_same_grids(built, second);
  // Which kinds the robot's grids exercise: refined ones have more cells than their pair's shape.
  const std::vector<PairClearanceGrid> shapes = detail::clearance_grid_shapes(m, cells);
  std::size_t refined = 0, periodic = 0;
  for (const PairClearanceGrid& g : built.grids()) {
    const auto shape = std::find_if(shapes.begin(), shapes.end(), [&](const PairClearanceGrid& s) { return s.pair == g.pair; });
    ASSERT_NE(shape, shapes.end());
    refined += shape->cells != g.cells;
    periodic += g.periodic[0] || g.periodic[1] || g.periodic[2];
  }
  if (GetParam() == "ur5e") {
    EXPECT_GT(refined, 0u);
  }
  if (GetParam() == "pr2") {
    EXPECT_GT(periodic, 0u);
  }
  std::filesystem::remove_all(folder);
}

// A file that does not check out is built again and replaced: a flipped byte, a cut one, and a
// sealed file whose grids are not the shapes the build gives (another cell budget's grids stored
// under this budget's key).
TEST(PairClearanceCache, AFileThatDoesNotCheckOutIsBuiltAgain) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::panda_as_moveit();
  const RobotCollisionModel& m = c.collision_model();
  const std::size_t cells = CheckerOptions().pair_clearance_cells;
  const PairClearance& built = c.accelerators().pair_clearance();
  const auto folder = fresh_folder("bvh_grid_cache_bad");
  const std::uint64_t key = pair_clearance_key(m, cells);
  const std::string file = pair_clearance_file(folder.string(), key);
  ASSERT_TRUE(write_cached_pair_clearance(folder.string(), key, built));
  std::string bytes;
  {
    std::ifstream in(file, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  ASSERT_GT(bytes.size(), 1000u);
  auto rewrite = [&](const std::string& content) {
    std::ofstream(file, std::ios::binary | std::ios::trunc) << content;
  };
  for (const std::size_t at : {std::size_t(9), bytes.size() / 2, bytes.size() - 1}) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(flipped[at] ^ 0x10);
    rewrite(flipped);
    EXPECT_FALSE(read_cached_pair_clearance(folder.string(), key, m, cells)) << "byte " << at;
  }
  rewrite(bytes.substr(0, bytes.size() / 3));
  EXPECT_FALSE(read_cached_pair_clearance(folder.string(), key, m, cells));
  const PairClearance rebuilt = cached_or_built_pair_clearance(m, cells, folder.string());
  EXPECT_FALSE(rebuilt.from_cache());
  expect_same_grids(built, rebuilt);
  const std::optional<PairClearance> read = read_cached_pair_clearance(folder.string(), key, m, cells);
  ASSERT_TRUE(read) << "the rebuilt grids replaced the bad file";
  expect_same_grids(built, *read);

  const PairClearance coarser = PairClearance::build(m, cells / 4);
  ASSERT_FALSE(coarser.grids().empty());
  ASSERT_TRUE(write_cached_pair_clearance(folder.string(), key, coarser));
  EXPECT_FALSE(read_cached_pair_clearance(folder.string(), key, m, cells)) << "grids of another shape";
  std::filesystem::remove_all(folder);
}

// The key changes with every input of the build: the cell budget, the pairs checked, a link's
// padding, a joint's limit; it is the same for the same robot loaded twice.
TEST(PairClearanceCache, KeysTellEveryInputOfTheBuildApart) {
  BVH_REQUIRE_ROBOTS();
  const std::size_t cells = CheckerOptions().pair_clearance_cells;
  CheckerOptions none;
  none.pair_clearance_cells = 0;
  const CollisionChecker adjacent = test::load_checker("panda", none), again = test::load_checker("panda", none);
  const CollisionChecker moveit = test::panda_as_moveit(none);
  CheckerOptions padded = none;
  padded.link_padding["panda_hand"] = 0.001;
  const CollisionChecker hand_padded = test::load_checker("panda", padded);
  const std::string dir = test::robots_dir() + "/panda";
  std::ifstream in(dir + "/robot.urdf");
  std::string urdf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t limit = urdf.find("upper=\"") + 7, end = urdf.find('"', limit);
  ASSERT_NE(end, std::string::npos);
  const double upper = std::stod(urdf.substr(limit, end - limit)) - 0.5;  // the first limit, 0.5 lower
  urdf.replace(limit, end - limit, std::to_string(upper));
  RobotModel changed = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver({dir}));
  std::size_t differ = 0;
  for (std::size_t j = 0; j < changed.joints().size(); ++j) differ += changed.joints()[j].upper != adjacent.model().joints()[j].upper;
  ASSERT_EQ(differ, 1u);
  const CollisionChecker limited(std::move(changed), AllowedCollisionMatrix::adjacent_links(adjacent.model()), none);

  const std::uint64_t key = pair_clearance_key(adjacent.collision_model(), cells);
  EXPECT_EQ(key, pair_clearance_key(again.collision_model(), cells));
  EXPECT_NE(key, pair_clearance_key(adjacent.collision_model(), cells - 1));
  EXPECT_NE(key, pair_clearance_key(moveit.collision_model(), cells));
  EXPECT_NE(key, pair_clearance_key(hand_padded.collision_model(), cells));
  EXPECT_NE(key, pair_clearance_key(limited.collision_model(), cells));
}

INSTANTIATE_TEST_SUITE_P(Robots, PairClearanceOnRobot, ::testing::Values("panda", "ur5e", "pr2"));

// Why the grids exist: on panda the wrist pairs (link6-hand, link5-link7) and the fingers sit
// close in every state, and most random states settle them with one lookup.
TEST(PairClearance, SettlesPandasAlwaysNearPairs) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker("panda");
  const RobotCollisionModel& m = c.collision_model();
  const PairClearance& grids = c.accelerators().pair_clearance();
  const RobotModel& robot = c.model();
  std::mt19937_64 rng(47);
  for (const auto& [x, y] : {std::pair<const char*, const char*>{"panda_link6", "panda_hand"}, {"panda_link5", "panda_link7"},
                             {"panda_leftfinger", "panda_rightfinger"}}) {
    const int a = robot.link_index(x), b = robot.link_index(y);
    std::size_t pair = m.checked_pairs().size();
    for (std::size_t p = 0; p < m.checked_pairs().size(); ++p) {
      if (m.checked_pairs()[p] == std::pair<int, int>(std::min(a, b), std::max(a, b))) pair = p;
    }
    ASSERT_LT(pair, m.checked_pairs().size()) << x << "-" << y << " is not checked";
    int settled = 0;
    for (int i = 0; i < 1000; ++i) {
      const auto s = random_configuration(robot, rng);
      settled += grids.lower_bound(pair, s.data()) > 0.0;
    }
    EXPECT_GT(settled, 800) << x << "-" << y;
  }
}

// Values the grid does not span get no bound: beyond a revolute joint's limits, NaN.
TEST(PairClearance, NoBoundOutsideTheGrid) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_checker("panda");
  const PairClearance& table = c.accelerators().pair_clearance();
  ASSERT_FALSE(table.grids().empty());
  std::mt19937_64 rng(53);
  for (const PairClearanceGrid& g : table.grids()) {
    auto s = random_configuration(c.model(), rng);
    ASSERT_FALSE(g.periodic[0]);
    s[g.variable[0]] = g.lower[0] - 1e-9;
    EXPECT_EQ(table.lower_bound(g.pair, s.data()), -std::numeric_limits<double>::infinity());
    s[g.variable[0]] = g.lower[0] + g.cell[0] * g.cells[0] + 1e-9;
    EXPECT_EQ(table.lower_bound(g.pair, s.data()), -std::numeric_limits<double>::infinity());
    s[g.variable[0]] = std::nan("");
    EXPECT_EQ(table.lower_bound(g.pair, s.data()), -std::numeric_limits<double>::infinity());
  }
  // A pair no grid covers (two variables or more apart from panda_link0... link7) has no bound.
  std::size_t ungridded = 0;
  const auto s = random_configuration(c.model(), rng);
  for (std::size_t p = 0; p < c.collision_model().checked_pairs().size(); ++p) {
    bool gridded = false;
    for (const PairClearanceGrid& g : table.grids()) gridded |= g.pair == p;
    if (gridded) continue;
    ++ungridded;
    EXPECT_EQ(table.lower_bound(p, s.data()), -std::numeric_limits<double>::infinity());
  }
  EXPECT_GT(ungridded, 0u);
}

// Panda as MoveIt checks it (its SRDF allows the wrist's neighbours): the forearm (link5) against
// each finger is moved by three variables (joints 6 and 7 and the finger's travel), and those two
// pairs took half the sphere walks of a planner's certified motions. They get three-variable grids
// whose bounds hold against the exact distance, in random states, on cell edges and along
// segments, and settle most states.
TEST(PairClearance, ThreeVariableGridsForPandasForearmAndFingers) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::panda_as_moveit();
  const RobotCollisionModel& m = c.collision_model();
  const PairClearance& grids = c.accelerators().pair_clearance();
  const RobotModel& robot = c.model();
  const int forearm = robot.link_index("panda_link5");
  std::mt19937_64 rng(59);
  for (const char* finger : {"panda_leftfinger", "panda_rightfinger"}) {
    const int f = robot.link_index(finger);
    const PairClearanceGrid* grid = nullptr;
    for (const PairClearanceGrid& g : grids.grids()) {
      if (m.checked_pairs()[g.pair] == std::pair<int, int>(std::min(forearm, f), std::max(forearm, f))) grid = &g;
    }
    ASSERT_NE(grid, nullptr) << "panda_link5-" << finger << " has no grid";
    ASSERT_EQ(grid->dims, 3);
    int settled = 0;
    for (int i = 0; i < test::sized(600); ++i) {
      auto s = random_configuration(robot, rng);
      if (i % 2 == 1) {  // on a cell edge of every variable
        for (int k = 0; k < grid->dims; ++k) {
          s[grid->variable[k]] = grid->lower[k] + std::uniform_int_distribution<int>(0, grid->cells[k])(rng) * grid->cell[k];
        }
      }
      const double bound = grids.lower_bound(grid->pair, s.data());
      if (!std::isfinite(bound)) continue;
      ++settled;
      ASSERT_LE(bound, exact_distance(m, forearm, f, s.data(), bound + 1e-6)) << finger;
    }
    EXPECT_GT(settled, test::sized(600) * 6 / 10) << finger;
    int over = 0;
    std::uniform_real_distribution<double> step(-0.1, 0.1);
    for (int i = 0; i < test::sized(100); ++i) {
      const auto a = random_configuration(robot, rng);
      auto b = a;
      for (double& v : b) v += step(rng);
      if (!grids.clear_over(grid->pair, a.data(), b.data(), 0.0)) continue;
      ++over;
      for (int k = 0; k <= 20; ++k) {
        std::vector<double> q(a.size());
        for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / 20.0;
        ASSERT_LT(0.0, exact_distance(m, forearm, f, q.data(), 1e-6)) << finger;
      }
    }
    EXPECT_GT(over, 0) << finger;
  }
}

// ur5e as MoveIt checks it: the forearm and wrist_2_link, moved by the first two wrist joints,
// are 8-40 mm apart over the whole of their ranges and never touch. A planner's certified motions
// turn both wrist joints by radians at a time; the pair took half the sphere walks of ur5e's
// motions at 10 mm when its grid (4,096 cells, 14 mm of closing per cell) left a tenth of its cells
// without a bound and a segment's proof took the least bound of its whole box, at most 64 cells.
// Now every cell is settled and a long segment of both wrist joints is proven by the pyramid.
TEST(PairClearance, ProvesUr5esWristAlongLongMotions) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker c = test::load_as_moveit("ur5e");
  const RobotCollisionModel& m = c.collision_model();
  const PairClearance& grids = c.accelerators().pair_clearance();
  const RobotModel& robot = c.model();
  const int forearm = robot.link_index("forearm_link"), wrist = robot.link_index("wrist_2_link");
  const PairClearanceGrid* grid = nullptr;
  for (const PairClearanceGrid& g : grids.grids()) {
    if (m.checked_pairs()[g.pair] == std::pair<int, int>(std::min(forearm, wrist), std::max(forearm, wrist))) grid = &g;
  }
  ASSERT_NE(grid, nullptr) << "forearm_link-wrist_2_link has no grid";
  ASSERT_EQ(grid->dims, 2);
  std::size_t settled = 0;
  for (const float f : grid->bound) settled += f > 0.0f;
  EXPECT_EQ(settled, grid->bound.size()) << "cells with no bound";
  std::mt19937_64 rng(67);
  int proven = 0;
  const int segments = test::sized(200);
  for (int i = 0; i < segments; ++i) {
    const auto a = random_configuration(robot, rng);
    const auto b = random_configuration(robot, rng);  // radians apart: the joints' ranges are 4 pi
    if (!grids.clear_over(grid->pair, a.data(), b.data(), m.paddings()[forearm] + m.paddings()[wrist] + 1e-5)) continue;
    ++proven;
    for (int k = 0; k <= 10; ++k) {
      std::vector<double> q(a.size());
      for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / 10.0;
      ASSERT_LT(1e-5, exact_distance(m, forearm, wrist, q.data(), 1e-3));
    }
  }
  EXPECT_EQ(proven, segments);
}

}  // namespace
}  // namespace bvh_collision
