// What a robot description may not contain, checked on the XML before urdfdom reads it.
//
// urdfdom drops a <collision> element it cannot parse (a radius of "nan" or "abc", a box of two
// numbers, an empty <geometry/>, an unknown shape) with a log line at most, and accepts numbers
// that make the geometry vanish or overflow (1e300, 1e308). A robot that silently loses a link's
// geometry answers "free" where it collides, so every such input is refused here, by name:
//
//   - every <collision> has one <geometry> holding exactly one of box, sphere, cylinder, mesh;
//   - every number (sizes, radii, lengths, mesh scales, origins, joint origins, axes, limits) is
//     a complete decimal number, finite, with the count its attribute needs, and within
//     kMaxCoordinate of 0 (beyond it corners and products overflow or lose every digit);
//   - sizes, radii and lengths are positive, mesh scales non-zero, a mesh names its file;
//   - a mesh file name holds no control character (U+0000..U+001F, U+007F), written or referenced;
//   - a joint's axis is not zero, its lower limit is not above its upper one, its parent is not its
//     child, and no link is the child of two joints.
//
// The message names the link (and collision element, 1-based) or joint, the attribute and the
// value found.
#pragma once

#include <optional>
#include <string>

namespace tinyxml2 {
class XMLElement;
}

namespace bvh_collision {

// The largest magnitude of a length or coordinate a robot description may hold (m).
constexpr double kMaxCoordinate = 1e5;

// One decimal number as URDF, SRDF, STL and states files write it ("-1.5e-3"; "nan" and "inf"
// are numbers, not finite ones), independent of the C locale; nothing for anything else,
// hexadecimal included (strtod reads "0x10" as 16, urdfdom refuses it and drops the element).
// A magnitude too large for a double gives infinity.
std::optional<double> parse_decimal(const std::string& word);

// Throws RobotDescriptionError for the first problem found under <robot>.
void validate_robot_xml(const tinyxml2::XMLElement& robot);

// Throws RobotDescriptionError for a <mesh> file name that holds a control character, literally
// or as a character reference ("mesh.stl&#0;x" would open mesh.stl). `robot_as_written` is the
// document parsed without replacing character references: once replaced, a NUL ends the value.
void validate_mesh_file_names(const tinyxml2::XMLElement& robot_as_written);

}  // namespace bvh_collision
