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

 private:
  void set(int a, int b, AcmReason why) {
    reasons_[a * n_ + b] = why;
    reasons_[b * n_ + a] = why;
  }
  std::size_t n_ = 0;
  std::vector<AcmReason> reasons_;
};

// What an SRDF says that the collision checker uses.
struct Srdf {
  std::vector<std::pair<std::string, std::string>> disabled_pairs;
  std::vector<std::string> disabled_default_links;
  std::vector<std::pair<std::string, std::string>> enabled_pairs;
  // <group_state name group>: joint values by joint name.
  std::map<std::string, std::map<std::string, double>> group_states;
};

// Parses SRDF XML with tinyxml2; throws std::invalid_argument (with the XML line) when malformed.
Srdf parse_srdf(const std::string& xml);

// Applies the SRDF to the matrix: default-disabled links, disabled pairs, then enabled pairs
// (which win). Names absent from the model are skipped and returned, so callers can warn.
std::vector<std::string> apply_srdf(const Srdf& srdf, const RobotModel& model, AllowedCollisionMatrix& acm);

}  // namespace bvh_collision
