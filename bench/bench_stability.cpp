// Numerical stability, section 7 of the report (make bench): every named hard case (the shared
// suite of test/hard_cases.h plus the mesh-level cases of test_hard_cases.cpp) with the exact
// answer (CGAL's exact predicates and distances, or the construction), ours and FCL's; and the
// scale sweep: box pairs of 1 mm to 100 m, posed up to 1e4 m from the origin, at gaps from
// overlapping to a tenth of their size, with the largest distance error and wrong answers seen;
// and the cylinder cases: exact cylinders (ours) against FCL's Cylinderd, touching and just apart
// at 1 mm to 100 m, 1e4 m from the origin; and the load of a 400k-triangle mesh against FCL's build.
// Usage: bench_stability [OUTPUT_DIR] [--quick]
#include <chrono>
#include <cstdio>
#include <iostream>
#include <random>

#include "bench_util.h"
#include "bvh_collision/bvh/primitive_queries.h"
#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "cgal_oracle.h"
#include "fcl_oracle.h"
#include "hard_cases.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

using bench::Table;

std::string answer(bool collision) { return collision ? "collision" : "free"; }

TriangleMesh one_triangle(const Triangle& t) {
  TriangleMesh m;
  m.vertices = {t[0], t[1], t[2]};
  m.triangles = {{0, 1, 2}};
  return m;
}

struct Answers {
  bool collision = false;
  double distance = 0.0;
};

// Ours through the whole pipeline (hierarchy, traversal, triangle routines), as surfaces.
Answers ours(const TriangleMesh& a, const Transform& pa, const TriangleMesh& b, const Transform& pb, bool solids = false) {
  const auto ba = Bvh<Obb>::build(a), bb = Bvh<Obb>::build(b);
  CollisionRequest c;
  c.solids = solids;
  DistanceRequest d;
  d.solids = solids;
  return {collide(ba, pa, bb, pb, c).collision, distance(ba, pa, bb, pb, d).distance};
}

Answers fcl_answers(const TriangleMesh& a, const Transform& pa, const TriangleMesh& b, const Transform& pb) {
  const auto ma = test::fcl_model<fcl::OBBRSSd>(a), mb = test::fcl_model<fcl::OBBRSSd>(b);
  return {test::fcl_collide(ma, pa, mb, pb), std::max(0.0, test::fcl_distance(ma, pa, mb, pb))};
}

Triangle shifted(Triangle t, double offset) {
  for (int i = 0; i < 3; ++i) t[i] += Vec3::Constant(offset);
  return t;
}

void triangle_cases(const std::string& dir) {
  Table table("stability_triangles", "Hard cases: triangle pairs (exact answer by CGAL's exact predicates)",
              {"case", "true answer", "true distance", "ours", "ours distance", "FCL", "FCL distance",
               "true at +8192 m", "ours at +8192 m", "FCL at +8192 m"});
  int ours_wrong = 0, fcl_wrong = 0;
  for (const test::NamedCase& c : test::hard_cases()) {
    const Transform identity;
    const bool truth = test::cgal_triangles_intersect(c.a, c.b);
    const double exact = test::cgal_triangle_distance(c.a, c.b);
    const Answers o = ours(one_triangle(c.a), identity, one_triangle(c.b), identity);
    const Answers f = fcl_answers(one_triangle(c.a), identity, one_triangle(c.b), identity);
    const Triangle fa = shifted(c.a, 8192), fb = shifted(c.b, 8192);
    const bool far_truth = test::cgal_triangles_intersect(fa, fb);
    const Answers fo = ours(one_triangle(fa), identity, one_triangle(fb), identity);
    const Answers ff = fcl_answers(one_triangle(fa), identity, one_triangle(fb), identity);
    ours_wrong += (o.collision != truth) + (fo.collision != far_truth);
    fcl_wrong += (f.collision != truth) + (ff.collision != far_truth);
    table.row({c.name, answer(truth), exact, answer(o.collision), o.distance, answer(f.collision), f.distance,
               answer(far_truth), answer(fo.collision), answer(ff.collision)});
  }
  table.note("Wrong answers: ours " + std::to_string(ours_wrong) + ", FCL " + std::to_string(fcl_wrong) + " (of " +
             std::to_string(2 * test::hard_cases().size()) + "). Both as surfaces; the +8192 m columns move both triangles "
             "by an exact power of two, where CGAL gives the true answer again.");
  table.write(dir);
}

// Box b beside box a along x, a face gap of `gap` (negative: overlap), each with its own pose:
// b's pose is a's moved by (size + gap) along a's x, so the scene's offset reaches the relative
// transform as it does in a real scene. The true gap is what that shift leaves exactly.
struct BoxPair {
  TriangleMesh a, b;
  Transform pa, pb;
  double true_gap;
};

BoxPair box_pair(double size, double gap, double offset, const Mat3& rotation) {
  BoxPair p{box_mesh(Vec3::Constant(size)), box_mesh(Vec3::Constant(size)), {}, {}, 0.0};
  const double shift = size + gap;
  p.pa = Transform{rotation, Vec3(offset, -offset, offset) / std::sqrt(3.0)};
  p.pb = p.pa * Transform::Translation(Vec3(shift, 0, 0));
  p.true_gap = shift - size;  // exact (Sterbenz): shift and size are within a factor of two
  return p;
}

void mesh_cases(const std::string& dir) {
  Table table("stability_meshes", "Hard cases: meshes (exact answer by construction)",
              {"case", "true answer", "true distance", "ours", "ours distance", "FCL", "FCL distance"});
  const Mat3 identity = Mat3::Identity();
  auto add = [&](const std::string& name, const TriangleMesh& a, const Transform& pa, const TriangleMesh& b,
                 const Transform& pb, bool truth, double exact, bool solids) {
    const Answers o = ours(a, pa, b, pb, solids), f = fcl_answers(a, pa, b, pb);
    table.row({name, answer(truth), exact, answer(o.collision), o.distance, answer(f.collision), f.distance});
  };
  for (const double gap : {0.0, 1e-15, -1e-15}) {
    const BoxPair p = box_pair(1.0, gap, 0.0, identity);
    add(gap == 0 ? "1 m boxes, faces touching" : gap > 0 ? "1 m boxes, faces 1e-15 m apart" : "1 m boxes, faces overlapping by 1e-15 m",
        p.a, p.pa, p.b, p.pb, gap <= 0, std::max(0.0, p.true_gap), false);
  }
  std::mt19937_64 rng(11);
  const TriangleMesh big = test::bumpy_sphere(rng, 1.0, 16, 24, 0.05), small = test::bumpy_sphere(rng, 0.05, 6, 8, 0.1);
  add("5 cm closed mesh wholly inside a 1 m one (solids; FCL sees surfaces)", big, Transform(), small,
      Transform::Translation(Vec3(0.3, -0.2, 0.1)), true, 0.0, true);
  add("the same 1e4 m from the origin", big, Transform::Translation(Vec3::Constant(1e4)), small,
      Transform::Translation(Vec3(1e4 + 0.3, 1e4 - 0.2, 1e4 + 0.1)), true, 0.0, true);
  TriangleMesh needles;  // zero-area triangles (segments) piercing a box face
  for (int i = 0; i < 10; ++i) {
    const double y = -0.4 + 0.08 * i;
    const auto base = static_cast<std::int32_t>(needles.vertices.size());
    needles.vertices.insert(needles.vertices.end(), {Vec3(0.3, y, 0), Vec3(0.6, y, 0), Vec3(0.9, y, 0)});
    needles.triangles.push_back({base, base + 1, base + 2});
  }
  const TriangleMesh box = box_mesh(Vec3(1, 1, 1));
  add("zero-area triangles (segments) through a box face", box, Transform(), needles, Transform(), true, 0.0, false);
  add("the same segments 0.01 m clear of the face", box, Transform(), needles, Transform::Translation(Vec3(0.21, 0, 0)),
      false, 0.01, false);
  table.note("Distances are 0 for colliding pairs. FCL treats meshes as surfaces, so it reports the closed mesh inside "
             "another as free (docs/design.md counts it as a collision).");
  table.write(dir);
}

void scale_sweep(bool quick, const std::string& dir) {
  Table table("stability_scale", "Scale sweep: box pairs by size and distance from the origin",
              {"size m", "offset m", "ours largest distance error m", "ours largest error / size",
               "FCL largest distance error m", "FCL largest error / size", "ours wrong answers", "FCL wrong answers"});
  std::mt19937_64 rng(5);
  const Mat3 rotation = test::random_rotation(rng).R;  // generic: no exact arithmetic to lean on
  const std::vector<double> relative_gaps = {-1e-3, -1e-6, 1e-6, 1e-3, 0.1};
  double worst_ours = 0.0, worst_fcl = 0.0;
  int wrong_ours = 0, wrong_fcl = 0;
  for (const double size : {1e-3, 1e-2, 1e-1, 1.0, 10.0, 100.0}) {
    for (const double offset : quick ? std::vector<double>{0.0, 1e4} : std::vector<double>{0.0, 1.0, 1e2, 1e3, 1e4}) {
      double eo = 0.0, ef = 0.0;
      int wo = 0, wf = 0;
      for (const double g : relative_gaps) {
        const BoxPair p = box_pair(size, g * size, offset, rotation);
        const double truth = std::max(0.0, p.true_gap);
        const Answers o = ours(p.a, p.pa, p.b, p.pb), f = fcl_answers(p.a, p.pa, p.b, p.pb);
        eo = std::max(eo, std::abs(o.distance - truth));
        ef = std::max(ef, std::abs(f.distance - truth));
        wo += o.collision != (p.true_gap <= 0);
        wf += f.collision != (p.true_gap <= 0);
      }
      table.row({size, offset, eo, eo / size, ef, ef / size, static_cast<double>(wo), static_cast<double>(wf)});
      worst_ours = std::max(worst_ours, eo / size), worst_fcl = std::max(worst_fcl, ef / size);
      wrong_ours += wo, wrong_fcl += wf;
    }
  }
  table.note("Gaps of -1e-3, -1e-6, 1e-6, 1e-3 and 0.1 times the size (negative: overlapping); each box has its own "
             "pose (a generic rotation, the offset along (1, -1, 1)), so the offset's rounding reaches the relative pose. "
             "Largest error relative to the size: ours " + bench::format(worst_ours) + ", FCL " + bench::format(worst_fcl) +
             "; wrong answers: ours " + std::to_string(wrong_ours) + ", FCL " + std::to_string(wrong_fcl) + ".");
  table.write(dir);
}


// ------------------------------------------------------------------------------ cylinders

// A placed shape for the cylinder cases: a primitive, or a mesh (box_mesh).
struct Placed {
  Primitive primitive;
  bool mesh = false;
  Transform pose;
};

Answers ours_pair(const Placed& a, const Placed& b) {
  if (b.mesh) {  // a is the cylinder
    const TriangleMesh box = box_mesh(2.0 * half_extents(b.primitive));
    const Bvh<Obb> bvh = Bvh<Obb>::build(box);
    CollisionRequest c;
    c.solids = false;
    DistanceRequest d;
    d.solids = false;
    return {collide(bvh, b.pose, a.primitive, a.pose, c).collision, distance(bvh, b.pose, a.primitive, a.pose, d).distance};
  }
  const Transform rel = relative_transform(a.pose, b.pose);
  const ConvexShape sa = ConvexShape::of(a.primitive), sb = ConvexShape::of(b.primitive);
  return {convex_within(sa, sb, rel, 0.0), convex_distance(sa, sb, rel).distance};
}

std::shared_ptr<fcl::CollisionGeometryd> fcl_shape(const Placed& p) {
  const Vec3 h = half_extents(p.primitive);
  if (p.mesh) return test::fcl_model<fcl::OBBRSSd>(box_mesh(2.0 * h));
  switch (p.primitive.kind) {
    case Primitive::Kind::kSphere: return std::make_shared<fcl::Sphered>(p.primitive.radius);
    case Primitive::Kind::kBox: return std::make_shared<fcl::Boxd>(2.0 * h);
    case Primitive::Kind::kCylinder: return std::make_shared<fcl::Cylinderd>(p.primitive.radius, 2.0 * p.primitive.half_length);
    default: return std::make_shared<fcl::Capsuled>(p.primitive.radius, 2.0 * p.primitive.half_length);
  }
}

Answers fcl_pair(const Placed& a, const Placed& b) {
  fcl::CollisionObjectd oa(fcl_shape(a), test::fcl_transform(a.pose)), ob(fcl_shape(b), test::fcl_transform(b.pose));
  fcl::CollisionRequestd creq;
  fcl::CollisionResultd cres;
  fcl::collide(&oa, &ob, creq, cres);
  fcl::DistanceRequestd dreq;
  fcl::DistanceResultd dres;
  fcl::distance(&oa, &ob, dreq, dres);
  return {cres.isCollision(), std::max(0.0, dres.min_distance)};
}

// A cylinder of radius s/4 and length s at `offset` (axis along z), and the other shape placed
// `gap` beyond touching along x (side contacts) or z (cap contacts). Sizes are powers of two, so
// the contact extents (s/2, 3s/4, s) are exact; the true gap is what the placed centres leave,
// computed exactly ((x_b - x_a) and the extent are within a factor of two: Sterbenz).
void cylinder_cases(const std::string& dir) {
  Table table("stability_cylinders", "Hard cases: exact cylinders (URDF cylinders) against other shapes",
              {"case", "size m", "offset m", "true answer", "true distance", "ours", "ours distance", "FCL", "FCL distance"});
  int ours_wrong = 0, fcl_wrong = 0;
  double ours_error = 0.0, fcl_error = 0.0;
  for (const double s : {0x1p-10, 1.0, 0x1p7}) {
    for (const double offset : {0.0, 8192.0}) {
      const Vec3 o = Vec3::Constant(offset);
      const double r = s / 4, half = s / 2;
      const Placed cylinder{Primitive::cylinder(r, s), false, Transform::Translation(o)};
      for (const double relative_gap : {0.0, 0x1p-40, 0x1p-18}) {
        const double gap = relative_gap * s;
        struct Case {
          std::string name;
          Placed other;
          int axis;       // the shapes are apart along this axis
          double extent;  // centre distance along it at touching
        };
        const Case cases[] = {
            {"cylinder side to parallel cylinder side", {Primitive::cylinder(r, s), false, Transform::Translation(o + Vec3(2 * r + gap, 0, 0))}, 0, 2 * r},
            {"cylinder cap to cylinder cap", {Primitive::cylinder(r, s), false, Transform::Translation(o + Vec3(0.5 * r, 0, s + gap))}, 2, s},
            {"cylinder side to box face", {Primitive::box(Vec3::Constant(s)), false, Transform::Translation(o + Vec3(r + half + gap, 0, 0))}, 0, r + half},
            {"cylinder cap to sphere", {Primitive::sphere(r), false, Transform::Translation(o + Vec3(0, 0, half + r + gap))}, 2, half + r},
            {"cylinder side to mesh box face", {Primitive::box(Vec3::Constant(s)), true, Transform::Translation(o + Vec3(r + half + gap, 0, 0))}, 0, r + half},
        };
        for (const Case& c : cases) {
          const double true_gap = std::max(0.0, (c.other.pose.t[c.axis] - cylinder.pose.t[c.axis]) - c.extent);
          const bool truth = true_gap == 0.0;
          const Answers a = ours_pair(cylinder, c.other), f = fcl_pair(cylinder, c.other);
          ours_wrong += a.collision != truth;
          fcl_wrong += f.collision != truth;
          ours_error = std::max(ours_error, std::abs(a.distance - true_gap) / s);
          fcl_error = std::max(fcl_error, std::abs(f.distance - true_gap) / s);
          table.row({c.name + (truth ? ", touching" : ", apart"), s, offset, answer(truth), true_gap, answer(a.collision),
                     a.distance, answer(f.collision), f.distance});
        }
      }
    }
  }
  table.note("Sizes 2^-10 m (about 1 mm), 1 m and 128 m; gaps of 0, 2^-40 and 2^-18 times the size, 0 and 8192 m "
             "from the origin (where the smallest gaps round away: the true distance column says what is left). Ours: exact primitives (GJK on the exact support function with a "
             "certified lower bound, an exact decision at 0); FCL: its Cylinderd, Boxd and Sphered (GJK/EPA). Wrong answers: "
             "ours " + std::to_string(ours_wrong) + ", FCL " + std::to_string(fcl_wrong) + "; largest distance error / size: ours " +
             bench::format(ours_error) + ", FCL " + bench::format(fcl_error) + ".");
  table.write(dir);
}

// A 200,000-vertex closed mesh (400k triangles, a bumpy sphere): what a robot link of a scanned
// part costs to load, against FCL's build of the same triangles, same run (moved here from
// test_limits, which bounds the work instead of the time).
void large_mesh(bool quick, const std::string& dir) {
  std::mt19937_64 rng(5);
  const TriangleMesh ball = test::bumpy_sphere(rng, 0.1, quick ? 100 : 400, 500, 0.002);
  const std::string path = dir + "/large_mesh.stl";
  test::write_binary_stl(ball, path);
  const std::string urdf = "<robot name=\"large\"><link name=\"ball\"><collision><geometry><mesh filename=\"" + path +
                           "\"/></geometry></collision></link></robot>";
  const auto time = [](auto&& work, int repeats = 3) {
    std::vector<double> runs;
    for (int i = 0; i < repeats; ++i) {
      const auto start = std::chrono::steady_clock::now();
      work();
      runs.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return bench::spread(runs);
  };
  const bench::Spread robot = time([&] {
    RobotModel model = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver({}));
    AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
    const CollisionChecker checker(std::move(model), std::move(acm), {});
  }, 1);  // once: a process imports each file once and reuses it
  const bench::Spread tree = time([&] { Bvh<Obb>::build(ball); });
  const bench::Spread hull = time([&] { convex_hull(ball.vertices); });
  const bench::Spread fcl = time([&] { test::fcl_model<fcl::OBBRSSd>(ball); });
  std::remove(path.c_str());
  Table table("large_mesh", "Loading a large closed mesh (" + std::to_string(ball.vertices.size()) + " vertices, " +
                                 std::to_string(ball.triangles.size()) + " triangles)",
              {"what", "s (median of 3)", "min", "max", "/ FCL's build"});
  const auto row = [&](const std::string& what, const bench::Spread& s) {
    // (Built cell by cell: an initializer list of the variant makes GCC 12 warn of a string it
    // thinks may be read uninitialised.)
    std::vector<Table::Cell> cells;
    cells.emplace_back(std::in_place_type<std::string>, what);
    for (const double c : {s.median, s.low, s.high, s.median / fcl.median}) cells.emplace_back(std::in_place_type<double>, c);
    table.row(std::move(cells));
  };
  row("ours: a robot link, first load (read the STL, hierarchy, hull, closedness, solidity; one run)", robot);
  row("ours: the OBB hierarchy with its slack bounds", tree);
  row("ours: the convex hull", hull);
  row("FCL 0.7: BVHModel<OBBRSS> build", fcl);
  table.note("A bumpy sphere (200,000 vertices; --quick: 50,000). Before issue 19 this robot took minutes (a quadratic "
             "hull), then 11 s. make test bounds the work of the same load (Limits.LargeMeshLoadsWithBoundedWork).");
  table.write(dir);
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  std::cout << "# Numerical stability\n# Machine: " << bench::machine_description() << "\n";
  const std::string dir = bench::output_dir(argc, argv);
  triangle_cases(dir);
  mesh_cases(dir);
  scale_sweep(bench::quick_mode(argc, argv), dir);
  cylinder_cases(dir);
  large_mesh(bench::quick_mode(argc, argv), dir);
  return 0;
}
