#include "bvh_collision/robot/allowed_collision_matrix.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "bvh_collision/robot/urdf_validation.h"

namespace bvh_collision {

const char* acm_reason_name(AcmReason r) {
  switch (r) {
    case AcmReason::kChecked: return "checked";
    case AcmReason::kAdjacent: return "adjacent";
    case AcmReason::kSrdf: return "srdf";
    case AcmReason::kSrdfDefault: return "srdf-default";
    case AcmReason::kNeverCollide: return "never-collide";
    case AcmReason::kAlwaysCollide: return "always-collide";
  }
  return "?";
}

AllowedCollisionMatrix AllowedCollisionMatrix::adjacent_links(const RobotModel& model) {
  const std::size_t n = model.links().size();
  std::vector<std::set<int>> neighbours(n);
  for (const RobotJoint& j : model.joints()) {
    neighbours[j.parent_link].insert(j.child_link);
    neighbours[j.child_link].insert(j.parent_link);
  }
  // Remove each link without geometry, joining its neighbours to one another.
  for (std::size_t l = 0; l < n; ++l) {
    if (!model.links()[l].collision.empty()) continue;
    const std::vector<int> around(neighbours[l].begin(), neighbours[l].end());
    for (int a : around) {
      neighbours[a].erase(static_cast<int>(l));
      for (int b : around) {
        if (a != b) neighbours[a].insert(b);
      }
    }
    neighbours[l].clear();
  }
  AllowedCollisionMatrix acm(n);
  for (std::size_t a = 0; a < n; ++a) {
    for (int b : neighbours[a]) acm.allow(static_cast<int>(a), b, AcmReason::kAdjacent);
  }
  return acm;
}

namespace {

std::string attribute(const tinyxml2::XMLElement* e, const char* name) {
  const char* v = e->Attribute(name);
  return v ? v : "";
}

[[noreturn]] void group_state_error(const std::string& state, const std::string& joint, int line, const std::string& what) {
  throw std::invalid_argument("SRDF <group_state name=\"" + state + "\"> (line " + std::to_string(line) + "): joint '" + joint +
                              "' " + what);
}

// A <group_state>'s joint values as srdfdom reads them: a space-separated list, each a finite
// decimal ("0." and "1." included), or an error naming the state, the joint and the line
// (tinyxml2's DoubleAttribute would read "abc" or a missing value as 0).
GroupStateJoint joint_values(const tinyxml2::XMLElement& state, const tinyxml2::XMLElement& joint) {
  const std::string state_name = attribute(&state, "name"), joint_name = attribute(&joint, "name");
  GroupStateJoint out;
  out.line = joint.GetLineNum();
  const char* text = joint.Attribute("value");
  if (text == nullptr) group_state_error(state_name, joint_name, out.line, "value is missing");
  std::istringstream words(text);
  for (std::string word; words >> word;) {
    const std::optional<double> v = parse_decimal(word);
    if (!v || !std::isfinite(*v)) {
      group_state_error(state_name, joint_name, out.line,
                        "value '" + std::string(text) + "': '" + word + "' is not a finite number");
    }
    out.values.push_back(*v);
  }
  if (out.values.empty()) group_state_error(state_name, joint_name, out.line, "value '" + std::string(text) + "' holds no number");
  return out;
}

const char* joint_type_word(JointType type) {
  switch (type) {
    case JointType::kFixed: return "fixed";
    case JointType::kRevolute: return "revolute";
    case JointType::kContinuous: return "continuous";
    case JointType::kPrismatic: return "prismatic";
    case JointType::kFloating: return "floating";
    case JointType::kPlanar: return "planar";
  }
  return "?";
}

std::string value_layout(JointType type) {
  switch (type) {
    case JointType::kFloating: return " (x y z qx qy qz qw)";
    case JointType::kPlanar: return " (x y theta)";
    default: return "";
  }
}

// The count the joint's type needs; a floating joint's quaternion scaled to unit length (by its
// largest component first, so that neither 1e-200 nor 1e200 under- or overflows the norm).
void check_joint_values(const std::string& state, const std::string& joint, JointType type, GroupStateJoint& v) {
  const std::size_t need = group_state_value_count(type);
  if (v.values.size() != need) {
    group_state_error(state, joint, v.line,
                      "(" + std::string(joint_type_word(type)) + ") needs " + std::to_string(need) +
                          (need == 1 ? " value" : " values") + value_layout(type) + ", got " + std::to_string(v.values.size()));
  }
  if (type != JointType::kFloating) return;
  double largest = 0.0;
  for (std::size_t i = 3; i < 7; ++i) largest = std::max(largest, std::abs(v.values[i]));
  if (largest == 0.0) group_state_error(state, joint, v.line, "(floating) has a zero quaternion: it is no rotation");
  double norm = 0.0;
  for (std::size_t i = 3; i < 7; ++i) norm += (v.values[i] / largest) * (v.values[i] / largest);
  norm = largest * std::sqrt(norm);
  for (std::size_t i = 3; i < 7; ++i) v.values[i] /= norm;
}

std::optional<JointType> virtual_joint_type(const std::string& type) {
  if (type == "fixed") return JointType::kFixed;
  if (type == "floating") return JointType::kFloating;
  if (type == "planar") return JointType::kPlanar;
  return std::nullopt;
}

SrdfVirtualJoint parse_virtual_joint(const tinyxml2::XMLElement& e) {
  SrdfVirtualJoint v{attribute(&e, "name"), attribute(&e, "parent_frame"), attribute(&e, "child_link"), JointType::kFixed,
                     e.GetLineNum()};
  const std::optional<JointType> type = virtual_joint_type(attribute(&e, "type"));
  if (!type) {
    throw std::invalid_argument("SRDF <virtual_joint name=\"" + v.name + "\"> (line " + std::to_string(v.line) + "): type '" +
                                attribute(&e, "type") + "' is not fixed, floating or planar");
  }
  v.type = *type;
  return v;
}

// Each group state's joints against their types: the robot's joints first, then the SRDF's
// virtual joints (srdfdom looks a name up in the URDF, then among the virtual joints).
void check_group_states(Srdf& srdf, const RobotModel* model) {
  for (auto& [state, joints] : srdf.group_states) {
    for (auto& [joint, values] : joints) {
      const int j = model ? model->joint_index(joint) : -1;
      if (j >= 0) {
        check_joint_values(state, joint, model->joints()[j].type, values);
        continue;
      }
      for (const SrdfVirtualJoint& v : srdf.virtual_joints) {
        if (v.name == joint) {
          check_joint_values(state, joint, v.type, values);
          break;
        }
      }
    }
  }
}

}  // namespace

std::size_t group_state_value_count(JointType type) {
  switch (type) {
    case JointType::kFixed: return 0;
    case JointType::kFloating: return 7;
    case JointType::kPlanar: return 3;
    default: return 1;
  }
}

Srdf parse_srdf(const std::string& xml, const RobotModel* model) {
  tinyxml2::XMLDocument doc;
  if (doc.Parse(xml.c_str(), xml.size()) != tinyxml2::XML_SUCCESS) {
    throw std::invalid_argument("SRDF is not well-formed XML (line " + std::to_string(doc.ErrorLineNum()) + "): " + doc.ErrorStr());
  }
  const tinyxml2::XMLElement* robot = doc.RootElement();
  if (robot == nullptr || std::string(robot->Name()) != "robot") throw std::invalid_argument("SRDF has no <robot> root element");
  Srdf srdf;
  for (const auto* e = robot->FirstChildElement(); e != nullptr; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "disable_collisions") {
      srdf.disabled_pairs.emplace_back(attribute(e, "link1"), attribute(e, "link2"));
    } else if (tag == "enable_collisions") {
      srdf.enabled_pairs.emplace_back(attribute(e, "link1"), attribute(e, "link2"));
    } else if (tag == "disable_default_collisions") {
      srdf.disabled_default_links.push_back(attribute(e, "link"));
    } else if (tag == "virtual_joint") {
      srdf.virtual_joints.push_back(parse_virtual_joint(*e));
    } else if (tag == "group_state") {
      auto& state = srdf.group_states[attribute(e, "name")];
      for (const auto* j = e->FirstChildElement("joint"); j != nullptr; j = j->NextSiblingElement("joint")) {
        state[attribute(j, "name")] = joint_values(*e, *j);
      }
    }
  }
  check_group_states(srdf, model);
  return srdf;
}

std::vector<std::string> apply_srdf(const Srdf& srdf, const RobotModel& model, AllowedCollisionMatrix& acm) {
  std::vector<std::string> unknown;
  auto index = [&](const std::string& name) {
    const int i = model.link_index(name);
    if (i < 0) unknown.push_back(name);
    return i;
  };
  for (const std::string& link : srdf.disabled_default_links) {
    const int a = index(link);
    if (a < 0) continue;
    for (std::size_t b = 0; b < model.links().size(); ++b) {
      if (static_cast<int>(b) != a) acm.allow(a, static_cast<int>(b), AcmReason::kSrdfDefault);
    }
  }
  for (const auto& [l1, l2] : srdf.disabled_pairs) {
    const int a = index(l1), b = index(l2);
    if (a >= 0 && b >= 0) acm.allow(a, b, AcmReason::kSrdf);
  }
  for (const auto& [l1, l2] : srdf.enabled_pairs) {
    const int a = index(l1), b = index(l2);
    if (a >= 0 && b >= 0) acm.check(a, b);
  }
  return unknown;
}

}  // namespace bvh_collision
