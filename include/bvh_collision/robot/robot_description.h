// Parsing a URDF robot description and summarising what it holds.
//
// urdfdom reports parse failures only through console_bridge log lines and a null model; this
// layer turns them into an exception whose message says what is wrong (XML syntax with its line,
// a missing <robot> element, or urdfdom's own complaint), so that the node can stop with it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <urdf_model/model.h>

namespace bvh_collision {

// A robot description that cannot be used: the message names the problem.
class RobotDescriptionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Counts that identify a robot model; what the node prints at start-up.
struct RobotSummary {
  std::string name;
  std::string root_link;
  std::size_t links = 0;
  std::size_t joints = 0;
  std::size_t collision_elements = 0;
  std::size_t links_without_collision = 0;
  std::size_t mimic_joints = 0;
  std::size_t nonidentity_collision_origins = 0;
  std::map<std::string, std::size_t> joint_types;         // "revolute" -> 7, ...
  std::map<std::string, std::size_t> collision_geometry;  // "mesh" -> 11, "box" -> ...
  // Links with more than one <collision> element: name -> geometry types in file order.
  std::map<std::string, std::vector<std::string>> links_with_multiple_collisions;

  // One line: name, root, and the counts above.
  std::string to_string() const;
};

// Parses URDF XML. Throws RobotDescriptionError naming the problem when the text is empty,
// not well-formed XML, has no <robot> root element, or is rejected by urdfdom.
std::shared_ptr<urdf::ModelInterface> parse_robot_description(const std::string& xml);

// The largest URDF, SRDF or states file read (bytes): real ones are well under a megabyte.
constexpr std::uintmax_t kMaxDescriptionBytes = std::uintmax_t(64) << 20;

// A description file's text: only a regular file of at most kMaxDescriptionBytes (not a device,
// FIFO or directory). `what` names it in the error ("URDF file", "SRDF file", ...).
std::string read_description_file(const std::string& what, const std::string& path);

// Reads and parses a URDF file; the error names the file.
std::shared_ptr<urdf::ModelInterface> load_robot_description_file(const std::string& path);

RobotSummary summarize(const urdf::ModelInterface& model);

// The lower-case name of a joint type as it is written in URDF ("revolute", "fixed", ...).
const char* joint_type_name(int urdf_joint_type);

}  // namespace bvh_collision
