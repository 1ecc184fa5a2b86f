#include "bvh_collision/robot/package_resolver.h"

#include <tinyxml2.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

namespace bvh_collision {
namespace fs = std::filesystem;

namespace {

std::optional<std::string> package_name(const fs::path& manifest) {
  tinyxml2::XMLDocument doc;
  if (doc.LoadFile(manifest.c_str()) != tinyxml2::XML_SUCCESS) return std::nullopt;
  const tinyxml2::XMLElement* root = doc.RootElement();
  const tinyxml2::XMLElement* name = root ? root->FirstChildElement("name") : nullptr;
  if (name == nullptr || name->GetText() == nullptr) return std::nullopt;
  std::string text = name->GetText();
  text.erase(0, text.find_first_not_of(" \t\r\n"));
  text.erase(text.find_last_not_of(" \t\r\n") + 1);
  return text;
}

// rospack's crawl: the first package found under a name wins (earlier roots first).
void crawl(const fs::path& dir, std::map<std::string, std::string>& packages, int depth) {
  std::error_code ec;
  if (depth > 16 || !fs::is_directory(dir, ec) || fs::exists(dir / "CATKIN_IGNORE", ec)) return;
  if (fs::exists(dir / "package.xml", ec)) {
    if (const auto name = package_name(dir / "package.xml")) packages.emplace(*name, fs::absolute(dir).string());
    return;
  }
  for (const auto& entry : fs::directory_iterator(dir, fs::directory_options::skip_permission_denied, ec)) {
    const std::string leaf = entry.path().filename().string();
    if (!leaf.empty() && leaf[0] == '.') continue;
    if (entry.is_directory(ec)) crawl(entry.path(), packages, depth + 1);
  }
}

}  // namespace

std::vector<std::string> split_path_list(const std::string& list) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t end = list.find(':', start);
    const std::string item = list.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (!item.empty()) out.push_back(item);
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

PackageResolver::PackageResolver(const std::vector<std::string>& roots, const std::vector<std::string>& prefixes)
    : prefixes_(prefixes) {
  for (const std::string& root : roots) crawl(root, packages_, 0);
}

PackageResolver PackageResolver::from_environment() {
  const char* rpp = std::getenv("ROS_PACKAGE_PATH");
  const char* cpp = std::getenv("CMAKE_PREFIX_PATH");
  return PackageResolver(split_path_list(rpp ? rpp : ""), split_path_list(cpp ? cpp : ""));
}

std::optional<std::string> PackageResolver::package_path(const std::string& name) const {
  if (const auto it = packages_.find(name); it != packages_.end()) return it->second;
  for (const std::string& prefix : prefixes_) {
    const fs::path share = fs::path(prefix) / "share" / name;
    std::error_code ec;
    if (fs::exists(share / "package.xml", ec)) return share.string();
  }
  return std::nullopt;
}

std::string PackageResolver::resolve(const std::string& uri) const {
  // A control character has no place in a file name, and a NUL would cut the name short: the
  // open would then read another file ("mesh.stl\0x" opened "mesh.stl").
  const auto control = std::find_if(uri.begin(), uri.end(), [](unsigned char c) { return c < 0x20 || c == 0x7f; });
  if (control != uri.end()) {
    char code[8];
    std::snprintf(code, sizeof code, "U+%04X", static_cast<unsigned>(static_cast<unsigned char>(*control)));
    throw std::invalid_argument("the URI holds a control character (" + std::string(code) + " at byte " +
                                std::to_string(control - uri.begin()) + ")");
  }
  const std::string package_scheme = "package://", file_scheme = "file://";
  if (uri.rfind(package_scheme, 0) == 0) {
    const std::string rest = uri.substr(package_scheme.size());
    const std::size_t slash = rest.find('/');
    const std::string name = rest.substr(0, slash);
    const auto dir = package_path(name);
    if (!dir) {
      throw std::invalid_argument("package '" + name + "' not found (searched ROS_PACKAGE_PATH and catkin prefixes)");
    }
    return slash == std::string::npos ? *dir : (fs::path(*dir) / rest.substr(slash + 1)).string();
  }
  if (uri.rfind(file_scheme, 0) == 0) return uri.substr(file_scheme.size());
  const std::size_t colon = uri.find("://");
  if (colon != std::string::npos) {
    throw std::invalid_argument("unsupported URI scheme '" + uri.substr(0, colon) + "://' (use package://, file:// or a path)");
  }
  return uri;
}

}  // namespace bvh_collision
