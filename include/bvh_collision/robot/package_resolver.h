// Resolving the URIs of URDF meshes (package://, file://, plain paths) without ROS: package
// folders are found the way rospack finds them, by crawling ROS_PACKAGE_PATH for package.xml
// files (a folder with a package.xml is not searched further; CATKIN_IGNORE stops a crawl), then
// catkin's CMAKE_PREFIX_PATH/share/<name>.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace bvh_collision {

class PackageResolver {
 public:
  // Crawls `roots` (folders) now; `prefixes` are catkin install/devel prefixes.
  explicit PackageResolver(const std::vector<std::string>& roots, const std::vector<std::string>& prefixes = {});
  // From ROS_PACKAGE_PATH and CMAKE_PREFIX_PATH.
  static PackageResolver from_environment();

  std::optional<std::string> package_path(const std::string& name) const;

  // The absolute file path a URI names. Throws std::invalid_argument with the reason (unknown
  // package, unsupported scheme) when it cannot be resolved; does not check that the file exists.
  std::string resolve(const std::string& uri) const;

 private:
  std::map<std::string, std::string> packages_;
  std::vector<std::string> prefixes_;
};

// Splits a colon-separated path list, dropping empty entries.
std::vector<std::string> split_path_list(const std::string& list);

}  // namespace bvh_collision
