// Allowed collisions that name collision objects, with MoveIt's semantics (its
// AllowedCollisionMatrix): an entry for a pair of names (a link and an object, or two objects),
// and a default entry per name that answers for every name it has no entry with. An entry for an
// object covers all its shapes. Pairs of links are the robot's own matrix
// (robot/allowed_collision_matrix.h), fixed when the checker is built.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>

namespace bvh_collision {

class NamedAllowedCollisions {
 public:
  void set_entry(const std::string& a, const std::string& b, bool allowed) { entries_[key(a, b)] = allowed; }
  void remove_entry(const std::string& a, const std::string& b) { entries_.erase(key(a, b)); }
  void set_default(const std::string& name, bool allowed) { defaults_[name] = allowed; }
  void remove_default(const std::string& name) { defaults_.erase(name); }

  std::optional<bool> entry(const std::string& a, const std::string& b) const {
    const auto it = entries_.find(key(a, b));
    return it == entries_.end() ? std::nullopt : std::optional<bool>(it->second);
  }
  std::optional<bool> default_entry(const std::string& name) const {
    const auto it = defaults_.find(name);
    return it == defaults_.end() ? std::nullopt : std::optional<bool>(it->second);
  }
  // The pair's entry; without one, the names' default entries (when both have one, allowed only
  // if both allow, as MoveIt answers); without any, not allowed.
  bool allowed(const std::string& a, const std::string& b) const {
    if (const std::optional<bool> e = entry(a, b)) return *e;
    const std::optional<bool> da = default_entry(a), db = default_entry(b);
    if (da && db) return *da && *db;
    return da ? *da : db ? *db : false;
  }
  bool empty() const { return entries_.empty() && defaults_.empty(); }

  // Sorted pairs (first < second) and names, for listing and saving.
  const std::map<std::pair<std::string, std::string>, bool>& entries() const { return entries_; }
  const std::map<std::string, bool>& defaults() const { return defaults_; }

 private:
  static std::pair<std::string, std::string> key(const std::string& a, const std::string& b) {
    return a < b ? std::make_pair(a, b) : std::make_pair(b, a);
  }
  std::map<std::pair<std::string, std::string>, bool> entries_;
  std::map<std::string, bool> defaults_;
};

}  // namespace bvh_collision
