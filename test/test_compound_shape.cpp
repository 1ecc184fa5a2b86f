// A body of several shapes (narrowphase/compound_shape.h) against closed forms: compounds of
// balls and boxes, whose part distances are |c1 - c2| - r1 - r2 and a ball centre's distance to a
// box less its radius, so the compound's distance is their minimum, its collision that minimum at
// most the padding, its points and rays the balls' and boxes' own. One binary with
// test_environment.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "bvh_collision/narrowphase/compound_shape.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Parts in the compound frame: balls (centre, radius) and axis-aligned boxes (centre, half sizes).
struct Ball {
  Vec3 c;
  double r;
};
struct Block {
  Vec3 c, half;
};

struct Body {
  std::vector<Ball> balls;
  std::vector<Block> blocks;
  std::vector<CompoundPart> parts;
  std::vector<Bvh<Obb>> meshes;  // none: every part an exact primitive
  std::vector<ConvexHull> hulls;
  CompoundShape shape() const { return CompoundShape(parts, meshes, hulls); }
};

Body random_body(std::mt19937_64& rng, int balls, int blocks) {
  std::uniform_real_distribution<double> at(-0.2, 0.2), size(0.02, 0.08);
  Body b;
  for (int i = 0; i < balls; ++i) {
    b.balls.push_back({Vec3(at(rng), at(rng), at(rng)), size(rng)});
    CompoundPart p;
    p.origin.t = b.balls.back().c;
    p.primitive = Primitive::sphere(b.balls.back().r);
    b.parts.push_back(p);
  }
  for (int i = 0; i < blocks; ++i) {
    b.blocks.push_back({Vec3(at(rng), at(rng), at(rng)), Vec3(size(rng), size(rng), size(rng))});
    CompoundPart p;
    p.origin.t = b.blocks.back().c;
    p.primitive = Primitive::box(2.0 * b.blocks.back().half);
    b.parts.push_back(p);
  }
  return b;
}

// Distance from a world point to a placed block (the block's frame: its centre, the body's axes).
double point_block(const Vec3& p, const Block& k, const Transform& pose) {
  const Vec3 q = pose.R.transpose() * (p - pose * k.c);
  return (q.cwiseAbs() - k.half).cwiseMax(0.0).norm();
}

// The closed-form distance of a ball body (a) to a body of balls and blocks (b), both placed.
double closed_form_distance(const Body& a, const Transform& pa, const Body& b, const Transform& pb) {
  double best = kInf;
  for (const Ball& x : a.balls) {
    const Vec3 cx = pa * x.c;
    for (const Ball& y : b.balls) best = std::min(best, std::max(0.0, (cx - pb * y.c).norm() - x.r - y.r));
    for (const Block& k : b.blocks) best = std::min(best, std::max(0.0, point_block(cx, k, pb) - x.r));
  }
  return best;
}

TEST(CompoundShape, DistanceAndCollisionAreTheNearestPartsAgainstClosedForms) {
  std::mt19937_64 rng(7);
  int hits = 0, misses = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Body a = random_body(rng, 3, 0), b = random_body(rng, 2, 2);
    const Transform pa = test::random_rotation(rng, Vec3::Zero());
    std::uniform_real_distribution<double> off(-0.5, 0.5);
    const Transform pb = test::random_rotation(rng, Vec3(off(rng), off(rng), off(rng)));
    const double truth = closed_form_distance(a, pa, b, pb);
    QueryStats stats;
    Vec3 wa = Vec3::Constant(kInf), wb = wa;
    const double d = compounds_distance(a.shape(), pa, b.shape(), pb, kInf, true, wa, wb, stats);
    ASSERT_NEAR(d, truth, 1e-9) << "trial " << trial;
    if (truth > 0.0) {
      EXPECT_NEAR((wa - wb).norm(), truth, 1e-9);
    }
    // Below a bound under the truth nothing is found, and the witnesses stay as they were.
    if (truth > 0.01) {
      Vec3 ua = Vec3::Constant(kInf), ub = ua;
      EXPECT_GE(compounds_distance(a.shape(), pa, b.shape(), pb, truth - 0.005, true, ua, ub, stats), truth - 0.005);
      EXPECT_FALSE(ua.allFinite());
    }
    for (const double padding : {0.0, 0.02}) {
      PairRequest request;
      request.padding = padding;
      const bool expected = truth <= padding;
      const bool margin_case = std::abs(truth - padding) < 1e-9;
      if (margin_case) continue;
      EXPECT_EQ(compounds_collide(a.shape(), pa, b.shape(), pb, request, nullptr, stats), expected) << "trial " << trial;
      (expected ? hits : misses)++;
    }
  }
  EXPECT_GT(hits, 40);
  EXPECT_GT(misses, 40);
}

TEST(CompoundShape, ContactsStopAtTheRequestedCountEachFromAnOverlappingPair) {
  std::mt19937_64 rng(8);
  int full = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Body a = random_body(rng, 4, 0), b = random_body(rng, 4, 0);
    const Transform pa = Transform::Identity();
    std::uniform_real_distribution<double> off(-0.1, 0.1);
    const Transform pb = test::random_rotation(rng, Vec3(off(rng), off(rng), off(rng)));
    int overlapping = 0;  // ball pairs that overlap: each can give a contact
    for (const Ball& x : a.balls) {
      for (const Ball& y : b.balls) overlapping += (x.c - pb * y.c).norm() < x.r + y.r ? 1 : 0;
    }
    for (const std::size_t wanted : {std::size_t(1), std::size_t(3)}) {
      PairRequest request;
      request.max_contacts = wanted;
      std::vector<MeshContact> contacts;
      QueryStats stats;
      const bool hit = compounds_collide(a.shape(), pa, b.shape(), pb, request, &contacts, stats);
      EXPECT_EQ(hit, closed_form_distance(a, pa, b, pb) <= 0.0) << "trial " << trial;
      EXPECT_LE(contacts.size(), wanted);
      EXPECT_EQ(contacts.size(), std::min<std::size_t>(wanted, static_cast<std::size_t>(overlapping))) << "trial " << trial;
      full += contacts.size() == wanted ? 1 : 0;
      // Each contact is one overlapping ball pair's: the point of b's ball towards a's centre,
      // the depth their overlap.
      for (const MeshContact& c : contacts) {
        bool matched = false;
        for (const Ball& x : a.balls) {
          for (const Ball& y : b.balls) {
            const Vec3 cx = pa * x.c, cy = pb * y.c;
            const double gap = (cx - cy).norm();
            if (gap >= x.r + y.r) continue;
            const Vec3 on_b = cy + (cx - cy) / gap * y.r;
            matched = matched || ((c.position - on_b).norm() < 1e-9 && std::abs(c.depth - (x.r + y.r - gap)) < 1e-9);
          }
        }
        EXPECT_TRUE(matched) << "trial " << trial;
      }
    }
  }
  EXPECT_GT(full, 50);
}

TEST(CompoundShape, PointsAndRaysAreTheFirstPartsAgainstClosedForms) {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> at(-0.4, 0.4);
  int inside = 0, entered = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const Body b = random_body(rng, 3, 2);
    const Transform pose = test::random_rotation(rng, Vec3(at(rng), at(rng), at(rng)));
    std::uniform_real_distribution<double> near(-0.25, 0.25);
    const Vec3 p = pose * Vec3(near(rng), near(rng), near(rng));
    double truth = kInf;
    for (const Ball& y : b.balls) truth = std::min(truth, (p - pose * y.c).norm() - y.r);
    for (const Block& k : b.blocks) truth = std::min(truth, point_block(p, k, pose));
    const double padding = 0.01;
    if (std::abs(std::max(truth, 0.0) - padding) > 1e-9) {
      EXPECT_EQ(compound_holds_point(b.shape(), pose, p, padding), truth <= padding) << "trial " << trial;
      inside += truth <= padding ? 1 : 0;
    }
    // A ray towards the first ball's centre enters the compound no later than that ball.
    const Vec3 target = pose * b.balls[0].c;
    const Vec3 unit = (target - p).normalized();
    const double entry = compound_ray_entry(b.shape(), pose, p, unit, 10.0);
    if (truth > 0.0) {
      const double ball_entry = (target - p).norm() - b.balls[0].r;
      EXPECT_LE(entry, ball_entry + 1e-9);
      EXPECT_GE(entry, truth - 1e-9);  // nothing of the compound is nearer than its distance
      entered += std::isfinite(entry) ? 1 : 0;
      // The entry point lies on the compound.
      const Vec3 q = p + entry * unit;
      double there = kInf;
      for (const Ball& y : b.balls) there = std::min(there, std::abs((q - pose * y.c).norm() - y.r));
      for (const Block& k : b.blocks) there = std::min(there, point_block(q, k, pose));
      EXPECT_LE(there, 1e-9) << "trial " << trial;
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_GT(entered, 200);
}

TEST(CompoundShape, TheOctreeIsTheNearestOccupiedCubeOfAnyPart) {
  std::mt19937_64 rng(10);
  Octree tree(0.05);
  std::uniform_real_distribution<double> at(-0.6, 0.6);
  for (int i = 0; i < 60; ++i) tree.update(*tree.grid().key(Vec3(at(rng), at(rng), at(rng))), tree.model().clamp_max);
  const std::vector<Octree::Leaf> leaves = tree.leaves();
  int hits = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Body a = random_body(rng, 3, 0);
    const Transform pose = test::random_rotation(rng, Vec3(at(rng), at(rng), at(rng)));
    double truth = kInf;
    for (const Octree::Leaf& leaf : leaves) {
      if (!tree.occupied(leaf.log_odds)) continue;
      const Vec3 lo = tree.cube_min(leaf.key), hi = lo + Vec3::Constant(tree.cube_size(leaf.depth));
      for (const Ball& x : a.balls) {
        const Vec3 c = pose * x.c;
        truth = std::min(truth, std::max(0.0, (c - c.cwiseMax(lo).cwiseMin(hi)).norm() - x.r));
      }
    }
    QueryStats stats;
    const OctreeDistance d = compound_octree_distance(a.shape(), pose, tree, true, kInf, stats);
    ASSERT_NEAR(d.distance, truth, 1e-9) << "trial " << trial;
    PairRequest request;
    request.padding = 0.02;
    if (std::abs(truth - request.padding) < 1e-9) continue;
    OctreeContact contact;
    const bool hit = compound_meets_octree(a.shape(), pose, tree, request, &contact, stats);
    EXPECT_EQ(hit, truth <= request.padding) << "trial " << trial;
    hits += hit ? 1 : 0;
    if (hit) {
      EXPECT_TRUE(tree.occupied(contact.voxel.log_odds));
    }
  }
  EXPECT_GT(hits, 20);
}

}  // namespace
}  // namespace bvh_collision
