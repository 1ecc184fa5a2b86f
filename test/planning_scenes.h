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

}  // namespace bvh_collision::test
