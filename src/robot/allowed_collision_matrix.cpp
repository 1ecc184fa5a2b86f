#include "bvh_collision/robot/allowed_collision_matrix.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cctype>
#include <map>
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

// An attribute as srdfdom reads it: trimmed of surrounding blanks; nothing when absent.
std::optional<std::string> attribute(const tinyxml2::XMLElement* e, const char* name) {
  const char* v = e->Attribute(name);
  if (v == nullptr) return std::nullopt;
  std::string s(v);
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return std::string();
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

std::string line_of(const tinyxml2::XMLElement& e) { return "(line " + std::to_string(e.GetLineNum()) + ")"; }

[[noreturn]] void group_state_error(const std::string& state, const std::string& joint, int line, const std::string& what) {
  throw std::invalid_argument("SRDF <group_state name=\"" + state + "\"> (line " + std::to_string(line) + "): joint '" + joint +
                              "' " + what);
}

// A <group_state>'s joint values: a space-separated list, each a finite decimal ("0." and "1."
// included), or an error naming the state, the joint and the line (srdfdom would read "abc" as
// 0 and MoveIt would use it: a value that is not a number is refused here).
GroupStateJoint joint_values(const std::string& state_name, const std::string& joint_name, const tinyxml2::XMLElement& joint,
                             const char* text) {
  GroupStateJoint out;
  out.line = joint.GetLineNum();
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

// The values a joint of `type` can take from a state, or why not (then Moveit's RobotModel logs
// it and the state leaves the joint alone; so does this, with a warning). A floating joint's
// quaternion is scaled to unit length (by its largest component first, so that neither 1e-200
// nor 1e200 under- or overflows the norm).
std::string usable_values(JointType type, GroupStateJoint& v) {
  const std::size_t need = group_state_value_count(type);
  if (v.values.size() != need) {
    return "(" + std::string(joint_type_word(type)) + ") needs " + std::to_string(need) + (need == 1 ? " value" : " values") +
           value_layout(type) + ", got " + std::to_string(v.values.size());
  }
  if (type != JointType::kFloating) return "";
  double largest = 0.0;
  for (std::size_t i = 3; i < 7; ++i) largest = std::max(largest, std::abs(v.values[i]));
  if (largest == 0.0) return "(floating) has a zero quaternion: it is no rotation";
  double norm = 0.0;
  for (std::size_t i = 3; i < 7; ++i) norm += (v.values[i] / largest) * (v.values[i] / largest);
  norm = largest * std::sqrt(norm);
  for (std::size_t i = 3; i < 7; ++i) v.values[i] /= norm;
  return "";
}

// srdfdom's reading of a <virtual_joint>: skipped when an attribute is missing or the child is
// not a link; an unknown type is taken as fixed.
std::optional<SrdfVirtualJoint> parse_virtual_joint(const tinyxml2::XMLElement& e, const RobotModel* model, std::vector<std::string>& warnings) {
  const std::optional<std::string> name = attribute(&e, "name"), child = attribute(&e, "child_link"),
                                   parent = attribute(&e, "parent_frame"), type = attribute(&e, "type");
  const std::string where = "SRDF <virtual_joint> " + line_of(e) + ": ";
  if (!name || !child || !parent || !type) {
    warnings.push_back(where + "its name, child_link, parent_frame or type is missing: ignored (as srdfdom ignores it)");
    return std::nullopt;
  }
  if (model != nullptr && model->link_index(*child) < 0) {
    warnings.push_back(where + "'" + *name + "' holds link '" + *child + "', which the robot does not have: ignored");
    return std::nullopt;
  }
  SrdfVirtualJoint v{*name, *parent, *child, JointType::kFixed, e.GetLineNum()};
  std::string word = *type;
  std::transform(word.begin(), word.end(), word.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (word == "floating") v.type = JointType::kFloating;
  else if (word == "planar") v.type = JointType::kPlanar;
  else if (word != "fixed") warnings.push_back(where + "'" + *name + "' of type '" + *type + "': taken as fixed (as srdfdom takes it)");
  return v;
}

// The groups srdfdom keeps: every named group whose subgroups are kept too.
std::set<std::string> known_groups(const tinyxml2::XMLElement& robot, std::vector<std::string>& warnings) {
  std::map<std::string, std::vector<std::string>> subgroups;
  for (const auto* g = robot.FirstChildElement("group"); g != nullptr; g = g->NextSiblingElement("group")) {
    const std::optional<std::string> name = attribute(g, "name");
    if (!name) {
      warnings.push_back("SRDF <group> " + line_of(*g) + ": no name: ignored");
      continue;
    }
    auto& subs = subgroups[*name];
    for (const auto* s = g->FirstChildElement("group"); s != nullptr; s = s->NextSiblingElement("group")) {
      if (const std::optional<std::string> sub = attribute(s, "name")) subs.push_back(*sub);
    }
  }
  std::set<std::string> known;
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& [name, subs] : subgroups) {
      if (known.count(name) == 0 && std::all_of(subs.begin(), subs.end(), [&](const std::string& s) { return known.count(s) > 0; })) {
        grew = known.insert(name).second || grew;
      }
    }
  }
  for (const auto& [name, subs] : subgroups) {
    if (known.count(name) == 0) warnings.push_back("SRDF group '" + name + "' has subgroups it does not define: ignored");
  }
  return known;
}

// Is `joint` a joint srdfdom knows: the robot's (when a model is given) or a virtual joint?
std::optional<JointType> joint_type(const std::string& joint, const Srdf& srdf, const RobotModel* model) {
  if (model != nullptr) {
    const int j = model->joint_index(joint);
    if (j >= 0) return model->joints()[static_cast<std::size_t>(j)].type;
  }
  for (const SrdfVirtualJoint& v : srdf.virtual_joints) {
    if (v.name == joint) return v.type;
  }
  return std::nullopt;
}

// One <group_state>, as srdfdom and MoveIt's RobotModel take it: what they skip is skipped with a
// warning; a joint known to neither the model nor the virtual joints (and no model given) is kept
// unchecked.
void parse_group_state(const tinyxml2::XMLElement& e, const std::set<std::string>& groups, const RobotModel* model, Srdf& srdf) {
  const std::optional<std::string> name = attribute(&e, "name"), group = attribute(&e, "group");
  const std::string where = "SRDF <group_state> " + line_of(e) + ": ";
  if (!name || !group) {
    srdf.warnings.push_back(where + "its name or group is missing: ignored (as srdfdom ignores it)");
    return;
  }
  if (groups.count(*group) == 0) {
    srdf.warnings.push_back(where + "'" + *name + "' is of group '" + *group + "', which the SRDF does not define: ignored");
    return;
  }
  auto& state = srdf.group_states[*name];
  for (const auto* j = e.FirstChildElement("joint"); j != nullptr; j = j->NextSiblingElement("joint")) {
    const std::optional<std::string> joint = attribute(j, "name");
    const char* value = j->Attribute("value");
    const std::string at = "SRDF <group_state name=\"" + *name + "\"> " + line_of(*j) + ": ";
    if (!joint || value == nullptr) {
      srdf.warnings.push_back(at + "a joint without a name or a value: ignored");
      continue;
    }
    GroupStateJoint values = joint_values(*name, *joint, *j, value);
    const std::optional<JointType> type = joint_type(*joint, srdf, model);
    if (!type && model != nullptr) {
      srdf.warnings.push_back(at + "joint '" + *joint + "' is not a joint of the robot: ignored");
      continue;
    }
    if (type) {
      if (const std::string why = usable_values(*type, values); !why.empty()) {
        srdf.warnings.push_back(at + "joint '" + *joint + "' " + why + ": this state does not set it (as MoveIt)");
        continue;
      }
    }
    state[*joint] = std::move(values);
  }
}

// <disable_collisions>, <enable_collisions>: a pair without both links is skipped.
void parse_pair(const tinyxml2::XMLElement& e, std::vector<std::pair<std::string, std::string>>& pairs, Srdf& srdf) {
  const std::optional<std::string> a = attribute(&e, "link1"), b = attribute(&e, "link2");
  if (!a || !b) {
    srdf.warnings.push_back("SRDF <" + std::string(e.Name()) + "> " + line_of(e) + ": link1 or link2 is missing: ignored");
    return;
  }
  pairs.emplace_back(*a, *b);
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
  const std::optional<std::string> name = attribute(robot, "name");
  if (!name) srdf.warnings.push_back("SRDF <robot> has no name");
  else if (model != nullptr && !model->name().empty() && *name != model->name()) {
    srdf.warnings.push_back("SRDF is for robot '" + *name + "', the URDF is '" + model->name() + "' (used all the same, as srdfdom does)");
  }
  for (const auto* e = robot->FirstChildElement("virtual_joint"); e != nullptr; e = e->NextSiblingElement("virtual_joint")) {
    if (std::optional<SrdfVirtualJoint> v = parse_virtual_joint(*e, model, srdf.warnings)) srdf.virtual_joints.push_back(std::move(*v));
  }
  const std::set<std::string> groups = known_groups(*robot, srdf.warnings);
  for (const auto* e = robot->FirstChildElement(); e != nullptr; e = e->NextSiblingElement()) {
    const std::string tag = e->Name();
    if (tag == "disable_collisions") {
      parse_pair(*e, srdf.disabled_pairs, srdf);
    } else if (tag == "enable_collisions") {
      parse_pair(*e, srdf.enabled_pairs, srdf);
    } else if (tag == "disable_default_collisions") {
      if (const std::optional<std::string> link = attribute(e, "link")) srdf.disabled_default_links.push_back(*link);
      else srdf.warnings.push_back("SRDF <disable_default_collisions> " + line_of(*e) + ": no link: ignored");
    } else if (tag == "group_state") {
      parse_group_state(*e, groups, model, srdf);
    }
  }
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
