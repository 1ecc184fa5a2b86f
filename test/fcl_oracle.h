// FCL as an independent oracle and baseline (test and benchmark dependency only).
#pragma once

#include <fcl/fcl.h>

#include <memory>

#include "bvh_collision/geometry/mesh.h"

namespace bvh_collision::test {

template <class FclBV>
std::shared_ptr<fcl::BVHModel<FclBV>> fcl_model(const TriangleMesh& mesh) {
  auto model = std::make_shared<fcl::BVHModel<FclBV>>();
  std::vector<fcl::Vector3d> points(mesh.vertices.begin(), mesh.vertices.end());
  std::vector<fcl::Triangle> triangles;
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);
  model->beginModel();
  model->addSubModel(points, triangles);
  model->endModel();
  return model;
}

inline fcl::Transform3d fcl_transform(const Transform& t) {
  fcl::Transform3d out = fcl::Transform3d::Identity();
  out.linear() = t.R;
  out.translation() = t.t;
  return out;
}

template <class FclBV>
bool fcl_collide(const std::shared_ptr<fcl::BVHModel<FclBV>>& a, const Transform& pa,
                 const std::shared_ptr<fcl::BVHModel<FclBV>>& b, const Transform& pb) {
  fcl::CollisionObjectd oa(a, fcl_transform(pa)), ob(b, fcl_transform(pb));
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(&oa, &ob, request, result);
  return result.isCollision();
}

template <class FclBV>
double fcl_distance(const std::shared_ptr<fcl::BVHModel<FclBV>>& a, const Transform& pa,
                    const std::shared_ptr<fcl::BVHModel<FclBV>>& b, const Transform& pb) {
  fcl::CollisionObjectd oa(a, fcl_transform(pa)), ob(b, fcl_transform(pb));
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  fcl::distance(&oa, &ob, request, result);
  return result.min_distance;
}

}  // namespace bvh_collision::test
