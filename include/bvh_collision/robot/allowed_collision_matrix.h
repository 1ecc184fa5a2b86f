// Which link pairs are never checked, and why: links adjacent through a joint (after collapsing
// links without geometry, as MoveIt's setup assistant does), SRDF entries, and sampled pairs.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

enum class AcmReason : std::uint8_t {
  kChecked = 0,
  kAdjacent,        // linked by a joint (through links without geometry)
  kSrdf,            // SRDF <disable_collisions>
  kSrdfDefault,     // SRDF <disable_default_collisions>
  kNeverCollide,    // sampling: never in collision
  kAlwaysCollide,   // sampling: always in collision
};

const char* acm_reason_name(AcmReason r);

class AllowedCollisionMatrix {
 public:
  AllowedCollisionMatrix() = default;
  explicit AllowedCollisionMatrix(std::size_t links) : n_(links), reasons_(links * links, AcmReason::kChecked) {}

  // Adjacency of `model`: every pair of links with geometry that a chain of joints through
  // geometry-less links connects.
  static AllowedCollisionMatrix adjacent_links(const RobotModel& model);

  void allow(int a, int b, AcmReason why) { set(a, b, why); }
  void check(int a, int b) { set(a, b, AcmReason::kChecked); }
  bool allowed(int a, int b) const { return reasons_[a * n_ + b] != AcmReason::kChecked; }
  AcmReason reason(int a, int b) const { return reasons_[a * n_ + b]; }
  std::size_t size() const { return n_; }
  // The same entries for the first size() links, and `links` - size() more links, checked
  // against everything (links appended to a model: RobotModel::with_fixed_link).
  AllowedCollisionMatrix grown_to(std::size_t links) const {
    AllowedCollisionMatrix out(links);
    for (std::size_t a = 0; a < n_ && a < links; ++a) {
      for (std::size_t b = 0; b < n_ && b < links; ++b) out.reasons_[a * links + b] = reasons_[a * n_ + b];
    }
    return out;
  }

 private:
  void set(int a, int b, AcmReason why) {
    reasons_[a * n_ + b] = why;
    reasons_[b * n_ + a] = why;
  }
  std::size_t n_ = 0;
  std::vector<AcmReason> reasons_;
};

// One joint of a <group_state>: its value attribute as srdfdom reads it, a space-separated list
// with one number per variable of the joint (floating: x y z qx qy qz qw; planar: x y theta;
// revolute, continuous, prismatic: one).
struct GroupStateJoint {
  std::vector<double> values;
  int line = 0;  // in the SRDF, for messages
};

// <virtual_joint>: how the robot's root is attached to a frame outside it (a floating base, a
// mobile base on a plane, a fixed mount).
struct SrdfVirtualJoint {
  std::string name, parent_frame, child_link;
  JointType type = JointType::kFixed;
  int line = 0;
};

// What an SRDF says that the collision checker uses.
struct Srdf {
  std::vector<std::pair<std::string, std::string>> disabled_pairs;
  std::vector<std::string> disabled_default_links;
  std::vector<std::pair<std::string, std::string>> enabled_pairs;
  std::vector<SrdfVirtualJoint> virtual_joints;
  // <group_state name group>: joint values by joint name.
  std::map<std::string, std::map<std::string, GroupStateJoint>> group_states;
  // What srdfdom or MoveIt's RobotModel would log and skip, skipped here too, each naming the
  // element (and its line): the caller shows them (the node's log, the tool's stderr).
  std::vector<std::string> warnings;
};

// How many values a joint of this type takes in a group state (its variables: 0 for fixed).
std::size_t group_state_value_count(JointType type);

// Parses SRDF XML with tinyxml2 as srdfdom does, and group states as MoveIt's RobotModel takes
// them: what they refuse is refused (std::invalid_argument: XML that is not well formed, a root
// that is not <robot>), and what they log and skip is skipped with a warning in Srdf::warnings (an
// element without the attributes it needs, a virtual joint on a link the robot lacks, a group
// state of a group the SRDF does not define or for a joint the robot lacks, a value count that
// does not fit the joint, a floating joint's zero quaternion); an unknown virtual joint type is
// taken as fixed, with a warning. Names are trimmed. One refusal of our own: a group-state value
// that is not a finite decimal (srdfdom would read "abc" as 0), with the state, the joint and
// the line. A floating joint's quaternion is normalised. Without a model, joints are known by the
// virtual joints only and others keep their values unchecked.
Srdf parse_srdf(const std::string& xml, const RobotModel* model = nullptr);

// Applies the SRDF to the matrix: default-disabled links, disabled pairs, then enabled pairs
// (which win). Names absent from the model are skipped and returned, so callers can warn.
std::vector<std::string> apply_srdf(const Srdf& srdf, const RobotModel& model, AllowedCollisionMatrix& acm);

}  // namespace bvh_collision
