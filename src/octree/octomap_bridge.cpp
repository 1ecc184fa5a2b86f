#include "bvh_collision/octree/octomap_bridge.h"

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

namespace bvh_collision {
namespace {

double probability(float log_odds) { return 1.0 - 1.0 / (1.0 + std::exp(double(log_odds))); }

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

void to_octomap(const Octree& tree, octomap::OcTree& out) {
  out.clear();
  out.setResolution(tree.resolution());
  const OccupancyModel& m = tree.model();
  out.setProbHit(probability(m.hit));
  out.setProbMiss(probability(m.miss));
  out.setClampingThresMin(probability(m.clamp_min));
  out.setClampingThresMax(probability(m.clamp_max));
  out.setOccupancyThres(probability(m.occupied));
  // Both sides speak the .ot node stream: ours writes it, OctoMap's readData builds its nodes.
  std::stringstream stream;
  tree.write_nodes(stream);
  if (!tree.empty()) out.readData(stream);
}

Octree from_octomap(const octomap::OcTree& tree) {
  OccupancyModel model;
  model.hit = tree.getProbHitLog();
  model.miss = tree.getProbMissLog();
  model.clamp_min = tree.getClampingThresMinLog();
  model.clamp_max = tree.getClampingThresMaxLog();
  model.occupied = tree.getOccupancyThresLog();
  std::stringstream stream;
  tree.writeData(stream);
  return Octree::read_nodes(stream, tree.getResolution(), model);
}

Octree load_octree(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw std::runtime_error("cannot open octree file '" + path + "'");
  if (ends_with(path, ".bt")) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(file)) throw std::runtime_error("'" + path + "' is not a valid OctoMap .bt file");
    return from_octomap(tree);
  }
  if (ends_with(path, ".ot")) {
    std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(file));
    const auto* tree = dynamic_cast<const octomap::OcTree*>(any.get());
    if (!tree) throw std::runtime_error("'" + path + "' is not an OctoMap .ot file holding an OcTree");
    return from_octomap(*tree);
  }
  throw std::runtime_error("octree file '" + path + "' must end in .bt or .ot");
}

void save_octree(const Octree& tree, const std::string& path) {
  const bool binary = ends_with(path, ".bt");
  if (!binary && !ends_with(path, ".ot")) throw std::runtime_error("octree file '" + path + "' must end in .bt or .ot");
  octomap::OcTree out(tree.resolution());
  to_octomap(tree, out);
  std::ofstream file(path, std::ios::binary);
  const bool written = file && (binary ? out.writeBinary(file) : out.write(file));
  file.close();
  if (!written || !file) throw std::runtime_error("cannot write octree file '" + path + "'");
}

}  // namespace bvh_collision
