// The OctoMap bridge: conversion to and from octomap::OcTree, and OctoMap's .bt and .ot files.
// This header only declares OctoMap's type; its .cpp is the one file that includes OctoMap.
#pragma once

#include <istream>
#include <string>

#include "bvh_collision/octree/octree.h"

namespace octomap {
class OcTree;
}

namespace bvh_collision {

// Node for node (same structure, values and sensor model). Values are exact; the model's
// parameters pass through OctoMap's probability setters, so they may move by one float ulp.
void to_octomap(const Octree& tree, octomap::OcTree& out);
Octree from_octomap(const octomap::OcTree& tree);

// .bt (OctoMap's compact binary: occupied / free per leaf, values become the clamping limits)
// or .ot (every value), chosen by the file's extension. Both throw std::runtime_error with the
// path and the reason when a file cannot be read or written, or is not an OcTree.
Octree load_octree(const std::string& path);
// The same from a stream; `name` (e.g. the quoted path) starts each error message.
enum class OctreeFormat { kBinary, kFull };  // .bt, .ot
Octree read_octree(std::istream& in, OctreeFormat format, const std::string& name);
void save_octree(const Octree& tree, const std::string& path);

}  // namespace bvh_collision
