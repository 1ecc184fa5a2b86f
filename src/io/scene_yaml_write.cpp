// A SceneFile written as a moveit_msgs/PlanningScene in YAML (io/scene_file.h), in the
// spelling `rostopic echo` uses: shape types as shape_msgs numbers, points and quaternions as maps.
#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "bvh_collision/io/scene_file.h"

namespace bvh_collision {

namespace {

// shape_msgs/SolidPrimitive's types.
enum PrimitiveType { kBox = 1, kSphere = 2, kCylinder = 3, kCone = 4 };

void emit_pose(YAML::Emitter& e, const Transform& t) {
  const Eigen::Quaterniond q(t.R);
  e << YAML::Flow << YAML::BeginMap;
  e << YAML::Key << "position" << YAML::Value << YAML::BeginMap << YAML::Key << "x" << YAML::Value << t.t.x() << YAML::Key << "y"
    << YAML::Value << t.t.y() << YAML::Key << "z" << YAML::Value << t.t.z() << YAML::EndMap;
  e << YAML::Key << "orientation" << YAML::Value << YAML::BeginMap << YAML::Key << "x" << YAML::Value << q.x() << YAML::Key << "y"
    << YAML::Value << q.y() << YAML::Key << "z" << YAML::Value << q.z() << YAML::Key << "w" << YAML::Value << q.w() << YAML::EndMap;
  e << YAML::EndMap;
}

// shape_msgs/SolidPrimitive's type and dimensions (a cylinder's and a cone's height first).
void emit_primitive(YAML::Emitter& e, const ObjectShape& s) {
  int type = 0;
  std::vector<double> dims;
  switch (s.kind) {
    case ObjectShape::Kind::kBox: type = kBox, dims = {s.size.x(), s.size.y(), s.size.z()}; break;
    case ObjectShape::Kind::kSphere: type = kSphere, dims = {s.radius}; break;
    case ObjectShape::Kind::kCylinder: type = kCylinder, dims = {s.length, s.radius}; break;
    case ObjectShape::Kind::kCone: type = kCone, dims = {s.length, s.radius}; break;
    case ObjectShape::Kind::kCapsule:
    case ObjectShape::Kind::kMesh: throw std::invalid_argument("a capsule has no shape_msgs form");
  }
  e << YAML::Flow << YAML::BeginMap << YAML::Key << "type" << YAML::Value << type << YAML::Key << "dimensions" << YAML::Value
    << YAML::Flow << dims << YAML::EndMap;
}

void emit_mesh(YAML::Emitter& e, const TriangleMesh& m) {
  e << YAML::BeginMap << YAML::Key << "vertices" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const Vec3& v : m.vertices) {
    e << YAML::Flow << YAML::BeginMap << YAML::Key << "x" << YAML::Value << v.x() << YAML::Key << "y" << YAML::Value << v.y()
      << YAML::Key << "z" << YAML::Value << v.z() << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::Key << "triangles" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const auto& t : m.triangles) {
    e << YAML::Flow << YAML::BeginMap << YAML::Key << "vertex_indices" << YAML::Value << YAML::Flow
      << std::vector<int>{t[0], t[1], t[2]} << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::EndMap;
}

void emit_object(YAML::Emitter& e, const SceneObject& o) {
  auto is_mesh = [](const SceneShape& s) { return s.shape.kind == ObjectShape::Kind::kMesh; };
  e << YAML::BeginMap << YAML::Key << "id" << YAML::Value << o.id;
  e << YAML::Key << "header" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "frame_id" << YAML::Value << o.frame_id
    << YAML::EndMap;
  e << YAML::Key << "pose" << YAML::Value;
  emit_pose(e, o.pose);
  for (const bool meshes : {false, true}) {
    e << YAML::Key << (meshes ? "meshes" : "primitives") << YAML::Value << YAML::BeginSeq;
    for (const SceneShape& s : o.shapes) {
      if (is_mesh(s) != meshes) continue;
      meshes ? emit_mesh(e, *s.shape.mesh) : emit_primitive(e, s.shape);
    }
    e << YAML::EndSeq << YAML::Key << (meshes ? "mesh_poses" : "primitive_poses") << YAML::Value << YAML::BeginSeq;
    for (const SceneShape& s : o.shapes) {
      if (is_mesh(s) == meshes) emit_pose(e, s.pose);
    }
    e << YAML::EndSeq;
  }
  std::vector<std::string> subframe_names;
  for (const auto& [name, pose] : o.subframes) subframe_names.push_back(name);
  e << YAML::Key << "subframe_names" << YAML::Value << YAML::Flow << subframe_names;
  e << YAML::Key << "subframe_poses" << YAML::Value << YAML::BeginSeq;
  for (const auto& [name, pose] : o.subframes) emit_pose(e, pose);
  e << YAML::EndSeq;
  // moveit_msgs/CollisionObject's constants: ADD 0, REMOVE 1, APPEND 2, MOVE 3.
  const int operation = o.operation == SceneOperation::kAdd      ? 0
                        : o.operation == SceneOperation::kRemove ? 1
                        : o.operation == SceneOperation::kAppend ? 2
                                                                 : 3;
  e << YAML::Key << "operation" << YAML::Value << operation << YAML::EndMap;
}

void emit_attached(YAML::Emitter& e, const SceneAttachedObject& a) {
  e << YAML::BeginMap << YAML::Key << "link_name" << YAML::Value << a.link;
  e << YAML::Key << "object" << YAML::Value;
  emit_object(e, a.object);
  e << YAML::Key << "touch_links" << YAML::Value << YAML::Flow << a.touch_links << YAML::EndMap;
}

// The pairs as MoveIt's matrix: every name once, a pair not listed not allowed; the defaults.
void emit_matrix(YAML::Emitter& e, const std::vector<AllowedCollision>& pairs, const std::vector<std::pair<std::string, bool>>& defaults) {
  std::vector<std::string> names;
  for (const AllowedCollision& p : pairs) names.insert(names.end(), {p.a, p.b});
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  const auto at = [&](const std::string& n) { return static_cast<std::size_t>(std::lower_bound(names.begin(), names.end(), n) - names.begin()); };
  std::vector<std::vector<bool>> enabled(names.size(), std::vector<bool>(names.size(), false));
  for (const AllowedCollision& p : pairs) enabled[at(p.a)][at(p.b)] = enabled[at(p.b)][at(p.a)] = p.allowed;
  e << YAML::BeginMap << YAML::Key << "entry_names" << YAML::Value << YAML::Flow << names;
  e << YAML::Key << "entry_values" << YAML::Value << YAML::BeginSeq;
  for (const auto& row : enabled) e << YAML::Flow << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value << YAML::Flow << row << YAML::EndMap;
  e << YAML::EndSeq;
  std::vector<std::string> default_names;
  std::vector<bool> default_values;
  for (const auto& [name, allowed] : defaults) default_names.push_back(name), default_values.push_back(allowed);
  e << YAML::Key << "default_entry_names" << YAML::Value << YAML::Flow << default_names;
  e << YAML::Key << "default_entry_values" << YAML::Value << YAML::Flow << default_values << YAML::EndMap;
}

}  // namespace

void write_scene_yaml(const SceneFile& scene, std::ostream& out) {
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << scene.name;
  std::vector<std::string> names;
  std::vector<double> values;
  for (const auto& [n, v] : scene.joint_values) names.push_back(n), values.push_back(v);
  e << YAML::Key << "robot_state" << YAML::Value << YAML::BeginMap << YAML::Key << "joint_state" << YAML::Value << YAML::BeginMap
    << YAML::Key << "name" << YAML::Value << YAML::Flow << names << YAML::Key << "position" << YAML::Value << YAML::Flow << values
    << YAML::EndMap;
  e << YAML::Key << "attached_collision_objects" << YAML::Value << YAML::BeginSeq;
  for (const SceneAttachedObject& a : scene.attached) emit_attached(e, a);
  e << YAML::EndSeq << YAML::EndMap;
  e << YAML::Key << "world" << YAML::Value << YAML::BeginMap << YAML::Key << "collision_objects" << YAML::Value << YAML::BeginSeq;
  for (const SceneObject& o : scene.objects) emit_object(e, o);
  e << YAML::EndSeq << YAML::EndMap;
  e << YAML::Key << "allowed_collision_matrix" << YAML::Value;
  emit_matrix(e, scene.allowed_collisions, scene.default_allowed);
  e << YAML::Key << "is_diff" << YAML::Value << scene.is_diff << YAML::EndMap;
  if (!e.good()) throw std::logic_error("scene YAML: " + e.GetLastError());
  out << e.c_str() << "\n";
}

}  // namespace bvh_collision
