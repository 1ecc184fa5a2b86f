// Link proxies kept on disk by content. A proxy depends only on its link's shapes and its level,
// and proves its bounds for that geometry (narrowphase/link_proxy.h), so it can be stored once and
// read at every later start (a build takes seconds, a read milliseconds: docs/performance.md).
// The key is a 64-bit FNV-1a hash of every number that describes the link
// (shape origins, primitives, each mesh's triangles and whether it is closed), the level and the
// builder's version; a file is used only when its key, format, structure and checksum all agree,
// and any other is rebuilt and replaced (written to a temporary name, then renamed).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/narrowphase/link_proxy.h"

namespace bvh_collision {

// Bump when LinkProxy::build changes what it builds: files of another version are rebuilt.
constexpr std::uint32_t kLinkProxyBuildVersion = 1;

std::uint64_t link_proxy_key(const std::vector<BodyShape>& shapes, double level);

// Whether two links' shapes have every number the key covers the same, bit for bit (the same
// meshes' triangles at the same origins: a robot's left and right arm, its four casters). Such
// links have the same proxy at every level.
bool same_shapes(const std::vector<BodyShape>& a, const std::vector<BodyShape>& b);

// Per link, the first link whose shapes are the same (same_shapes), itself when none before it is:
// a link alike an earlier one takes a copy of that one's proxy instead of a build of its own. (A
// link without shapes is its own.)
std::vector<std::size_t> first_alike(const std::vector<std::vector<BodyShape>>& links);

// The file that holds the proxy of `key` in `folder`.
std::string link_proxy_file(const std::string& folder, std::uint64_t key);

// The proxy stored under `key`, or nothing (no file, or one that does not check out).
std::optional<LinkProxy> read_cached_link_proxy(const std::string& folder, std::uint64_t key);

// Stores `proxy` under `key` (creating the folder); false when it cannot be written.
bool write_cached_link_proxy(const std::string& folder, std::uint64_t key, const LinkProxy& proxy);

}  // namespace bvh_collision
