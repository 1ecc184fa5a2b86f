// The world's object list and its persistent containers (world/object_list.h,
// persistent_vector.h, persistent_map.h): random changes against std::vector and
// std::unordered_map, every snapshot taken along the way unchanged afterwards, box queries
// against brute force, and the work of one change bounded by counts (nodes and entries copied)
// that grow as log n: adding the n-th object copied all n records before.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "bvh_collision/world/environment.h"
#include "bvh_collision/world/object_list.h"
#include "bvh_collision/world/persistent_map.h"
#include "bvh_collision/world/persistent_vector.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

template <class T>
std::vector<T> contents(const PersistentVector<T>& v) {
  return std::vector<T>(v.begin(), v.end());
}

TEST(PersistentVector, MatchesAVectorAndKeepsEverySnapshot) {
  std::mt19937_64 rng(3);
  PersistentVector<int> v;
  std::vector<int> oracle;
  std::vector<std::pair<PersistentVector<int>, std::vector<int>>> snapshots;
  for (int step = 0; step < test::sized(40000); ++step) {
    const int op = static_cast<int>(rng() % 10);
    if (op < 6 || oracle.empty()) {  // grows through several levels (32, 1024, 32768)
      const int x = static_cast<int>(rng() % 1000000);
      v.push_back(x);
      oracle.push_back(x);
    } else if (op < 8) {
      const std::size_t i = rng() % oracle.size();
      const int x = -static_cast<int>(rng() % 1000);
      v.set(i, x);
      oracle[i] = x;
    } else {
      v.pop_back();
      oracle.pop_back();
    }
    ASSERT_EQ(v.size(), oracle.size());
    if (!oracle.empty()) {
      const std::size_t i = rng() % oracle.size();
      ASSERT_EQ(v[i], oracle[i]) << "step " << step << " index " << i;
    }
    if (step % 997 == 0) snapshots.emplace_back(v, oracle);
  }
  EXPECT_EQ(contents(v), oracle);
  for (const auto& [snap, expected] : snapshots) {
    EXPECT_EQ(contents(snap), expected);
  }
  // Emptied and grown again.
  while (!v.empty()) v.pop_back();
  v.push_back(7);
  EXPECT_EQ(contents(v), std::vector<int>{7});
}

// A hash that sends every key to one of two values: the trie's deepest nodes list leaves.
struct TwoHashes {
  std::size_t operator()(int k) const { return static_cast<std::size_t>(k & 1); }
};

template <class Map>
void check_map(Map& map, int keys, int steps, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::unordered_map<int, int> oracle;
  std::vector<std::pair<Map, std::unordered_map<int, int>>> snapshots;
  for (int step = 0; step < steps; ++step) {
    const int key = static_cast<int>(rng() % keys);
    if (rng() % 3 == 0) {
      ASSERT_EQ(map.erase(key), oracle.erase(key) == 1) << step;
    } else {
      const int value = static_cast<int>(rng());
      map.set(key, value);
      oracle[key] = value;
    }
    ASSERT_EQ(map.size(), oracle.size());
    const int probe = static_cast<int>(rng() % keys);
    const int* found = map.find(probe);
    const auto it = oracle.find(probe);
    ASSERT_EQ(found != nullptr, it != oracle.end()) << step;
    if (found) {
      ASSERT_EQ(*found, it->second);
    }
    if (step % 499 == 0) snapshots.emplace_back(map, oracle);
  }
  for (const auto& [snap, expected] : snapshots) {
    std::unordered_map<int, int> seen;
    snap.for_each([&](int k, int v) { seen[k] = v; });
    EXPECT_EQ(seen, expected);
    EXPECT_EQ(snap.size(), expected.size());
  }
}

TEST(PersistentMap, MatchesAnUnorderedMapAndKeepsEverySnapshot) {
  PersistentMap<int, int> map;
  check_map(map, 5000, test::sized(30000), 5);
  PersistentMap<int, int, TwoHashes> colliding;
  check_map(colliding, 60, test::sized(3000), 6);
}

// Spheres and boxes on a jittered grid, some large, some far away (beyond the tree's root cube).
CollisionObject random_object(std::mt19937_64& rng, const std::string& id) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Transform pose;
  pose.R = Eigen::AngleAxisd(6.3 * unit(rng), Vec3(unit(rng), unit(rng), unit(rng) + 0.1).normalized()).toRotationMatrix();
  const double spread = unit(rng) < 0.02 ? 3e5 : 20.0;
  pose.t = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * spread;
  const double size = unit(rng) < 0.05 ? 5.0 * unit(rng) + 0.01 : 0.001 + 0.2 * unit(rng);
  const ObjectShape shape = rng() % 2 ? ObjectShape::sphere(size) : ObjectShape::box(Vec3(size, 0.5 * size, 2.0 * size));
  return make_collision_object(id, shape, pose);
}

bool boxes_meet(const Vec3& alo, const Vec3& ahi, const Vec3& blo, const Vec3& bhi) {
  return (alo.array() <= bhi.array()).all() && (blo.array() <= ahi.array()).all();
}

// The list against a vector of the same records: slots, ids, objects' shapes and box queries.
void expect_same(const ObjectList& list, const std::vector<CollisionObject>& oracle, std::mt19937_64& rng) {
  ASSERT_EQ(list.size(), oracle.size());
  std::vector<std::string> ids, expected;
  for (const CollisionObject& o : list) ids.push_back(o.id);
  for (const CollisionObject& o : oracle) expected.push_back(o.id);
  std::sort(ids.begin(), ids.end());
  std::sort(expected.begin(), expected.end());
  ASSERT_EQ(ids, expected);
  for (std::size_t s = 0; s < list.size(); ++s) {
    ASSERT_EQ(list.find(list[s].id), static_cast<std::ptrdiff_t>(s));
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int q = 0; q < 20; ++q) {
    const Vec3 c = Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5) * 24.0;
    const Vec3 r = Vec3::Constant(unit(rng) * 3.0);
    std::vector<std::string> got, want;
    list.for_each_meeting(c - r, c + r, [&](std::uint32_t slot) { got.push_back(list[slot].id); });
    for (const CollisionObject& o : oracle) {
      Vec3 lo, hi;
      object_world_box(o, lo, hi);
      if (boxes_meet(lo, hi, c - r, c + r)) want.push_back(o.id);
    }
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    ASSERT_EQ(got, want) << "query " << q;
  }
}

TEST(ObjectList, MatchesAVectorOfObjectsAndKeepsEverySnapshot) {
  std::mt19937_64 rng(11);
  ObjectList list;
  std::vector<CollisionObject> oracle;
  std::vector<std::pair<ObjectList, std::vector<CollisionObject>>> snapshots;
  const int steps = test::sized(6000);
  for (int step = 0; step < steps; ++step) {
    const int op = static_cast<int>(rng() % 10);
    // Objects of one shape ("o17") and of several ("m3#0", "m3#1", ...).
    const std::string name = (rng() % 4 == 0 ? "m" : "o") + std::to_string(rng() % 700);
    const std::string id = name[0] == 'm' ? name + "#" + std::to_string(rng() % 3) : name;
    if (op < 7) {
      CollisionObject o = random_object(rng, id);
      list.add(std::make_shared<const CollisionObject>(o));
      const auto it = std::find_if(oracle.begin(), oracle.end(), [&](const CollisionObject& x) { return x.id == id; });
      if (it != oracle.end()) {
        *it = o;
      } else {
        oracle.push_back(o);
      }
    } else if (op < 9) {
      const auto it = std::find_if(oracle.begin(), oracle.end(), [&](const CollisionObject& x) { return x.id == id; });
      ASSERT_EQ(list.remove(id), it != oracle.end());
      if (it != oracle.end()) oracle.erase(it);
    } else {
      const std::size_t before = oracle.size();
      oracle.erase(std::remove_if(oracle.begin(), oracle.end(), [&](const CollisionObject& x) { return object_name(x.id) == name; }),
                   oracle.end());
      ASSERT_EQ(list.remove_object(name), before - oracle.size());
    }
    if (step % 50 == 0) expect_same(list, oracle, rng);
    if (step % 400 == 0) snapshots.emplace_back(list, oracle);
  }
  expect_same(list, oracle, rng);
  for (const auto& [snap, expected] : snapshots) expect_same(snap, expected, rng);
  // The shapes of an object by name, against the oracle.
  for (int m = 0; m < 700; ++m) {
    const std::string name = "m" + std::to_string(m);
    std::vector<std::string> got, want;
    for (const std::uint32_t s : list.shapes_of(name)) got.push_back(list[s].id);
    for (const CollisionObject& o : oracle) {
      if (object_name(o.id) == name) want.push_back(o.id);
    }
    std::sort(got.begin(), got.end());
    std::sort(want.begin(), want.end());
    ASSERT_EQ(got, want) << name;
    EXPECT_EQ(list.has_object(name), !want.empty());
  }
}

// Adding the n-th object to an environment copies a number of nodes and entries that grows as
// log n: on main it copied the list of all n records (n entries), so the 20,000th add copied
// 20,000. The bound below holds at every add; the largest count also barely grows from the
// first thousand adds to the last (log32 n levels of the record vector and of the id map, one
// path of the box tree whose depth is set by the objects' size).
TEST(ObjectList, AddingTheNthObjectCopiesLogNNotN) {
  std::mt19937_64 rng(17);
  Environment env(0.05);
  const int n = test::sanitized() ? 5000 : 20000;
  std::size_t worst_first = 0, worst_last = 0, worst_nodes = 0;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    Transform pose;
    pose.t = Vec3(unit(rng), unit(rng), unit(rng)) * 30.0;
    env.add_object("s" + std::to_string(i), ObjectShape::sphere(0.01 + 0.05 * unit(rng)), pose);
    const PersistentWork& w = env.objects().last_work();
    ASSERT_LE(w.entries, 1200u) << "add " << i;
    worst_nodes = std::max(worst_nodes, w.nodes);
    (i < 1000 ? worst_first : worst_last) = std::max(i < 1000 ? worst_first : worst_last, w.entries);
  }
  std::cout << "entries copied per add, most: " << worst_first << " (adds 1-1000), " << worst_last << " (adds 1001-" << n
            << "); nodes: " << worst_nodes << "\n";
  EXPECT_LE(worst_nodes, 60u);
  EXPECT_LE(worst_last, 2 * worst_first) << "first thousand adds: " << worst_first << ", the rest: " << worst_last;
  // Replacing and removing one is bounded alike.
  env.add_object("s5", ObjectShape::box({0.1, 0.1, 0.1}), Transform());
  EXPECT_LE(env.objects().last_work().entries, 1200u);
  ASSERT_TRUE(env.remove_object("s7"));
  EXPECT_LE(env.objects().last_work().entries, 2400u);  // two paths: its own and the last slot's
  EXPECT_EQ(env.objects().size(), static_cast<std::size_t>(n - 1));
}

}  // namespace
}  // namespace bvh_collision
