// A robot and a planning scene as MoveIt hands them to FCL, for bench_planning's FCL rows and its
// re-check of every path: link meshes as BVHModel<OBBRSS>, URDF primitives as FCL's, the checked
// pairs each behind an AABB test, the scene's primitive objects in a dynamic AABB tree.
#pragma once

#include <fcl/fcl.h>

#include <memory>
#include <stdexcept>
#include <vector>

#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/query/collision_checker.h"
#include "fcl_oracle.h"

namespace bvh_collision {

// The links' geometry as MoveIt gives it to FCL, built once for every scene: meshes as
// BVHModel<OBBRSS>, URDF boxes, spheres and cylinders as FCL's primitives.
using FclLinkModels = std::vector<std::shared_ptr<fcl::CollisionGeometryd>>;
FclLinkModels fcl_link_models(const RobotModel& model) {
  FclLinkModels out;
  for (const RobotLink& link : model.links()) {
    for (const CollisionElement& e : link.collision) {
      switch (e.shape) {
        case ShapeKind::kBox: out.push_back(std::make_shared<fcl::Boxd>(e.size.x(), e.size.y(), e.size.z())); break;
        case ShapeKind::kSphere: out.push_back(std::make_shared<fcl::Sphered>(e.radius)); break;
        case ShapeKind::kCylinder: out.push_back(std::make_shared<fcl::Cylinderd>(e.radius, e.length)); break;
        default: out.push_back(test::fcl_model<fcl::OBBRSSd>(*e.mesh)); break;
      }
    }
  }
  return out;
}

class FclRobot {
 public:
  FclRobot(const CollisionChecker& checker, const FclLinkModels& models, const SceneFile& scene) : checker_(checker) {
    const RobotModel& model = checker.model();
    std::size_t k = 0;
    for (std::size_t l = 0; l < model.links().size(); ++l) {
      for (const CollisionElement& e : model.links()[l].collision) {
        links_.push_back({static_cast<int>(l), e.origin, std::make_unique<fcl::CollisionObjectd>(models[k++])});
      }
    }
    of_link_.resize(model.links().size());
    for (std::size_t i = 0; i < links_.size(); ++i) of_link_[static_cast<std::size_t>(links_[i].link)].push_back(i);
    for (const SceneObject& o : scene.objects) {
      for (const SceneShape& s : o.shapes) world_.push_back(std::make_unique<fcl::CollisionObjectd>(geometry(s.shape), test::fcl_transform(o.pose * s.pose)));
    }
    for (auto& w : world_) {
      w->computeAABB();
      manager_.registerObject(w.get());
    }
    manager_.setup();
  }

  bool collides(const double* state) {
    forward_kinematics(checker_.model(), state, poses_);
    for (LinkObject& l : links_) {
      l.object->setTransform(test::fcl_transform(poses_[l.link] * l.origin));
      l.object->computeAABB();
    }
    // The checked pairs, each behind the AABB test MoveIt's broad phase gives it.
    for (const auto& [a, b] : checker_.checked_pairs()) {
      for (const std::size_t ia : of_link_[a]) {
        const fcl::CollisionObjectd& oa = *links_[ia].object;
        for (const std::size_t ib : of_link_[b]) {
          const fcl::CollisionObjectd& ob = *links_[ib].object;
          if (!oa.getAABB().overlap(ob.getAABB())) continue;
          fcl::CollisionRequestd request;
          fcl::CollisionResultd result;
          if (fcl::collide(&oa, &ob, request, result) > 0) return true;
        }
      }
    }
    for (LinkObject& l : links_) {
      fcl::DefaultCollisionData<double> data;
      manager_.collide(l.object.get(), &data, fcl::DefaultCollisionFunction<double>);
      if (data.result.isCollision()) return true;
    }
    return false;
  }

 private:
  static std::shared_ptr<fcl::CollisionGeometryd> geometry(const ObjectShape& s) {
    switch (s.kind) {
      case ObjectShape::Kind::kBox: return std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
      case ObjectShape::Kind::kSphere: return std::make_shared<fcl::Sphered>(s.radius);
      case ObjectShape::Kind::kCylinder: return std::make_shared<fcl::Cylinderd>(s.radius, s.length);
      default: throw std::logic_error("the scene generator makes boxes, spheres and cylinders only");
    }
  }
  struct LinkObject {
    int link;
    Transform origin;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  const CollisionChecker& checker_;
  std::vector<LinkObject> links_;
  std::vector<std::vector<std::size_t>> of_link_;  // per link, its entries of links_
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> world_;
  fcl::DynamicAABBTreeCollisionManagerd manager_;
  std::vector<Transform> poses_;
};

}  // namespace bvh_collision
