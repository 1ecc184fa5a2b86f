#include "bvh_collision/robot/urdf_validation.h"

#include <tinyxml2.h>
#include <locale.h>

#include <charconv>
#include <cerrno>
#include <clocale>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

#include "bvh_collision/robot/robot_description.h"

namespace bvh_collision {
namespace {

[[noreturn]] void fail(const std::string& where, const std::string& what) {
  throw RobotDescriptionError(where + ": " + what);
}

// Whitespace-separated decimal numbers, each one complete (no trailing characters), or nothing
// when a token is not a number.
std::optional<std::vector<double>> parse_numbers(const char* text) {
  std::vector<double> out;
  std::istringstream words(text);
  std::string word;
  while (words >> word) {
    const std::optional<double> v = parse_decimal(word);
    if (!v) return std::nullopt;
    out.push_back(*v);
  }
  return out;
}

enum class Sign { kAny, kPositive, kNonZero };

struct Attribute {
  const char* name;
  std::size_t count;
  Sign sign;
};

// The attribute's numbers, checked: the right count, finite, within kMaxCoordinate, the sign.
// A missing optional attribute gives nothing; a missing required one is an error.
std::optional<std::vector<double>> numbers(const tinyxml2::XMLElement& e, const Attribute& a, const std::string& where,
                                           bool required) {
  const char* text = e.Attribute(a.name);
  const std::string quoted = std::string("<") + e.Name() + "> attribute '" + a.name + "'";
  if (text == nullptr) {
    if (required) fail(where, quoted + " is missing");
    return std::nullopt;
  }
  const std::string value = std::string(" is '") + text + "'";
  const auto v = parse_numbers(text);
  if (!v) fail(where, quoted + value + ": not a number");
  if (v->size() != a.count) {
    fail(where, quoted + value + ": needs " + std::to_string(a.count) + (a.count == 1 ? " number" : " numbers") +
                    ", got " + std::to_string(v->size()));
  }
  for (const double x : *v) {
    if (!std::isfinite(x)) fail(where, quoted + value + ": not finite");
    if (std::abs(x) > kMaxCoordinate) {
      fail(where, quoted + value + ": beyond " + std::to_string(static_cast<long>(kMaxCoordinate)) +
                      " (larger than any robot; its geometry would overflow)");
    }
    if (a.sign == Sign::kPositive && !(x > 0.0)) fail(where, quoted + value + ": must be positive");
    if (a.sign == Sign::kNonZero && x == 0.0) fail(where, quoted + value + ": must not be zero");
  }
  return v;
}

void check_origin(const tinyxml2::XMLElement& parent, const std::string& where) {
  if (const tinyxml2::XMLElement* origin = parent.FirstChildElement("origin")) {
    numbers(*origin, {"xyz", 3, Sign::kAny}, where, false);
    numbers(*origin, {"rpy", 3, Sign::kAny}, where, false);
  }
}

int element_count(const tinyxml2::XMLElement& e) {
  int n = 0;
  for (const tinyxml2::XMLElement* c = e.FirstChildElement(); c != nullptr; c = c->NextSiblingElement()) ++n;
  return n;
}

void check_shape(const tinyxml2::XMLElement& shape, const std::string& where) {
  const std::string name = shape.Name();
  if (name == "box") {
    numbers(shape, {"size", 3, Sign::kPositive}, where, true);
  } else if (name == "sphere") {
    numbers(shape, {"radius", 1, Sign::kPositive}, where, true);
  } else if (name == "cylinder") {
    numbers(shape, {"radius", 1, Sign::kPositive}, where, true);
    numbers(shape, {"length", 1, Sign::kPositive}, where, true);
  } else if (name == "mesh") {
    const char* file = shape.Attribute("filename");
    if (file == nullptr || *file == '\0') fail(where, "<mesh> has no filename");
    numbers(shape, {"scale", 3, Sign::kNonZero}, where, false);
  } else {
    fail(where, "unknown shape <" + name + "> (supported: box, sphere, cylinder, mesh)");
  }
}

void check_collision(const tinyxml2::XMLElement& collision, const std::string& where) {
  check_origin(collision, where);
  const tinyxml2::XMLElement* geometry = collision.FirstChildElement("geometry");
  if (geometry == nullptr) fail(where, "<collision> has no <geometry>");
  const int shapes = element_count(*geometry);
  if (shapes == 0) fail(where, "<geometry> is empty (supported shapes: box, sphere, cylinder, mesh)");
  if (shapes > 1) fail(where, "<geometry> holds " + std::to_string(shapes) + " shapes; one per <collision>");
  check_shape(*geometry->FirstChildElement(), where);
}

std::string name_of(const tinyxml2::XMLElement& e) {
  const char* name = e.Attribute("name");
  return name ? name : "";
}

std::string link_of(const tinyxml2::XMLElement& joint, const char* which) {
  const tinyxml2::XMLElement* e = joint.FirstChildElement(which);
  const char* link = e ? e->Attribute("link") : nullptr;
  return link ? link : "";
}

void check_joint(const tinyxml2::XMLElement& joint, std::map<std::string, std::string>& parent_joint) {
  const std::string name = name_of(joint), where = "joint '" + name + "'";
  check_origin(joint, where);
  const std::string parent = link_of(joint, "parent"), child = link_of(joint, "child");
  if (!child.empty() && child == parent) fail(where, "its parent link '" + parent + "' is also its child");
  if (!child.empty()) {
    const auto [it, fresh] = parent_joint.emplace(child, name);
    if (!fresh) fail("link '" + child + "'", "is the child of two joints, '" + it->second + "' and '" + name + "'");
  }
  // urdfdom reads an axis only for moving joints, and limits only for revolute and prismatic.
  const char* type_attribute = joint.Attribute("type");
  const std::string type = type_attribute ? type_attribute : "";
  const bool moves = type == "revolute" || type == "continuous" || type == "prismatic" || type == "planar";
  const tinyxml2::XMLElement* axis = moves ? joint.FirstChildElement("axis") : nullptr;
  if (axis != nullptr) {
    const auto xyz = numbers(*axis, {"xyz", 3, Sign::kAny}, where, false);
    if (xyz && (*xyz)[0] == 0.0 && (*xyz)[1] == 0.0 && (*xyz)[2] == 0.0) {
      fail(where, std::string("<axis> attribute 'xyz' is '") + axis->Attribute("xyz") + "': a zero axis has no direction");
    }
  }
  const bool bounded = type == "revolute" || type == "prismatic";
  if (const tinyxml2::XMLElement* limit = bounded ? joint.FirstChildElement("limit") : nullptr) {
    const auto lower = numbers(*limit, {"lower", 1, Sign::kAny}, where, false);
    const auto upper = numbers(*limit, {"upper", 1, Sign::kAny}, where, false);
    if (lower && upper && (*lower)[0] > (*upper)[0]) {
      fail(where, std::string("<limit> lower '") + limit->Attribute("lower") + "' is above upper '" +
                      limit->Attribute("upper") + "'");
    }
  }
  if (const tinyxml2::XMLElement* mimic = joint.FirstChildElement("mimic")) {
    numbers(*mimic, {"multiplier", 1, Sign::kAny}, where, false);
    numbers(*mimic, {"offset", 1, Sign::kAny}, where, false);
  }
}

// The first control character (U+0000..U+001F, U+007F) in an attribute as written, before
// tinyxml2 replaces its character references: "&#0;" becomes a NUL that ends the C string, so
// the decoded value would look clean and name another file. Returns how it was written.
std::optional<std::string> control_character(const std::string& raw) {
  for (std::size_t i = 0; i < raw.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(raw[i]);
    if (c < 0x20 || c == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof code, "U+%04X", static_cast<unsigned>(c));
      return std::string(code);
    }
    if (raw.compare(i, 2, "&#") != 0) continue;
    const bool hex = i + 2 < raw.size() && (raw[i + 2] == 'x' || raw[i + 2] == 'X');
    const std::size_t digits = i + (hex ? 3 : 2), end = raw.find(';', digits);
    if (end == std::string::npos || end == digits || end - digits > 8) continue;
    unsigned long code = 0;
    const auto [stop, error] = std::from_chars(raw.data() + digits, raw.data() + end, code, hex ? 16 : 10);
    if (error != std::errc() || stop != raw.data() + end) continue;
    if (code < 0x20 || code == 0x7f) return raw.substr(i, end + 1 - i);
  }
  return std::nullopt;
}

// Calls `visit(collision, where)` for every <collision> of every <link>, `where` naming the link
// and the element (1-based) as every message of this file does.
template <class Visit>
void for_each_collision(const tinyxml2::XMLElement& robot, Visit&& visit) {
  for (const tinyxml2::XMLElement* link = robot.FirstChildElement("link"); link != nullptr;
       link = link->NextSiblingElement("link")) {
    int element = 0;
    for (const tinyxml2::XMLElement* c = link->FirstChildElement("collision"); c != nullptr;
         c = c->NextSiblingElement("collision")) {
      visit(*c, "link '" + name_of(*link) + "', collision element " + std::to_string(++element));
    }
  }
}

}  // namespace

void validate_mesh_file_names(const tinyxml2::XMLElement& robot_as_written) {
  for_each_collision(robot_as_written, [](const tinyxml2::XMLElement& c, const std::string& where) {
    const tinyxml2::XMLElement* geometry = c.FirstChildElement("geometry");
    const tinyxml2::XMLElement* mesh = geometry ? geometry->FirstChildElement("mesh") : nullptr;
    const char* file = mesh ? mesh->Attribute("filename") : nullptr;
    if (file == nullptr) return;
    if (const std::optional<std::string> found = control_character(file)) {
      fail(where, "<mesh> attribute 'filename' holds a control character (" + *found + "): not a file name");
    }
  });
}

std::optional<double> parse_decimal(const std::string& word) {
  const char* begin = word.data();
  const char* const end = word.data() + word.size();
  if (begin != end && *begin == '+' && begin + 1 != end && begin[1] != '-') ++begin;  // from_chars takes no '+'
  double v = 0.0;
  const auto [stop, error] = std::from_chars(begin, end, v, std::chars_format::general);
  if (stop != end || begin == end) return std::nullopt;
  if (error == std::errc::result_out_of_range) {
    // A valid decimal too large (infinity) or too small (zero) for a double: strtod in the C
    // locale gives which, whatever the process's locale is.
    static const locale_t c_locale = ::newlocale(LC_NUMERIC_MASK, "C", locale_t(0));
    return ::strtod_l(word.c_str(), nullptr, c_locale);
  }
  if (error != std::errc()) return std::nullopt;
  return v;
}

void validate_robot_xml(const tinyxml2::XMLElement& robot) {
  for_each_collision(robot, check_collision);
  std::map<std::string, std::string> parent_joint;  // child link -> the joint that has it
  for (const tinyxml2::XMLElement* joint = robot.FirstChildElement("joint"); joint != nullptr;
       joint = joint->NextSiblingElement("joint")) {
    check_joint(*joint, parent_joint);
  }
}

}  // namespace bvh_collision
