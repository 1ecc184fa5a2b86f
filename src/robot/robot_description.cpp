#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/robot/urdf_validation.h"

#include <console_bridge/console.h>
#include <tinyxml2.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>

namespace bvh_collision {
namespace {

// Collects urdfdom's error messages while a parse runs. console_bridge has one global handler,
// so parses are serialised by a mutex and the previous handler is restored afterwards.
class CapturingOutputHandler : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_WARN) {
      if (!messages.empty()) messages += "; ";
      messages += text;
    }
  }
  std::string messages;
};

std::mutex& console_mutex() {
  static std::mutex m;
  return m;
}

// XML's attribute-value normalization, which TinyXML 1 (urdfdom) skips: a tab or line break
// inside a value is a space. urdfdom splits numbers on spaces only, so "0\n0 0.1" passed the
// validation as three numbers and then lost its whole <collision> in urdfdom (found by
// fuzz_robot_description).
void normalize_attribute_whitespace(tinyxml2::XMLElement& e) {
  for (const tinyxml2::XMLAttribute* a = e.FirstAttribute(); a != nullptr; a = a->Next()) {
    std::string value = a->Value();
    if (value.find_first_of("\t\n\r") == std::string::npos) continue;
    std::replace_if(value.begin(), value.end(), [](char c) { return c == '\t' || c == '\n' || c == '\r'; }, ' ');
    e.SetAttribute(a->Name(), value.c_str());
  }
  for (tinyxml2::XMLElement* c = e.FirstChildElement(); c != nullptr; c = c->NextSiblingElement()) {
    normalize_attribute_whitespace(*c);
  }
}

// tinyxml2 gives the line of a syntax error, which urdfdom's tinyxml parse does not report.
// Returns the validated document as tinyxml2 prints it back, which is what urdfdom then reads:
// urdfdom parses with TinyXML 1, which reads some text differently (an unknown entity such as
// "b&ase" in a name), and the document checked must be the document loaded.
std::string check_xml(const std::string& xml) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    throw RobotDescriptionError("robot description is not well-formed XML (line " +
                                std::to_string(doc.ErrorLineNum()) + "): " + doc.ErrorStr());
  }
  tinyxml2::XMLElement* root = doc.RootElement();
  if (root == nullptr || std::string(root->Name()) != "robot") {
    throw RobotDescriptionError(std::string("robot description has no <robot> root element (found <") +
                                (root ? root->Name() : "nothing") + ">)");
  }
  tinyxml2::XMLDocument as_written(/*processEntities=*/false);
  as_written.Parse(xml.c_str(), xml.size());  // the same text, parsed above
  validate_mesh_file_names(*as_written.RootElement());
  normalize_attribute_whitespace(*root);
  validate_robot_xml(*root);  // what urdfdom would drop or accept silently
  tinyxml2::XMLPrinter printer(nullptr, /*compact=*/true);
  doc.Print(&printer);
  return std::string(printer.CStr(), static_cast<std::size_t>(printer.CStrSize() - 1));
}

std::string geometry_name(const urdf::Geometry& g) {
  switch (g.type) {
    case urdf::Geometry::SPHERE: return "sphere";
    case urdf::Geometry::BOX: return "box";
    case urdf::Geometry::CYLINDER: return "cylinder";
    case urdf::Geometry::MESH: return "mesh";
  }
  return "unknown";
}

bool is_identity(const urdf::Pose& p) {
  const bool no_rotation = p.rotation.x == 0.0 && p.rotation.y == 0.0 && p.rotation.z == 0.0;
  return p.position.x == 0.0 && p.position.y == 0.0 && p.position.z == 0.0 && no_rotation;
}

}  // namespace

const char* joint_type_name(int urdf_joint_type) {
  switch (urdf_joint_type) {
    case urdf::Joint::REVOLUTE: return "revolute";
    case urdf::Joint::CONTINUOUS: return "continuous";
    case urdf::Joint::PRISMATIC: return "prismatic";
    case urdf::Joint::FLOATING: return "floating";
    case urdf::Joint::PLANAR: return "planar";
    case urdf::Joint::FIXED: return "fixed";
    default: return "unknown";
  }
}

std::shared_ptr<urdf::ModelInterface> parse_robot_description(const std::string& xml) {
  if (xml.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw RobotDescriptionError("robot description is empty");
  }
  const std::string validated = check_xml(xml);
  std::lock_guard<std::mutex> lock(console_mutex());
  CapturingOutputHandler handler;
  console_bridge::useOutputHandler(&handler);
  std::shared_ptr<urdf::ModelInterface> model = urdf::parseURDF(validated);
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    throw RobotDescriptionError("urdfdom rejected the robot description: " +
                                (handler.messages.empty() ? std::string("no reason given")
                                                          : handler.messages));
  }
  return model;
}

std::string read_description_file(const std::string& what, const std::string& path) {
  // Only regular files, and not without bound: /dev/zero is read forever, a FIFO blocks.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) throw RobotDescriptionError("cannot open " + what + " '" + path + "'");
  if (!std::filesystem::is_regular_file(status)) {
    throw RobotDescriptionError(what + " '" + path + "' is not a regular file");
  }
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size > kMaxDescriptionBytes) {
    throw RobotDescriptionError(what + " '" + path + "' is larger than " + std::to_string(kMaxDescriptionBytes >> 20) +
                                " MiB");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RobotDescriptionError("cannot open " + what + " '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::shared_ptr<urdf::ModelInterface> load_robot_description_file(const std::string& path) {
  const std::string text = read_description_file("URDF file", path);
  try {
    return parse_robot_description(text);
  } catch (const RobotDescriptionError& e) {
    throw RobotDescriptionError("URDF file '" + path + "': " + e.what());
  }
}

RobotSummary summarize(const urdf::ModelInterface& model) {
  RobotSummary s;
  s.name = model.getName();
  if (model.getRoot()) s.root_link = model.getRoot()->name;
  s.links = model.links_.size();
  s.joints = model.joints_.size();
  for (const auto& [name, link] : model.links_) {
    std::vector<urdf::CollisionSharedPtr> elements;
    for (const auto& c : link->collision_array) {
      if (c && c->geometry) elements.push_back(c);
    }
    // urdfdom fills collision_array for every <collision>; older versions kept a lone element
    // only in `collision`, so fall back to it.
    if (elements.empty() && link->collision && link->collision->geometry) {
      elements.push_back(link->collision);
    }
    std::vector<std::string> types;
    for (const auto& c : elements) {
      types.push_back(geometry_name(*c->geometry));
      ++s.collision_geometry[types.back()];
      if (!is_identity(c->origin)) ++s.nonidentity_collision_origins;
    }
    s.collision_elements += elements.size();
    if (elements.empty()) ++s.links_without_collision;
    if (elements.size() > 1) s.links_with_multiple_collisions[name] = std::move(types);
  }
  for (const auto& [name, joint] : model.joints_) {
    ++s.joint_types[joint_type_name(joint->type)];
    if (joint->mimic) ++s.mimic_joints;
  }
  return s;
}

std::string RobotSummary::to_string() const {
  std::ostringstream out;
  out << "robot '" << name << "' (root link '" << root_link << "'): " << links << " links, "
      << joints << " joints (";
  bool first = true;
  for (const auto& [type, n] : joint_types) {
    out << (first ? "" : ", ") << n << ' ' << type;
    first = false;
  }
  if (mimic_joints > 0) out << ", " << mimic_joints << " mimic";
  out << "), " << collision_elements << " collision elements (";
  first = true;
  for (const auto& [type, n] : collision_geometry) {
    out << (first ? "" : ", ") << n << ' ' << type;
    first = false;
  }
  out << "), " << links_without_collision
      << (links_without_collision == 1 ? " link" : " links") << " without collision geometry";
  return out.str();
}

}  // namespace bvh_collision
