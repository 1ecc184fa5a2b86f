// MoveIt-style planning scenes for panda, generated from a seed: tables, shelves of several
// boards, boxes open on one side, cages of bars, and loose clutter, placed at random around the
// robot (never on its base), each built from shape_msgs-like boxes, cylinders and spheres. What
// the planning benchmark (bench/bench_planning.cpp) and the planning fast-path tests use; each
// scene is a SceneFile (io/scene_file.h), written as MoveIt `.scene` text so that other
// tools can read the same problems.
#pragma once

#include <cmath>
#include <cstdio>
#include <ostream>
#include <random>
#include <string>
#include <vector>

#include "bvh_collision/io/scene_file.h"

namespace bvh_collision::test {

// A generated scene: its objects' shapes posed in the world (each object at the identity), as
// MoveIt keeps them; io/scene_file.h writes it as `.scene` text.
using PlanningScene = SceneFile;

namespace scene_detail {

inline Transform yawed(double x, double y, double z, double yaw) {
  Transform t;
  t.R = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix();
  t.t = Vec3(x, y, z);
  return t;
}

// A shape at `local` in a frame `frame` (the object's placement).
inline SceneShape placed(const Transform& frame, const ObjectShape& shape, const Vec3& local) {
  Transform at;
  at.R = Mat3::Identity();
  at.t = local;
  return {shape, frame * at};
}

class Generator {
 public:
  explicit Generator(std::uint64_t seed) : rng_(seed) {}
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng_); }

  // Somewhere around the robot at `distance` from its base, facing it (x towards the robot).
  Transform around(double distance, double z) {
    const double azimuth = uniform(-M_PI, M_PI);
    return yawed(distance * std::cos(azimuth), distance * std::sin(azimuth), z, azimuth + M_PI);
  }

  SceneObject table(const std::string& id) {
    const double w = uniform(0.4, 0.8), d = uniform(0.4, 0.7), h = uniform(-0.3, 0.35), top = uniform(0.02, 0.05);
    const Transform f = around(uniform(0.45, 0.75) + d / 2, h);
    SceneObject o{id, Transform(), {placed(f, ObjectShape::box({d, w, top}), {0, 0, -top / 2})}, ""};
    const double leg = 0.04, height = h + 0.6;  // legs to 0.6 m below the base
    for (const int sx : {-1, 1}) {
      for (const int sy : {-1, 1}) {
        o.shapes.push_back(placed(f, ObjectShape::box({leg, leg, height}), {sx * (d / 2 - leg), sy * (w / 2 - leg), -top - height / 2}));
      }
    }
    return o;
  }

  SceneObject shelf(const std::string& id) {
    const double w = uniform(0.4, 0.9), d = uniform(0.25, 0.4), board = uniform(0.015, 0.03);
    const int boards = integer(2, 4);
    const double gap = uniform(0.22, 0.35), bottom = uniform(-0.2, 0.3);
    const double height = boards * gap;
    const Transform f = around(uniform(0.5, 0.8) + d / 2, bottom);
    SceneObject o{id, Transform(), {}, ""};
    for (int b = 0; b <= boards; ++b) o.shapes.push_back(placed(f, ObjectShape::box({d, w, board}), {0, 0, b * gap}));
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({d, board, height}), {0, s * (w / 2 + board / 2), height / 2}));
    o.shapes.push_back(placed(f, ObjectShape::box({board, w, height}), {d / 2 + board / 2, 0, height / 2}));  // the back
    return o;
  }

  // A box open towards the robot (or open on top): bottom and four or three walls.
  SceneObject open_box(const std::string& id) {
    const double w = uniform(0.2, 0.45), d = uniform(0.2, 0.4), h = uniform(0.15, 0.35), t = uniform(0.01, 0.02);
    const Transform f = around(uniform(0.4, 0.7) + d / 2, uniform(-0.1, 0.45));
    const bool open_top = integer(0, 1) == 0;
    SceneObject o{id, Transform(), {placed(f, ObjectShape::box({d, w, t}), {0, 0, t / 2})}, ""};
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({d, t, h}), {0, s * (w / 2 - t / 2), h / 2}));
    o.shapes.push_back(placed(f, ObjectShape::box({t, w, h}), {d / 2 - t / 2, 0, h / 2}));
    if (open_top) {
      o.shapes.push_back(placed(f, ObjectShape::box({t, w, h}), {-d / 2 + t / 2, 0, h / 2}));
    } else {
      o.shapes.push_back(placed(f, ObjectShape::box({d, w, t}), {0, 0, h - t / 2}));  // the lid: open towards the robot
    }
    return o;
  }

  // Vertical bars on a rectangle with a rail of horizontal bars on top: thin obstacles a
  // discrete check steps over.
  SceneObject cage(const std::string& id) {
    const double w = uniform(0.3, 0.6), d = uniform(0.25, 0.5), h = uniform(0.3, 0.7), r = uniform(0.005, 0.015);
    const Transform f = around(uniform(0.4, 0.75) + d / 2, uniform(-0.2, 0.2));
    const int per_side = integer(2, 4);
    SceneObject o{id, Transform(), {}, ""};
    for (int i = 0; i < per_side; ++i) {
      const double y = -w / 2 + w * i / (per_side - 1);
      for (const int sx : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::cylinder(r, h), {sx * d / 2, y, h / 2}));
    }
    Transform along_y;
    along_y.R = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()).toRotationMatrix();
    for (const int sx : {-1, 1}) {
      SceneShape rail = placed(f, ObjectShape::cylinder(r, w), {sx * d / 2, 0, h});
      rail.pose.R = rail.pose.R * along_y.R;
      o.shapes.push_back(rail);
    }
    return o;
  }

  // ---- Furniture in a frame whose x axis points away from the robot (its back at +x) ----

  // A frame at `distance` from the base towards `azimuth`, at height z, facing away from the base.
  static Transform away(double distance, double azimuth, double z) {
    return yawed(distance * std::cos(azimuth), distance * std::sin(azimuth), z, azimuth);
  }

  // A table top of d x w (its top at the frame's z) on four legs down to the floor at `floor`.
  SceneObject table_at(const std::string& id, const Transform& f, double d, double w, double floor) {
    const double top = uniform(0.02, 0.04), leg = 0.04, height = f.t.z() - top - floor;
    SceneObject o{id, Transform(), {placed(f, ObjectShape::box({d, w, top}), {0, 0, -top / 2})}, ""};
    for (const int sx : {-1, 1}) {
      for (const int sy : {-1, 1}) {
        o.shapes.push_back(placed(f, ObjectShape::box({leg, leg, height}), {sx * (d / 2 - leg), sy * (w / 2 - leg), -top - height / 2}));
      }
    }
    return o;
  }

  // Shelves: `boards` + 1 boards of thickness t, `gap` apart from the frame's z up, two sides and
  // a back; `target` between two boards, in the middle.
  SceneObject shelf_at(const std::string& id, const Transform& f, double d, double w, int boards, double gap, double t,
                       Vec3* target) {
    SceneObject o{id, Transform(), {}, ""};
    const double height = boards * gap;
    for (int b = 0; b <= boards; ++b) o.shapes.push_back(placed(f, ObjectShape::box({d, w, t}), {0, 0, b * gap}));
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({d, t, height}), {0, s * (w / 2 + t / 2), height / 2}));
    o.shapes.push_back(placed(f, ObjectShape::box({t, w, height}), {d / 2 + t / 2, 0, height / 2}));
    if (target != nullptr) *target = f * Vec3(0.0, uniform(-w / 4, w / 4), (integer(0, boards - 1) + 0.5) * gap);
    return o;
  }

  // A cabinet of d x w x h open towards the robot (bottom, top, sides, back).
  SceneObject cabinet_at(const std::string& id, const Transform& f, double d, double w, double h, double t) {
    SceneObject o{id, Transform(), {}, ""};
    for (const double z : {t / 2, h - t / 2}) o.shapes.push_back(placed(f, ObjectShape::box({d, w, t}), {0, 0, z}));
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({d, t, h}), {0, s * (w / 2 - t / 2), h / 2}));
    o.shapes.push_back(placed(f, ObjectShape::box({t, w, h}), {d / 2 - t / 2, 0, h / 2}));
    return o;
  }

  // ---- Harder fixtures for panda: thin boards, dense bars, a drawer; `target` inside each ----

  SceneObject thin_shelf(const std::string& id, Vec3* target) {
    const double d = uniform(0.25, 0.35), w = uniform(0.4, 0.7);
    const Transform f = away(uniform(0.45, 0.6) + d / 2, uniform(-M_PI, M_PI), uniform(-0.1, 0.2));
    return shelf_at(id, f, d, w, integer(2, 3), uniform(0.18, 0.25), uniform(0.004, 0.008), target);
  }

  SceneObject dense_cage(const std::string& id, Vec3* target) {
    const double w = uniform(0.3, 0.45), d = uniform(0.3, 0.4), h = uniform(0.35, 0.55), r = uniform(0.003, 0.006);
    const Transform f = away(uniform(0.4, 0.55) + d / 2, uniform(-M_PI, M_PI), uniform(-0.15, 0.15));
    const int per_side = integer(4, 6);
    SceneObject o{id, Transform(), {}, ""};
    for (int i = 0; i < per_side; ++i) {
      const double y = -w / 2 + w * i / (per_side - 1);
      for (const int sx : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::cylinder(r, h), {sx * d / 2, y, h / 2}));
    }
    for (int i = 1; i + 1 < per_side; ++i) {  // bars across the top
      SceneShape bar = placed(f, ObjectShape::cylinder(r, d), {0, -w / 2 + w * i / (per_side - 1), h});
      bar.pose.R = bar.pose.R * Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
      o.shapes.push_back(bar);
    }
    *target = f * Vec3(0.0, 0.0, h * uniform(0.3, 0.6));
    return o;
  }

  // A cabinet with its drawer pulled out towards the robot; the target in the drawer.
  SceneObject drawer(const std::string& id, Vec3* target) {
    const double d = uniform(0.35, 0.45), w = uniform(0.4, 0.6), h = uniform(0.5, 0.8), t = 0.015;
    const double out = uniform(0.2, 0.3), dh = uniform(0.08, 0.14), z0 = uniform(0.1, 0.3);
    const Transform f = away(uniform(0.55, 0.75) + d / 2, uniform(-M_PI, M_PI), uniform(-0.4, -0.2));
    SceneObject o = cabinet_at(id, f, d, w, h, t);
    const double x0 = -d / 2 - out / 2 + 0.05;  // the drawer's centre: mostly out of the cabinet
    o.shapes.push_back(placed(f, ObjectShape::box({out + 0.1, w - 2 * t, 0.01}), {x0, 0, z0}));
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({out + 0.1, 0.01, dh}), {x0, s * (w / 2 - t - 0.005), z0 + dh / 2}));
    for (const int s : {-1, 1}) o.shapes.push_back(placed(f, ObjectShape::box({0.01, w - 2 * t, dh}), {x0 + s * (out + 0.1) / 2, 0, z0 + dh / 2}));
    *target = f * Vec3(x0, 0.0, z0 + dh + 0.05);
    return o;
  }

  SceneObject clutter(const std::string& id) {
    const Transform f = around(uniform(0.35, 0.8), uniform(-0.1, 0.8));
    switch (integer(0, 2)) {
      case 0: return {id, Transform(), {placed(f, ObjectShape::sphere(uniform(0.02, 0.08)), Vec3::Zero())}, ""};
      case 1: return {id, Transform(), {placed(f, ObjectShape::cylinder(uniform(0.01, 0.05), uniform(0.05, 0.3)), Vec3::Zero())}, ""};
      default: return {id, Transform(), {placed(f, ObjectShape::box({uniform(0.03, 0.15), uniform(0.03, 0.15), uniform(0.03, 0.15)}), Vec3::Zero())}, ""};
    }
  }

 private:
  std::mt19937_64 rng_;
};

}  // namespace scene_detail

// Scene `index` of the generator with `seed`: a mix of furniture and clutter with 20 to 60
// shapes. Nothing is placed within 0.3 m of the base's axis below 0.9 m (the base's own space).
inline PlanningScene generate_scene(std::uint64_t seed, int index) {
  scene_detail::Generator g(seed * 1000003 + static_cast<std::uint64_t>(index));
  PlanningScene scene;
  scene.name = "panda_scene_" + std::to_string(index);
  int n = 0;
  auto next = [&](const char* what) { return std::string(what) + "_" + std::to_string(n++); };
  const int kind = index % 4;
  if (kind == 0 || g.integer(0, 2) == 0) scene.objects.push_back(g.table(next("table")));
  if (kind == 1 || g.integer(0, 2) == 0) scene.objects.push_back(g.shelf(next("shelf")));
  if (kind == 2 || g.integer(0, 2) == 0) scene.objects.push_back(g.open_box(next("box")));
  if (kind == 3 || g.integer(0, 2) == 0) scene.objects.push_back(g.cage(next("cage")));
  while (scene.shape_count() < 20 || (scene.shape_count() < 60 && g.integer(0, 3) != 0)) {
    scene.objects.push_back(g.integer(0, 3) == 0 ? g.cage(next("cage")) : g.clutter(next("clutter")));
  }
  while (scene.shape_count() > 60) scene.objects.pop_back();
  return scene;
}

// A harder panda scene: one fixture a hand must reach into (a shelf of thin boards, a dense cage
// of thin bars, or a drawer pulled out of a cabinet), then furniture and clutter as above to 20-60
// shapes. `target` (world) is a point inside the fixture that goals are drawn towards.
inline PlanningScene hard_scene(std::uint64_t seed, int index, Vec3* target) {
  scene_detail::Generator g(seed * 1000003 + static_cast<std::uint64_t>(index) + 500009);
  PlanningScene scene;
  scene.name = "panda_hard_scene_" + std::to_string(index);
  int n = 0;
  auto next = [&](const char* what) { return std::string(what) + "_" + std::to_string(n++); };
  switch (index % 3) {
    case 0: scene.objects.push_back(g.thin_shelf(next("thin_shelf"), target)); break;
    case 1: scene.objects.push_back(g.dense_cage(next("dense_cage"), target)); break;
    default: scene.objects.push_back(g.drawer(next("drawer"), target)); break;
  }
  if (g.integer(0, 1) == 0) scene.objects.push_back(g.table(next("table")));
  while (scene.shape_count() < 20 || (scene.shape_count() < 60 && g.integer(0, 3) != 0)) scene.objects.push_back(g.clutter(next("clutter")));
  while (scene.shape_count() > 60) scene.objects.pop_back();
  return scene;
}

// A scene around both of pr2's arms (its base at the origin, the floor at z = 0, shoulders at
// y = +-0.19 m and 0.8-1.1 m high): a table in front with a cabinet on it between the arms,
// shelves on each side, clutter on the table. `target` is inside one of them (goals are drawn
// towards it).
inline PlanningScene pr2_scene(std::uint64_t seed, int index, Vec3* target) {
  scene_detail::Generator g(seed * 1000003 + static_cast<std::uint64_t>(index) + 700001);
  using G = scene_detail::Generator;
  PlanningScene scene;
  scene.name = "pr2_scene_" + std::to_string(index);
  const double td = g.uniform(0.5, 0.7), tw = g.uniform(0.9, 1.3), top = g.uniform(0.6, 0.8);
  const Transform table = G::away(g.uniform(0.5, 0.65) + td / 2, g.uniform(-0.15, 0.15), top);
  scene.objects.push_back(g.table_at("table", table, td, tw, 0.0));
  const double cd = g.uniform(0.25, 0.35), cw = g.uniform(0.3, 0.45), ch = g.uniform(0.25, 0.4);
  const Transform cabinet = table * scene_detail::yawed(td / 2 - cd / 2 - 0.02, g.uniform(-0.1, 0.1), 0.0, 0.0);
  scene.objects.push_back(g.cabinet_at("cabinet", cabinet, cd, cw, ch, 0.015));
  Vec3 shelf_target[2];
  for (const int side : {0, 1}) {
    const double sd = g.uniform(0.3, 0.4), sw = g.uniform(0.5, 0.8);
    const double azimuth = (side == 0 ? 1 : -1) * g.uniform(1.2, 1.6);  // to the left, to the right
    const Transform f = G::away(g.uniform(0.6, 0.75) + sd / 2, azimuth, g.uniform(0.5, 0.75));
    scene.objects.push_back(g.shelf_at(side == 0 ? "shelf_left" : "shelf_right", f, sd, sw, g.integer(2, 3),
                                       g.uniform(0.25, 0.32), g.uniform(0.015, 0.025), &shelf_target[side]));
  }
  for (int k = 0; scene.shape_count() < 30 && k < 12; ++k) {  // clutter on the table
    const Transform at = table * scene_detail::yawed(g.uniform(-td / 2 + 0.05, td / 2 - cd - 0.05), g.uniform(-tw / 2 + 0.05, tw / 2 - 0.05), 0.0,
                                                     g.uniform(-M_PI, M_PI));
    const double size = g.uniform(0.03, 0.1);
    const ObjectShape shape = g.integer(0, 1) == 0 ? ObjectShape::box({size, size, 2 * size}) : ObjectShape::cylinder(size / 2, 2 * size);
    scene.objects.push_back({"clutter_" + std::to_string(k), Transform(), {scene_detail::placed(at, shape, {0, 0, size})}, ""});
  }
  switch (index % 4) {
    case 0: *target = shelf_target[0]; break;
    case 1: *target = shelf_target[1]; break;
    case 2: *target = cabinet * Vec3(0.0, 0.0, ch / 2); break;
    default: *target = table * Vec3(g.uniform(-0.1, 0.1), g.uniform(-0.3, 0.3), 0.15); break;
  }
  return scene;
}

}  // namespace bvh_collision::test
