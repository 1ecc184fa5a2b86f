#include "loader_targets.h"

#include <tinyxml2.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "bvh_collision/bvh/bounding_volumes.h"
#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/mesh_loader.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/robot/robot_model.h"
#include "check_tool.h"

namespace bvh_collision::fuzz {
namespace {

// <collision> elements per link name, read from the text independently of urdfdom: the count a
// loaded model must have (a dropped element is the defect this target exists for).
std::map<std::string, int> collision_counts(const std::string& xml) {
  tinyxml2::XMLDocument doc;
  std::map<std::string, int> counts;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS || !doc.RootElement()) return counts;
  for (auto* link = doc.RootElement()->FirstChildElement("link"); link; link = link->NextSiblingElement("link")) {
    int n = 0;
    for (auto* c = link->FirstChildElement("collision"); c; c = c->NextSiblingElement("collision")) ++n;
    counts[link->Attribute("name") ? link->Attribute("name") : ""] += n;
  }
  return counts;
}

std::string check_shapes(const RobotModel& model, const std::map<std::string, int>& counts) {
  for (const RobotLink& link : model.links()) {
    const auto it = counts.find(link.name);
    const int expected = it == counts.end() ? 0 : it->second;
    if (static_cast<int>(link.collision.size()) != expected) {
      return "link '" + link.name + "' has " + std::to_string(link.collision.size()) + " shapes for " +
             std::to_string(expected) + " <collision> elements";
    }
    for (const CollisionElement& e : link.collision) {
      const bool finite = e.origin.R.allFinite() && e.origin.t.allFinite() && std::isfinite(e.radius) && std::isfinite(e.length) &&
                          e.size.allFinite();
      if (!finite) return "link '" + link.name + "' has a shape that is not finite: " + e.source;
      if (e.mesh) {
        if (e.mesh->triangles.empty()) return "link '" + link.name + "' has an empty mesh: " + e.source;
        for (const Vec3& v : e.mesh->vertices) {
          if (!v.allFinite()) return "link '" + link.name + "' has a vertex that is not finite: " + e.source;
        }
      }
    }
  }
  return "";
}

// Self checks at the lower, middle and upper joint values: finite poses, an answer that is not NaN.
std::string check_kinematics(RobotModel model) {
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  const CollisionChecker checker(std::move(model), std::move(acm));
  const RobotModel& m = checker.model();
  for (const double at : {0.0, 0.5, 1.0}) {
    std::vector<double> state(m.variable_count(), 0.0);
    for (std::size_t v = 0; v < state.size(); ++v) {
      const RobotJoint& j = m.joints()[m.joint_index(m.variable_names()[v])];
      if (j.bounded) state[v] = j.lower + at * (j.upper - j.lower);
    }
    std::vector<Transform> poses;
    forward_kinematics(m, state.data(), poses);
    for (std::size_t l = 0; l < poses.size(); ++l) {
      if (!(poses[l].R.allFinite() && poses[l].t.allFinite())) return "link '" + m.links()[l].name + "' has a pose that is not finite";
    }
    SelfCollisionRequest request;
    request.distance = true;
    request.all_pairs = true;
    const SelfCollisionResult r = checker.check_self(state.data(), request);
    if (std::isnan(r.min_distance)) return "the self check answered a distance of NaN";
  }
  return "";
}

// The package `fuzz_meshes` (test/fuzz/meshes, copied into a scratch folder once per process:
// a package.xml in the source tree would be taken by catkin for a package of the workspace).
struct ScratchPackage {
  std::filesystem::path root = std::filesystem::temp_directory_path() / ("bvh_collision_fuzz_" + std::to_string(::getpid()));
  ScratchPackage() {
    namespace fs = std::filesystem;
    fs::create_directories(root / "fuzz_meshes");
    std::ofstream(root / "fuzz_meshes" / "package.xml") << "<package format=\"3\"><name>fuzz_meshes</name></package>\n";
    fs::copy(BVH_COLLISION_FUZZ_MESHES, root / "fuzz_meshes" / "meshes", fs::copy_options::overwrite_existing);
  }
  ~ScratchPackage() {
    std::error_code ec;
    std::filesystem::remove_all(root, ec);
  }
};

const std::string& fuzz_package_root() {
  static const ScratchPackage package;
  static const std::string root = package.root.string();
  return root;
}

// Every group-state value finite; a joint of the robot or a virtual joint has the count its type
// needs, and a floating joint's quaternion is a unit one.
std::string group_state_problem(const Srdf& srdf, const RobotModel& robot) {
  for (const auto& [name, joints] : srdf.group_states) {
    for (const auto& [joint, value] : joints) {
      for (const double v : value.values) {
        if (!std::isfinite(v)) return "group state '" + name + "' holds a value that is not finite";
      }
      std::optional<JointType> type;
      if (const int j = robot.joint_index(joint); j >= 0) type = robot.joints()[j].type;
      for (const SrdfVirtualJoint& v : srdf.virtual_joints) {
        if (!type && v.name == joint) type = v.type;
      }
      if (!type) continue;
      if (value.values.size() != group_state_value_count(*type)) {
        return "group state '" + name + "': joint '" + joint + "' has " + std::to_string(value.values.size()) + " values";
      }
      if (*type == JointType::kFloating) {
        const double n = Eigen::Vector4d(value.values[3], value.values[4], value.values[5], value.values[6]).norm();
        if (!(std::abs(n - 1.0) < 1e-12)) return "group state '" + name + "': joint '" + joint + "' has a quaternion of length " + std::to_string(n);
      }
    }
  }
  return "";
}

std::string refusal_problem(const std::string& message) {
  return message.empty() ? "refused without a message" : "";
}

// What bvh_collision_check answers for the same text: it loads what the library loads and refuses
// what the library refuses (with the library's message), and a robot without any collision
// geometry is an error naming the robot, as every query of the node on it is.
std::string cli_problem(const std::string& xml, const std::string& library_error, const std::string& no_geometry_error) {
  const std::string base = fuzz_package_root() + "/input";
  std::ofstream(base + ".urdf", std::ios::binary) << xml;
  std::ofstream(base + ".states") << "joints:\n\n";
  std::ostringstream out, err;
  const int code = run_check_tool({"--urdf", base + ".urdf", "--states", base + ".states", "--package-path", fuzz_package_root()},
                                  out, err);
  const std::string expected_error = library_error.empty() ? no_geometry_error : library_error;
  if (expected_error.empty()) return code == 0 ? "" : "the CLI refused what the library loads: " + err.str();
  if (code == 0) return "the CLI answered where it must refuse (" + expected_error + ")";
  return err.str().find(expected_error) == std::string::npos ? "the CLI refused with another message: " + err.str() : "";
}

// Loaded: the shapes, the kinematics and the CLI's answer; refused: by name, in the CLI too.
std::string robot_description_problem(const std::string& xml, bool& loaded) {
  try {
    RobotModel model =
        RobotModel::from_urdf(*parse_robot_description(xml), PackageResolver({fuzz_package_root()}));
    loaded = true;
    if (std::string problem = check_shapes(model, collision_counts(xml)); !problem.empty()) return problem;
    const std::string no_geometry = has_collision_geometry(model) ? "" : no_collision_geometry_error(model);
    if (std::string problem = check_kinematics(std::move(model)); !problem.empty()) return problem;
    return cli_problem(xml, "", no_geometry);
  } catch (const RobotDescriptionError& e) {
    if (std::string problem = refusal_problem(e.what()); !problem.empty()) return problem;
    return cli_problem(xml, e.what(), "");
  } catch (const RobotLoadError& e) {
    if (std::string problem = refusal_problem(e.what()); !problem.empty()) return problem;
    return cli_problem(xml, e.what(), "");
  }
}

// A character reference to a control character inside a mesh's filename attribute (as written):
// tinyxml2 turns "&#0;" into a NUL that ends the name, so what loads is another file.
bool references_a_control_character_in_a_file_name(const std::string& xml) {
  static const std::regex reference("filename\\s*=\\s*(\"[^\"]*|'[^']*)&#(0*([0-9]|[12][0-9]|3[01]|127)|[xX]0*([01]?[0-9a-fA-F]|7[fF]));");
  return std::regex_search(xml, reference);
}

}  // namespace

std::string check_robot_description(const std::uint8_t* data, std::size_t size) {
  const std::string xml(reinterpret_cast<const char*>(data), size);
  bool loaded = false;
  const std::string problem = robot_description_problem(xml, loaded);
  if (!problem.empty()) return problem;
  if (loaded && references_a_control_character_in_a_file_name(xml)) {
    return "a mesh file name with a control character loaded";
  }
  return "";
}

std::string check_mesh(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return "";
  const char* extensions[] = {".stl", ".obj", ".dae"};
  const int pick = data[0] == 's' ? 0 : data[0] == 'o' ? 1 : data[0] == 'd' ? 2 : data[0] % 3;
  const std::string path = "/tmp/bvh_collision_fuzz_" + std::to_string(::getpid()) + extensions[pick];
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data + 1), std::streamsize(size - 1));
  MeshImportLimits in_process;
  in_process.isolated = false;
  try {
    const TriangleMesh mesh = load_mesh(path, Vec3::Ones(), in_process);
    ::unlink(path.c_str());
    if (mesh.triangles.empty()) return "loaded with no triangle";
    bool some_area = false;
    for (const auto& t : mesh.triangles) {
      for (const int i : t) {
        if (i < 0 || static_cast<std::size_t>(i) >= mesh.vertices.size()) return "loaded with an index out of range";
      }
      const Vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
      if (!a.allFinite() || !b.allFinite() || !c.allFinite()) return "loaded with a vertex that is not finite";
      some_area = some_area || (b - a).cross(c - a).squaredNorm() > 0.0;
    }
    if (!some_area) return "loaded with every triangle of zero area";
    const Bvh<Obb> tree = Bvh<Obb>::build(mesh);
    for (const auto& t : mesh.triangles) {  // a vertex no triangle uses is not part of the surface
      for (const int i : t) {
        if (!contains(tree.nodes()[0].volume, mesh.vertices[i])) return "the hierarchy's root does not bound a vertex";
      }
    }
    return "";
  } catch (const MeshLoadError& e) {
    ::unlink(path.c_str());
    return std::string(e.what()).find(path) == std::string::npos ? "refused without naming the file: " + std::string(e.what())
                                                                  : "";
  }
}

std::string check_srdf(const std::uint8_t* data, std::size_t size) {
  // A revolute, a fixed, a prismatic and a planar joint; the SRDF may add virtual joints.
  static const RobotModel robot = RobotModel::from_urdf(
      *parse_robot_description(
          "<robot name=\"r\"><link name=\"a\"><collision><geometry><box size=\"1 1 1\"/></geometry></collision></link>"
          "<link name=\"b\"><collision><geometry><sphere radius=\"0.5\"/></geometry></collision></link>"
          "<link name=\"c\"/><link name=\"d\"><collision><geometry><sphere radius=\"0.5\"/></geometry></collision></link>"
          "<link name=\"e\"><collision><geometry><sphere radius=\"0.2\"/></geometry></collision></link>"
          "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/><axis xyz=\"0 0 1\"/>"
          "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
          "<joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint>"
          "<joint name=\"j3\" type=\"prismatic\"><parent link=\"c\"/><child link=\"d\"/><axis xyz=\"1 0 0\"/>"
          "<limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
          "<joint name=\"j4\" type=\"planar\"><parent link=\"d\"/><child link=\"e\"/><axis xyz=\"0 0 1\"/></joint></robot>"),
      PackageResolver({}));
  try {
    AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(robot);
    const Srdf srdf = parse_srdf(std::string(reinterpret_cast<const char*>(data), size), &robot);
    if (std::string problem = group_state_problem(srdf, robot); !problem.empty()) return problem;
    apply_srdf(srdf, robot, acm);
    for (std::size_t a = 0; a < acm.size(); ++a) {
      for (std::size_t b = 0; b < acm.size(); ++b) {
        if (acm.allowed(int(a), int(b)) != acm.allowed(int(b), int(a))) return "the matrix is not symmetric";
      }
    }
    return "";
  } catch (const std::invalid_argument& e) {
    return refusal_problem(e.what());
  }
}

namespace {

// A loaded tree: every leaf finite, inside the key range, and the tree reads back what it writes.
std::string check_octree(const Octree& tree) {
  if (!(std::isfinite(tree.resolution()) && tree.resolution() > 0.0)) return "loaded with a resolution that is not positive";
  const std::vector<Octree::Leaf> leaves = tree.leaves();
  for (const Octree::Leaf& leaf : leaves) {
    if (!std::isfinite(leaf.log_odds)) return "loaded with a leaf value that is not finite";
    if (leaf.depth < 0 || leaf.depth > kOctreeDepth) return "loaded with a leaf at depth " + std::to_string(leaf.depth);
  }
  std::stringstream stream;
  tree.write_nodes(stream);
  const Octree again = Octree::read_nodes(stream, tree.resolution(), tree.model());
  const std::vector<Octree::Leaf> reread = again.leaves();
  if (reread.size() != leaves.size()) return "written and read back, the tree has another number of leaves";
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (!(reread[i].key == leaves[i].key) || reread[i].depth != leaves[i].depth || reread[i].log_odds != leaves[i].log_odds) {
      return "written and read back, leaf " + std::to_string(i) + " differs";
    }
  }
  return "";
}

}  // namespace

namespace {

std::string shape_problem(const SceneObject& o, const SceneShape& s) {
  if (!is_rigid(s.pose) || !is_rigid(o.pose)) return "object '" + o.id + "': a pose that is not rigid";
  const ObjectShape& d = s.shape;
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  bool ok = false;
  switch (d.kind) {
    case ObjectShape::Kind::kBox: ok = positive(d.size.x()) && positive(d.size.y()) && positive(d.size.z()); break;
    case ObjectShape::Kind::kSphere: ok = positive(d.radius); break;
    case ObjectShape::Kind::kCylinder:
    case ObjectShape::Kind::kCone:
    case ObjectShape::Kind::kCapsule: ok = positive(d.radius) && positive(d.length); break;
    case ObjectShape::Kind::kMesh:
      ok = d.mesh != nullptr && !d.mesh->triangles.empty() &&
           std::all_of(d.mesh->vertices.begin(), d.mesh->vertices.end(), [](const Vec3& v) { return v.allFinite(); });
      break;
  }
  return ok ? "" : "object '" + o.id + "': a dimension or vertex that is not positive and finite";
}

// The scene written in the form it came in and read back: the same objects and numbers.
std::string round_trip_problem(const SceneFile& scene, bool yaml) {
  std::ostringstream out;
  yaml ? write_scene_yaml(scene, out) : write_scene_text(scene, out);
  std::istringstream in(out.str());
  const SceneFile back = yaml ? read_scene_yaml(in, "written") : read_scene_text(in, "written");
  if (back.objects.size() != scene.objects.size()) return "written and read back, another object count";
  for (std::size_t i = 0; i < back.objects.size(); ++i) {
    const SceneObject& a = scene.objects[i];
    const SceneObject& b = back.objects[i];
    if (a.id != b.id || a.shapes.size() != b.shapes.size()) return "written and read back, object " + std::to_string(i) + " differs";
    if (!a.pose.t.isApprox(b.pose.t, 1e-12) && (a.pose.t - b.pose.t).norm() > 1e-12) return "written and read back, '" + a.id + "' moved";
  }
  return "";
}

}  // namespace

std::string check_scene_file(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return "";
  const bool yaml = data[0] % 2 == 1;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    const SceneFile scene = yaml ? read_scene_yaml(in, "fuzz input") : read_scene_text(in, "fuzz input");
    for (const SceneObject& o : scene.objects) {
      if (o.id.empty() || o.id.find('#') != std::string::npos) return "an object id '" + o.id + "' was accepted";
      if (o.shapes.empty()) return "object '" + o.id + "' without a shape was accepted";
      for (const SceneShape& s : o.shapes) {
        if (std::string problem = shape_problem(o, s); !problem.empty()) return problem;
      }
    }
    scene.environment();  // throws std::invalid_argument for a shape it does not take
    return round_trip_problem(scene, yaml);
  } catch (const SceneFileError& e) {
    return refusal_problem(e.what());
  } catch (const std::invalid_argument& e) {
    return std::string("read, but the environment refused it: ") + e.what();
  }
}

std::string check_octree_file(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return "";
  const OctreeFormat format = data[0] % 2 == 0 ? OctreeFormat::kBinary : OctreeFormat::kFull;
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    return check_octree(read_octree(in, format, "fuzz input"));
  } catch (const std::runtime_error& e) {
    return refusal_problem(e.what());
  } catch (const std::invalid_argument& e) {
    return refusal_problem(e.what());
  }
}

}  // namespace bvh_collision::fuzz
