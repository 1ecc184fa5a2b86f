// moveit_msgs/PlanningScene as YAML into a SceneFile (io/scene_file.h), in both spellings.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <map>
#include <sstream>

#include "bvh_collision/io/scene_file.h"

namespace bvh_collision {

namespace {

constexpr double kLargest = 1e5;  // metres, as the .scene reader and the URDF rule

// shape_msgs/SolidPrimitive's types, and how many dimensions each takes.
enum PrimitiveType { kBox = 1, kSphere = 2, kCylinder = 3, kCone = 4 };

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// Errors and warnings name the source, the line of the node (1-based) and the field's path.
class YamlScene {
 public:
  explicit YamlScene(std::string source) : source_(std::move(source)) {}
  SceneFile read(const YAML::Node& root);

 private:
  std::string at(const YAML::Node& n) const {
    const int line = n.IsDefined() && n.Mark().line >= 0 ? n.Mark().line + 1 : 0;
    return source_ + ":" + (line > 0 ? std::to_string(line) : std::string("?"));
  }
  [[noreturn]] void fail(const YAML::Node& n, const std::string& field, const std::string& what) const {
    throw SceneFileError(at(n) + ": " + field + ": " + what);
  }
  void warn(const YAML::Node& n, const std::string& field, const std::string& what) {
    scene_.warnings.push_back(at(n) + ": " + field + ": " + what);
  }
  static bool given(const YAML::Node& n) { return n.IsDefined() && !n.IsNull(); }
  YAML::Node map_field(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    if (!parent.IsMap()) fail(parent, field, "not a map (of " + key + " and more)");
    return parent[key];
  }
  YAML::Node required(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    const YAML::Node n = map_field(parent, key, field);
    if (!given(n)) fail(parent, field + "." + key, "missing");
    return n;
  }
  YAML::Node sequence(const YAML::Node& parent, const std::string& key, const std::string& field) const {
    const YAML::Node n = map_field(parent, key, field);
    if (!given(n)) return YAML::Node(YAML::NodeType::Sequence);
    if (!n.IsSequence()) fail(n, field + "." + key, "not a list");
    return n;
  }
  double number(const YAML::Node& n, const std::string& field) const;
  bool boolean(const YAML::Node& n, const std::string& field) const;
  std::string text(const YAML::Node& n, const std::string& field) const;
  std::vector<double> numbers(const YAML::Node& n, const std::string& field, const char* names) const;
  Vec3 point(const YAML::Node& n, const std::string& field) const;
  Eigen::Matrix3d rotation(const YAML::Node& n, const std::string& field);
  Transform pose(const YAML::Node& n, const std::string& field);
  ObjectShape primitive(const YAML::Node& n, const std::string& field);
  ObjectShape mesh(const YAML::Node& n, const std::string& field) const;
  void shapes(const YAML::Node& object, const std::string& field, const char* kind, const char* poses, SceneObject& out);
  SceneOperation operation(const YAML::Node& n, const std::string& field) const;
  SceneObject object(const YAML::Node& n, const std::string& field, bool attached = false);
  void robot_state(const YAML::Node& n);
  void attached(const YAML::Node& n, const std::string& field);
  void allowed(const YAML::Node& n);
  void fixed_frames(const YAML::Node& n);
  void unused(const YAML::Node& root);

  std::string source_;
  SceneFile scene_;
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

bool YamlScene::boolean(const YAML::Node& n, const std::string& field) const {
  bool flag = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, flag)) {
    fail(n, field, "'" + (n.IsScalar() ? n.Scalar() : std::string("(not a scalar)")) + "' is not true or false");
  }
  return flag;
}

std::string YamlScene::text(const YAML::Node& n, const std::string& field) const {
  if (!n.IsScalar()) fail(n, field, "not a string");
  return n.Scalar();
}

// A map of the named fields (x, y, z) or a list of as many numbers, in that order.
std::vector<double> YamlScene::numbers(const YAML::Node& n, const std::string& field, const char* names) const {
  const std::string keys(names);
  std::vector<double> out;
  if (n.IsSequence()) {
    if (n.size() != keys.size()) {
      fail(n, field, "a list of " + std::to_string(n.size()) + " where " + std::to_string(keys.size()) + " (" + keys + ") belong");
    }
    for (std::size_t i = 0; i < keys.size(); ++i) out.push_back(number(n[i], field + "[" + std::to_string(i) + "]"));
    return out;
  }
  if (!n.IsMap()) fail(n, field, "neither a map of " + keys + " nor a list of " + std::to_string(keys.size()) + " numbers");
  for (const char k : keys) out.push_back(number(required(n, std::string(1, k), field), field + "." + k));
  return out;
}

Vec3 YamlScene::point(const YAML::Node& n, const std::string& field) const {
  const std::vector<double> v = numbers(n, field, "xyz");
  const Vec3 p(v[0], v[1], v[2]);
  if (p.cwiseAbs().maxCoeff() > kLargest) fail(n, field, "beyond 1e5 m");
  return p;
}

// As MoveIt reads a message's quaternion: normalised; a zero one is no rotation (it warns).
Eigen::Matrix3d YamlScene::rotation(const YAML::Node& n, const std::string& field) {
  const std::vector<double> q = numbers(n, field, "xyzw");
  const Eigen::Quaterniond r(q[3], q[0], q[1], q[2]);
  const double largest = std::max({std::abs(q[0]), std::abs(q[1]), std::abs(q[2]), std::abs(q[3])});
  if (largest == 0.0) {
    warn(n, field, "a zero quaternion, taken as no rotation (as MoveIt takes it)");
    return Eigen::Matrix3d::Identity();
  }
  const Eigen::Quaterniond scaled(r.w() / largest, r.x() / largest, r.y() / largest, r.z() / largest);
  const double norm = largest * scaled.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    std::ostringstream text;
    text << "not a unit quaternion (norm " << norm << "): normalised, as MoveIt does";
    warn(n, field, text.str());
  }
  return scaled.normalized().toRotationMatrix();
}

// A geometry_msgs/Pose: position and orientation, either spelling; a missing orientation is no
// rotation (a message's default is a zero quaternion, which MoveIt takes as that).
Transform YamlScene::pose(const YAML::Node& n, const std::string& field) {
  if (!n.IsMap()) fail(n, field, "not a pose (position and orientation)");
  Transform t;
  if (given(n["position"])) t.t = point(n["position"], field + ".position");
  if (given(n["orientation"])) {
    t.R = rotation(n["orientation"], field + ".orientation");
  } else {
    warn(n, field, "no orientation: taken as no rotation");
  }
  return t;
}

ObjectShape YamlScene::primitive(const YAML::Node& n, const std::string& field) {
  const YAML::Node kind = required(n, "type", field);
  if (!kind.IsScalar()) fail(kind, field + ".type", "not a type");
  const std::string word = lower(kind.Scalar());
  const int type = word == "box" ? kBox : word == "sphere" ? kSphere : word == "cylinder" ? kCylinder : word == "cone" ? kCone
                 : word.find_first_not_of("0123456789") == std::string::npos && !word.empty() && word.size() < 4 ? std::stoi(word)
                                                                                                                 : 0;
  const std::size_t want = type == kBox ? 3 : type == kSphere ? 1 : (type == kCylinder || type == kCone) ? 2 : 0;
  if (want == 0) {
    fail(kind, field + ".type", "type '" + kind.Scalar() + "' is not BOX (1), SPHERE (2), CYLINDER (3) or CONE (4), by number or name");
  }
  const YAML::Node dims = required(n, "dimensions", field);
  if (!dims.IsSequence()) fail(dims, field + ".dimensions", "not a list");
  if (dims.size() < want) fail(dims, field + ".dimensions", std::to_string(want) + " needed, " + std::to_string(dims.size()) + " given");
  if (dims.size() > want) {
    warn(dims, field + ".dimensions", std::to_string(dims.size()) + " given, the first " + std::to_string(want) +
                                          " used (MoveIt ignores the rest too)");
  }
  double d[3] = {0, 0, 0};
  for (std::size_t i = 0; i < want; ++i) {
    const std::string name = field + ".dimensions[" + std::to_string(i) + "]";
    d[i] = number(dims[i], name);
    if (!(d[i] > 0.0) || d[i] > kLargest) fail(dims[i], name, "not a positive number up to 1e5 m");
  }
  if (type == kBox) return ObjectShape::box({d[0], d[1], d[2]});
  if (type == kSphere) return ObjectShape::sphere(d[0]);
  // CYLINDER_HEIGHT = 0, CYLINDER_RADIUS = 1 (the cone's the same).
  return type == kCylinder ? ObjectShape::cylinder(d[1], d[0]) : ObjectShape::cone(d[1], d[0]);
}

ObjectShape YamlScene::mesh(const YAML::Node& n, const std::string& field) const {
  if (n.IsMap() && given(n["resource"])) fail(n["resource"], field + ".resource", "a mesh by file is not read here: give its vertices and triangles");
  TriangleMesh m;
  const YAML::Node vertices = sequence(n, "vertices", field), triangles = sequence(n, "triangles", field);
  for (std::size_t v = 0; v < vertices.size(); ++v) m.vertices.push_back(point(vertices[v], field + ".vertices[" + std::to_string(v) + "]"));
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    // shape_msgs/MeshTriangle: {vertex_indices: [a, b, c]}, or the bare list.
    const std::string name = field + ".triangles[" + std::to_string(t) + "]";
    const YAML::Node idx = triangles[t].IsMap() ? required(triangles[t], "vertex_indices", name) : triangles[t];
    if (!idx.IsSequence() || idx.size() != 3) fail(idx, name, "not three vertex indices");
    std::array<std::int32_t, 3> tri{};
    for (int i = 0; i < 3; ++i) {
      const double k = number(idx[i], name);
      if (k < 0 || k != std::floor(k) || k >= static_cast<double>(m.vertices.size())) {
        fail(idx[i], name, "vertex " + idx[i].Scalar() + " of " + std::to_string(m.vertices.size()));
      }
      tri[i] = static_cast<std::int32_t>(k);
    }
    m.triangles.push_back(tri);
  }
  if (m.triangles.empty()) fail(n, field, "a mesh without triangles");
  return ObjectShape::triangles(std::move(m));
}

// The shapes of one kind (primitives or meshes) with their poses. Fewer poses than shapes: the
// rest at the object's origin (as MoveIt); more: refused (MoveIt refuses the object).
void YamlScene::shapes(const YAML::Node& object, const std::string& field, const char* kind, const char* poses,
                       SceneObject& out) {
  const YAML::Node list = sequence(object, kind, field), at = sequence(object, poses, field);
  if (at.size() > list.size()) {
    fail(object, field, std::to_string(list.size()) + " " + kind + " but " + std::to_string(at.size()) + " " + poses);
  }
  if (at.size() < list.size() && out.operation != SceneOperation::kMove) {
    warn(object, field, std::to_string(list.size()) + " " + kind + " but " + std::to_string(at.size()) + " " + poses +
                            ": the rest at the object's origin (as MoveIt)");
  }
  for (std::size_t k = 0; k < list.size(); ++k) {
    const std::string name = field + "." + kind + "[" + std::to_string(k) + "]";
    SceneShape s;
    s.shape = std::string(kind) == "meshes" ? mesh(list[k], name) : primitive(list[k], name);
    if (k < at.size()) s.pose = pose(at[k], field + "." + poses + "[" + std::to_string(k) + "]");
    out.shapes.push_back(std::move(s));
  }
}

SceneOperation YamlScene::operation(const YAML::Node& n, const std::string& field) const {
  if (!given(n)) return SceneOperation::kAdd;
  if (!n.IsScalar()) fail(n, field, "not an operation");
  const std::string word = lower(n.Scalar());
  if (word == "add" || word == "0") return SceneOperation::kAdd;
  if (word == "remove" || word == "1") return SceneOperation::kRemove;
  if (word == "append" || word == "2") return SceneOperation::kAppend;
  if (word == "move" || word == "3") return SceneOperation::kMove;
  fail(n, field, "'" + n.Scalar() + "' is not ADD (0), REMOVE (1), APPEND (2) or MOVE (3), by number or name");
}

SceneObject YamlScene::object(const YAML::Node& n, const std::string& field, bool attached) {
  if (!n.IsMap()) fail(n, field, "not a collision object");
  SceneObject o;
  o.line = n.Mark().line + 1;
  o.operation = operation(n["operation"], field + ".operation");
  const YAML::Node id = n["id"];
  o.id = given(id) ? text(id, field + ".id") : std::string();
  const std::string what = field + " ('" + printable_id(o.id) + "')";
  if (!(o.operation == SceneOperation::kRemove && o.id.empty())) {  // REMOVE of "" is of every object
    if (const std::string problem = object_id_problem(o.id); !problem.empty()) fail(given(id) ? id : n, field + ".id", problem);
  }
  if (given(n["header"]) && given(map_field(n["header"], "frame_id", what + ".header"))) o.frame_id = text(n["header"]["frame_id"], what + ".header.frame_id");
  const bool posed = given(n["pose"]);
  if (posed) o.pose = pose(n["pose"], what + ".pose");
  if (sequence(n, "planes", what).size() > 0) fail(n["planes"], what + ".planes", "a plane (infinite) is not supported");
  shapes(n, what, "primitives", "primitive_poses", o);
  shapes(n, what, "meshes", "mesh_poses", o);
  const YAML::Node names = sequence(n, "subframe_names", what), poses = sequence(n, "subframe_poses", what);
  if (names.size() != poses.size()) {
    fail(n, what, std::to_string(names.size()) + " subframe_names but " + std::to_string(poses.size()) + " subframe_poses");
  }
  for (std::size_t k = 0; k < names.size(); ++k) {
    o.subframes.emplace_back(text(names[k], what + ".subframe_names[" + std::to_string(k) + "]"),
                             pose(poses[k], what + ".subframe_poses[" + std::to_string(k) + "]"));
  }
  // One shape and no object pose: the shape's pose is the object's (MoveIt's rule; the same
  // place). Not for APPEND, whose shapes go in the existing object's frame at their own poses
  // (MoveIt's swap would put a lone appended shape at that object's origin).
  if (!posed && o.shapes.size() == 1 && o.operation == SceneOperation::kAdd) std::swap(o.pose, o.shapes[0].pose);
  const bool adds = o.operation == SceneOperation::kAdd || o.operation == SceneOperation::kAppend;
  // (An attached object without shapes is the world's object of its id, moved to the robot.)
  if (adds && o.shapes.empty() && !attached) fail(n, what, "no shape");
  if (!scene_.is_diff && !adds) {
    fail(n["operation"], what + ".operation", "REMOVE and MOVE change a world that is there: only a diff (is_diff: true) holds them");
  }
  return o;
}

void YamlScene::attached(const YAML::Node& n, const std::string& field) {
  if (!n.IsMap()) fail(n, field, "not an attached collision object");
  SceneAttachedObject a;
  a.link = text(required(n, "link_name", field), field + ".link_name");
  const YAML::Node touch = sequence(n, "touch_links", field);
  for (std::size_t k = 0; k < touch.size(); ++k) a.touch_links.push_back(text(touch[k], field + ".touch_links[" + std::to_string(k) + "]"));
  const YAML::Node body = required(n, "object", field);
  // Attaching is an ADD of the robot's own: a whole state holds nothing else (MoveIt ignores the rest).
  if (!body.IsMap() || operation(body["operation"], field + ".object.operation") != SceneOperation::kAdd) {
    warn(body, field + ".object.operation", "only ADD attaches an object: this one is ignored (as MoveIt ignores it)");
    return;
  }
  a.object = object(body, field + ".object", true);
  scene_.attached.push_back(std::move(a));
}

void YamlScene::robot_state(const YAML::Node& n) {
  const YAML::Node multi = map_field(n, "multi_dof_joint_state", "robot_state");
  if (given(multi) && sequence(multi, "joint_names", "robot_state.multi_dof_joint_state").size() > 0) {
    fail(multi, "robot_state.multi_dof_joint_state", "multi-DOF joints are not supported (give the root's pose through tf)");
  }
  const YAML::Node list = sequence(n, "attached_collision_objects", "robot_state");
  for (std::size_t k = 0; k < list.size(); ++k) attached(list[k], "robot_state.attached_collision_objects[" + std::to_string(k) + "]");
  const YAML::Node js = n["joint_state"];
  if (!given(js)) return;
  const YAML::Node names = sequence(js, "name", "robot_state.joint_state"), values = sequence(js, "position", "robot_state.joint_state");
  if (names.size() != values.size()) {
    fail(js, "robot_state.joint_state", std::to_string(names.size()) + " names but " + std::to_string(values.size()) + " positions");
  }
  for (std::size_t i = 0; i < names.size(); ++i) {
    scene_.joint_values.emplace_back(text(names[i], "robot_state.joint_state.name[" + std::to_string(i) + "]"),
                                     number(values[i], "robot_state.joint_state.position[" + std::to_string(i) + "]"));
  }
}

// MoveIt's matrix from its message: rows of the wrong count are ignored with an error (so are
// they here, with a warning); row i sets every pair (i, j), so a later row wins where two differ.
void YamlScene::allowed(const YAML::Node& n) {
  const std::string field = "allowed_collision_matrix";
  const YAML::Node names = sequence(n, "entry_names", field), rows = sequence(n, "entry_values", field);
  std::vector<std::string> name;
  for (std::size_t i = 0; i < names.size(); ++i) name.push_back(text(names[i], field + ".entry_names[" + std::to_string(i) + "]"));
  if (names.size() != rows.size()) {
    warn(n, field, std::to_string(names.size()) + " entry_names but " + std::to_string(rows.size()) + " entry_values: the matrix is ignored (as MoveIt ignores it)");
    return;
  }
  std::map<std::pair<std::size_t, std::size_t>, bool> pairs;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::string row = field + ".entry_values[" + std::to_string(i) + "]";
    // AllowedCollisionEntry: {enabled: [...]}, or the bare list.
    const YAML::Node enabled = rows[i].IsMap() ? sequence(rows[i], "enabled", row) : rows[i];
    if (!enabled.IsSequence()) fail(enabled, row, "not a list of true or false");
    if (enabled.size() != names.size()) {
      warn(rows[i], row, std::to_string(enabled.size()) + " values for " + std::to_string(names.size()) + " names: the row is ignored (as MoveIt ignores it)");
      continue;
    }
    for (std::size_t j = 0; j < names.size(); ++j) {
      if (j != i) pairs[std::minmax(i, j)] = boolean(enabled[j], row + "[" + std::to_string(j) + "]");
    }
  }
  for (const auto& [p, flag] : pairs) scene_.allowed_collisions.push_back({name[p.first], name[p.second], flag});
  const YAML::Node dnames = sequence(n, "default_entry_names", field), dvalues = sequence(n, "default_entry_values", field);
  if (dnames.size() != dvalues.size()) {
    warn(n, field, std::to_string(dnames.size()) + " default_entry_names but " + std::to_string(dvalues.size()) +
                       " default_entry_values: the defaults are ignored (as MoveIt ignores them)");
    return;
  }
  for (std::size_t i = 0; i < dnames.size(); ++i) {
    scene_.default_allowed.emplace_back(text(dnames[i], field + ".default_entry_names[" + std::to_string(i) + "]"),
                                        boolean(dvalues[i], field + ".default_entry_values[" + std::to_string(i) + "]"));
  }
}

void YamlScene::fixed_frames(const YAML::Node& n) {
  if (!n.IsSequence()) fail(n, "fixed_frame_transforms", "not a list");
  for (std::size_t k = 0; k < n.size(); ++k) {
    const std::string field = "fixed_frame_transforms[" + std::to_string(k) + "]";
    SceneFixedFrame f;
    f.frame = text(required(n[k], "child_frame_id", field), field + ".child_frame_id");
    const YAML::Node header = map_field(n[k], "header", field);
    if (given(header) && given(map_field(header, "frame_id", field + ".header"))) f.parent = text(header["frame_id"], field + ".header.frame_id");
    const YAML::Node t = required(n[k], "transform", field);
    if (given(map_field(t, "translation", field + ".transform"))) f.pose.t = point(t["translation"], field + ".transform.translation");
    if (given(t["rotation"])) f.pose.R = rotation(t["rotation"], field + ".transform.rotation");
    scene_.fixed_frames.push_back(std::move(f));
  }
}

// What changes answers in MoveIt and is not applied here, and fields no PlanningScene has.
void YamlScene::unused(const YAML::Node& root) {
  for (const char* key : {"link_padding", "link_scale"}) {
    const YAML::Node list = sequence(root, key, "the document");
    const bool padding = std::string(key) == "link_padding";
    for (std::size_t k = 0; k < list.size(); ++k) {
      const std::string field = std::string(key) + "[" + std::to_string(k) + "]";
      const double v = number(required(list[k], padding ? "padding" : "scale", field), field);
      if (v != (padding ? 0.0 : 1.0)) warn(list[k], field, "not applied (the node's padding parameters decide)");
    }
  }
  static const char* const kKnown[] = {"name", "robot_state", "robot_model_name", "fixed_frame_transforms", "allowed_collision_matrix",
                                       "link_padding", "link_scale", "object_colors", "world", "is_diff"};
  for (const auto& entry : root) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string();
    if (std::find(std::begin(kKnown), std::end(kKnown), key) == std::end(kKnown)) warn(entry.first, key, "not a PlanningScene field: ignored");
  }
}

SceneFile YamlScene::read(const YAML::Node& root) {
  if (!root.IsMap()) fail(root, "the document", "not a PlanningScene (a map of name, world, robot_state, ...)");
  if (given(root["name"])) scene_.name = text(root["name"], "name");
  if (given(root["is_diff"])) scene_.is_diff = boolean(root["is_diff"], "is_diff");
  if (given(root["fixed_frame_transforms"])) fixed_frames(root["fixed_frame_transforms"]);
  const YAML::Node world = root["world"];
  if (given(world)) {
    const YAML::Node list = sequence(world, "collision_objects", "world");
    for (std::size_t k = 0; k < list.size(); ++k) scene_.objects.push_back(object(list[k], "world.collision_objects[" + std::to_string(k) + "]"));
    const YAML::Node map = map_field(world, "octomap", "world");
    if (given(map) && given(map_field(map, "octomap", "world.octomap")) && given(map_field(map["octomap"], "data", "world.octomap.octomap")) &&
        (!map["octomap"]["data"].IsSequence() || map["octomap"]["data"].size() > 0)) {
      fail(map, "world.octomap", "an octomap in a scene is not read (start from it with ~octree_file)");
    }
  }
  if (given(root["robot_state"])) robot_state(root["robot_state"]);
  if (given(root["allowed_collision_matrix"])) allowed(root["allowed_collision_matrix"]);
  unused(root);
  // Two entries of one id in a whole scene: both kept (their shapes merge where it is applied).
  std::map<std::string, int> first;
  for (const SceneObject& o : scene_.objects) {
    const auto [it, added] = first.emplace(o.id, o.line);
    if (!added && o.operation == SceneOperation::kAdd) {
      scene_.warnings.push_back(source_ + ":" + std::to_string(o.line) + ": object '" + o.id + "' is also at line " +
                                std::to_string(it->second) + ": its shapes are added to that object's (MoveIt would keep only these)");
    }
  }
  return std::move(scene_);
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
