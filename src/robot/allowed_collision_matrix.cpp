#include "bvh_collision/robot/allowed_collision_matrix.h"

#include <tinyxml2.h>

#include <cmath>
#include <optional>
#include <set>
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

// A <group_state>'s joint value: a finite decimal number, or an error naming the state, the joint
// and the line (tinyxml2's DoubleAttribute would read "abc" or a missing value as 0).
double joint_value(const tinyxml2::XMLElement& state, const tinyxml2::XMLElement& joint) {
  const char* text = joint.Attribute("value");
  const std::optional<double> v = text ? parse_decimal(text) : std::nullopt;
  if (!v || !std::isfinite(*v)) {
    throw std::invalid_argument("SRDF <group_state name=\"" + std::string(state.Attribute("name") ? state.Attribute("name") : "") +
                                "\"> (line " + std::to_string(joint.GetLineNum()) + "): joint '" +
                                (joint.Attribute("name") ? joint.Attribute("name") : "") + "' value " +
                                (text ? "'" + std::string(text) + "' is not a finite number" : "is missing"));
  }
  return *v;
}

}  // namespace

Srdf parse_srdf(const std::string& xml) {
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
    } else if (tag == "group_state") {
      auto& state = srdf.group_states[attribute(e, "name")];
      for (const auto* j = e->FirstChildElement("joint"); j != nullptr; j = j->NextSiblingElement("joint")) {
        state[attribute(j, "name")] = joint_value(*e, *j);
      }
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
