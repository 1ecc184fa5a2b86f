// moveit_msgs/PlanningScene as YAML into a SceneFile (checker/scene_file.h).
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "bvh_collision/checker/scene_file.h"

namespace bvh_collision {

namespace {

constexpr double kLargest = 1e5;  // metres, as the .scene reader and the URDF rule

// shape_msgs/SolidPrimitive's types and the index of each dimension.
enum PrimitiveType { kBox = 1, kSphere = 2, kCylinder = 3, kCone = 4 };

// Errors name the source, the line of the node (1-based) and the field's path.
class YamlScene {
 public:
  explicit YamlScene(std::string source) : source_(std::move(source)) {}
  SceneFile read(const YAML::Node& root);

 private:
  [[noreturn]] void fail(const YAML::Node& at, const std::string& field, const std::string& what) const {
    const int line = at.IsDefined() && at.Mark().line >= 0 ? at.Mark().line + 1 : 0;
    throw SceneFileError(source_ + ":" + (line > 0 ? std::to_string(line) : std::string("?")) + ": " + field + ": " + what);
  }
  YAML::Node required(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    if (!parent.IsMap()) fail(parent, field, "not a map (of " + key + " and more)");
    const YAML::Node n = parent[key];
    if (!n.IsDefined() || n.IsNull()) fail(parent, field + "." + key, "missing");
    return n;
  }
  YAML::Node sequence(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    if (!parent.IsMap()) fail(parent, field, "not a map (of " + key + " and more)");
    const YAML::Node n = parent[key];
    if (!n.IsDefined() || n.IsNull()) return YAML::Node(YAML::NodeType::Sequence);
    if (!n.IsSequence()) fail(n, field + "." + key, "not a list");
    return n;
  }
  double number(const YAML::Node& n, const std::string& field) const;
  std::string text(const YAML::Node& n, const std::string& field) const;
  Transform pose(const YAML::Node& n, const std::string& field) const;
  ObjectShape primitive(const YAML::Node& n, const std::string& field) const;
  ObjectShape mesh(const YAML::Node& n, const std::string& field) const;
  void shapes(const YAML::Node& object, const std::string& field, const char* kind, const char* poses, SceneObject& out) const;
  SceneObject object(const YAML::Node& n, const std::string& field) const;
  void robot_state(const YAML::Node& n, SceneFile& scene) const;
  void allowed(const YAML::Node& n, SceneFile& scene) const;

  std::string source_;
};

double YamlScene::number(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) fail(n, field, "not a number");
  const std::string t = n.Scalar();
  const bool decimal = !t.empty() && t.find_first_not_of("0123456789+-.eE") == std::string::npos;
  char* end = nullptr;
  const double v = decimal ? std::strtod(t.c_str(), &end) : 0.0;
  if (!decimal || end != t.c_str() + t.size()) fail(n, field, "'" + t + "' is not a number");
  if (!std::isfinite(v)) fail(n, field, "'" + t + "' is not finite");
  return v;
}

std::string YamlScene::text(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) fail(n, field, "not a string");
  return n.Scalar();
}

Transform YamlScene::pose(const YAML::Node& n, const std::string& field) const {
  if (!n.IsMap()) fail(n, field, "not a pose (position and orientation)");
  const YAML::Node p = required(n, "position", field), o = required(n, "orientation", field);
  Vec3 t;
  for (int i = 0; i < 3; ++i) t[i] = number(required(p, std::string(1, "xyz"[i]), field + ".position"), field + ".position." + "xyz"[i]);
  if (t.cwiseAbs().maxCoeff() > kLargest) fail(p, field + ".position", "beyond 1e5 m");
  double q[4];
  for (int i = 0; i < 4; ++i) q[i] = number(required(o, std::string(1, "xyzw"[i]), field + ".orientation"), field + ".orientation." + "xyzw"[i]);
  const Eigen::Quaterniond r(q[3], q[0], q[1], q[2]);
  if (std::abs(r.norm() - 1.0) > 1e-3) {
    std::ostringstream norm;
    norm << r.norm();
    fail(o, field + ".orientation", "not a unit quaternion (norm " + norm.str() + ")");
  }
  return {r.normalized().toRotationMatrix(), t};
}

ObjectShape YamlScene::primitive(const YAML::Node& n, const std::string& field) const {
  const double type = number(required(n, "type", field), field + ".type");
  const YAML::Node dims = required(n, "dimensions", field);
  if (!dims.IsSequence()) fail(dims, field + ".dimensions", "not a list");
  const std::size_t want = type == kBox ? 3 : type == kSphere ? 1 : (type == kCylinder || type == kCone) ? 2 : 0;
  if (want == 0) fail(n, field + ".type", "type " + n["type"].Scalar() + " is not BOX (1), SPHERE (2), CYLINDER (3) or CONE (4)");
  if (dims.size() != want) fail(dims, field + ".dimensions", std::to_string(want) + " needed, " + std::to_string(dims.size()) + " given");
  double d[3];
  for (std::size_t i = 0; i < want; ++i) {
    d[i] = number(dims[i], field + ".dimensions[" + std::to_string(i) + "]");
    if (!(d[i] > 0.0) || d[i] > kLargest) fail(dims[i], field + ".dimensions[" + std::to_string(i) + "]", "not a positive number up to 1e5 m");
  }
  if (type == kBox) return ObjectShape::box({d[0], d[1], d[2]});
  if (type == kSphere) return ObjectShape::sphere(d[0]);
  // CYLINDER_HEIGHT = 0, CYLINDER_RADIUS = 1 (the cone's the same).
  return type == kCylinder ? ObjectShape::cylinder(d[1], d[0]) : ObjectShape::cone(d[1], d[0]);
}

ObjectShape YamlScene::mesh(const YAML::Node& n, const std::string& field) const {
  TriangleMesh m;
  const YAML::Node vertices = sequence(n, "vertices", field), triangles = sequence(n, "triangles", field);
  for (std::size_t v = 0; v < vertices.size(); ++v) {
    const std::string at = field + ".vertices[" + std::to_string(v) + "]";
    Vec3 p;
    for (int i = 0; i < 3; ++i) p[i] = number(required(vertices[v], std::string(1, "xyz"[i]), at), at + "." + "xyz"[i]);
    if (p.cwiseAbs().maxCoeff() > kLargest) fail(vertices[v], at, "beyond 1e5 m");
    m.vertices.push_back(p);
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    const std::string at = field + ".triangles[" + std::to_string(t) + "].vertex_indices";
    const YAML::Node idx = required(triangles[t], "vertex_indices", field + ".triangles[" + std::to_string(t) + "]");
    if (!idx.IsSequence() || idx.size() != 3) fail(idx, at, "not three indices");
    std::array<std::int32_t, 3> tri{};
    for (int i = 0; i < 3; ++i) {
      const double k = number(idx[i], at);
      if (k < 0 || k != std::floor(k) || k >= static_cast<double>(m.vertices.size())) {
        fail(idx[i], at, "vertex " + idx[i].Scalar() + " of " + std::to_string(m.vertices.size()));
      }
      tri[i] = static_cast<std::int32_t>(k);
    }
    m.triangles.push_back(tri);
  }
  if (m.triangles.empty()) fail(n, field, "a mesh without triangles");
  return ObjectShape::triangles(std::move(m));
}

// The shapes of one kind (primitives or meshes) with their poses, one pose each.
void YamlScene::shapes(const YAML::Node& object, const std::string& field, const char* kind, const char* poses,
                       SceneObject& out) const {
  const YAML::Node list = sequence(object, kind, field), at = sequence(object, poses, field);
  if (list.size() != at.size()) {
    fail(object, field, std::to_string(list.size()) + " " + kind + " but " + std::to_string(at.size()) + " " + poses);
  }
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string name = field + "." + kind + "[" + std::to_string(k) + "]";
    SceneShape s;
    s.shape = std::string(kind) == "meshes" ? mesh(list[k], name) : primitive(list[k], name);
    s.pose = pose(at[k], field + "." + poses + "[" + std::to_string(k) + "]");
    out.shapes.push_back(std::move(s));
  }
}

SceneObject YamlScene::object(const YAML::Node& n, const std::string& field) const {
  if (!n.IsMap()) fail(n, field, "not a collision object");
  SceneObject o;
  o.id = text(required(n, "id", field), field + ".id");
  const std::string what = field + " ('" + o.id + "')";
  if (o.id.empty()) fail(n["id"], field + ".id", "empty");
  if (o.id.find('#') != std::string::npos) fail(n["id"], field + ".id", "'" + o.id + "' contains '#' (it names an object's shapes: id#k)");
  if (n["operation"].IsDefined() && number(n["operation"], what + ".operation") != 0.0) {
    fail(n["operation"], what + ".operation", "only ADD (0) makes sense in a scene");
  }
  if (n["header"].IsDefined() && n["header"]["frame_id"].IsDefined()) o.frame_id = text(n["header"]["frame_id"], what + ".header.frame_id");
  if (n["pose"].IsDefined()) o.pose = pose(n["pose"], what + ".pose");
  if (sequence(n, "planes", what).size() > 0) fail(n["planes"], what + ".planes", "a plane (infinite) is not supported");
  shapes(n, what, "primitives", "primitive_poses", o);
  shapes(n, what, "meshes", "mesh_poses", o);
  if (o.shapes.empty()) fail(n, what, "no shape");
  return o;
}

void YamlScene::robot_state(const YAML::Node& n, SceneFile& scene) const {
  if (sequence(n, "attached_collision_objects", "robot_state").size() > 0) {
    fail(n["attached_collision_objects"], "robot_state.attached_collision_objects", "attached objects are not supported yet");
  }
  const YAML::Node multi = n["multi_dof_joint_state"];
  if (multi.IsDefined() && sequence(multi, "joint_names", "robot_state.multi_dof_joint_state").size() > 0) {
    fail(multi, "robot_state.multi_dof_joint_state", "multi-DOF joints are not supported (give the root's pose through tf)");
  }
  const YAML::Node js = n["joint_state"];
  if (!js.IsDefined() || js.IsNull()) return;
  const YAML::Node names = sequence(js, "name", "robot_state.joint_state"), values = sequence(js, "position", "robot_state.joint_state");
  if (names.size() != values.size()) {
    fail(js, "robot_state.joint_state", std::to_string(names.size()) + " names but " + std::to_string(values.size()) + " positions");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    scene.joint_values.emplace_back(text(names[i], "robot_state.joint_state.name[" + std::to_string(i) + "]"),
                                    number(values[i], "robot_state.joint_state.position[" + std::to_string(i) + "]"));
  }
}

void YamlScene::allowed(const YAML::Node& n, SceneFile& scene) const {
  const std::string field = "allowed_collision_matrix";
  const YAML::Node names = sequence(n, "entry_names", field), rows = sequence(n, "entry_values", field);
  if (names.size() != rows.size()) fail(n, field, std::to_string(names.size()) + " entry_names but " + std::to_string(rows.size()) + " entry_values");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string row = field + ".entry_values[" + std::to_string(i) + "].enabled";
    const YAML::Node enabled = sequence(rows[i], "enabled", field + ".entry_values[" + std::to_string(i) + "]");
    if (enabled.size() != names.size()) fail(rows[i], row, std::to_string(enabled.size()) + " values for " + std::to_string(names.size()) + " names");
    for (std::size_t j = i + 1; j < names.size(); ++j) {
      bool flag = false;
      if (!YAML::convert<bool>::decode(enabled[j], flag)) fail(enabled[j], row, "'" + enabled[j].Scalar() + "' is not true or false");
      scene.allowed_collisions.push_back({text(names[i], field + ".entry_names"), text(names[j], field + ".entry_names"), flag});
    }
  }
}

SceneFile YamlScene::read(const YAML::Node& root) {
  if (!root.IsMap()) fail(root, "the document", "not a PlanningScene (a map of name, world, robot_state, ...)");
  SceneFile scene;
  if (root["name"].IsDefined() && !root["name"].IsNull()) scene.name = text(root["name"], "name");
  const YAML::Node world = root["world"];
  if (world.IsDefined() && !world.IsNull()) {
    const YAML::Node list = sequence(world, "collision_objects", "world");
    for (std::size_t k = 0; k < list.size(); ++k) {
      SceneObject o = object(list[k], "world.collision_objects[" + std::to_string(k) + "]");
      auto same = std::find_if(scene.objects.begin(), scene.objects.end(), [&](const SceneObject& x) { return x.id == o.id; });
      if (same != scene.objects.end()) scene.objects.erase(same);
      scene.objects.push_back(std::move(o));
    }
    const YAML::Node map = world["octomap"];
    if (map.IsDefined() && map["octomap"].IsDefined() && sequence(map["octomap"], "data", "world.octomap.octomap").size() > 0) {
      fail(map, "world.octomap", "an octomap in a scene is not read (start from it with ~octree_file)");
    }
  }
  if (root["robot_state"].IsDefined() && !root["robot_state"].IsNull()) robot_state(root["robot_state"], scene);
  if (root["allowed_collision_matrix"].IsDefined() && !root["allowed_collision_matrix"].IsNull()) allowed(root["allowed_collision_matrix"], scene);
  return scene;
}

}  // namespace

SceneFile read_scene_yaml(std::istream& in, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(in);
  } catch (const YAML::Exception& e) {
    throw SceneFileError(source + ":" + std::to_string(e.mark.line + 1) + ": not YAML: " + e.msg);
  }
  try {
    return YamlScene(source).read(root);
  } catch (const YAML::Exception& e) {
    // A node of another kind than its field needs (a scalar where a map belongs, say) that the
    // checks above did not name: refused all the same, with its line.
    throw SceneFileError(source + ":" + std::to_string(e.mark.line + 1) + ": malformed: " + e.msg);
  }
}

}  // namespace bvh_collision

namespace bvh_collision {

namespace {

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
  e << YAML::Key << "operation" << YAML::Value << 0 << YAML::EndMap;
}

// The pairs as MoveIt's matrix: every name once, a pair not listed not allowed.
void emit_matrix(YAML::Emitter& e, const std::vector<AllowedCollision>& pairs) {
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
  e << YAML::EndSeq << YAML::EndMap;
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
    << YAML::EndMap << YAML::EndMap;
  e << YAML::Key << "world" << YAML::Value << YAML::BeginMap << YAML::Key << "collision_objects" << YAML::Value << YAML::BeginSeq;
  for (const SceneObject& o : scene.objects) emit_object(e, o);
  e << YAML::EndSeq << YAML::EndMap;
  e << YAML::Key << "allowed_collision_matrix" << YAML::Value;
  emit_matrix(e, scene.allowed_collisions);
  e << YAML::Key << "is_diff" << YAML::Value << false << YAML::EndMap;
  if (!e.good()) throw std::logic_error("scene YAML: " + e.GetLastError());
  out << e.c_str() << "\n";
}

}  // namespace bvh_collision
