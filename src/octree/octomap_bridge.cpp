#include "bvh_collision/octree/octomap_bridge.h"

#include <octomap/AbstractOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <optional>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <vector>

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
  if (ends_with(path, ".bt")) return read_octree(file, OctreeFormat::kBinary, "'" + path + "'");
  if (ends_with(path, ".ot")) return read_octree(file, OctreeFormat::kFull, "'" + path + "'");
  throw std::runtime_error("octree file '" + path + "' must end in .bt or .ot");
}

namespace {

// The node count the header declares ("size N" before the "data" line), if it has one.
std::optional<unsigned long long> declared_size(const std::string& bytes) {
  std::istringstream header(bytes.substr(0, std::min<std::size_t>(bytes.size(), 4096)));
  std::string line;
  while (std::getline(header, line) && line != "data") {
    if (line.rfind("size ", 0) != 0) continue;
    const std::string digits = line.substr(5);
    if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 18) return std::nullopt;
    return std::stoull(digits);
  }
  return std::nullopt;
}

// OctoMap reads a truncated data section without a word (the nodes it could not read keep
// whatever the stream left) and skips the data when the header says size 0 (found by the
// octree_file fuzz seeds): what it read must be whole, all of the file, and the size declared.
void check_read(std::istream& stream, std::size_t nodes, const std::optional<unsigned long long>& declared,
                const std::string& name) {
  if (stream.fail()) throw std::runtime_error(name + ": the data section ends before its last node");
  if (stream.peek() != std::char_traits<char>::eof()) throw std::runtime_error(name + ": there is data after the last node");
  if (!declared || *declared != nodes) {
    throw std::runtime_error(name + ": the header declares " + (declared ? std::to_string(*declared) : "no") +
                             " nodes, the data holds " + std::to_string(nodes));
  }
}

// Where OctoMap's readers start on the data: past the first line, the header's tokens up to
// "data", and the rest of that line. npos without a "data" token.
std::size_t data_start(const std::string& bytes) {
  std::istringstream in(bytes);
  std::string line, token;
  std::getline(in, line);
  while (in >> token) {
    if (token != "data") continue;
    for (int c = in.get(); in.good() && c != '\n'; c = in.get()) {
    }
    return in.good() ? static_cast<std::size_t>(in.tellg()) : bytes.size();
  }
  return std::string::npos;
}

// OctoMap's node readers recurse once per level with no bound (a .bt of nested inner nodes took
// the process down with a stack overflow: found by the octree_file fuzz target). The structure is
// walked here first, without recursion: no node deeper than the tree's 16 levels, none cut off.
void check_structure(const std::string& bytes, OctreeFormat format, const std::string& name) {
  // Without its header line OctoMap's .bt reader falls back to its headerless legacy format and
  // reads on past the end of the file (out of memory, or a stack overflow: found by the fuzz
  // target): only files that start with their format's header line and have a data line are read.
  const std::string header = format == OctreeFormat::kBinary ? "# Octomap OcTree binary file" : "# Octomap OcTree file";
  std::size_t at = bytes.compare(0, header.size(), header) == 0 ? data_start(bytes) : std::string::npos;
  if (at == std::string::npos) {
    throw std::runtime_error(name + " does not start with '" + header + "' and a header ending in a 'data' line");
  }
  const std::size_t record = format == OctreeFormat::kBinary ? 2 : 5;  // .bt: two bytes; .ot: float and mask
  // An empty tree ("size 0", as OctoMap and save_octree write it) has no node record at all: its
  // data section must be empty too (check_read sees to that).
  if (const auto declared = declared_size(bytes); declared && *declared == 0) return;
  std::vector<int> pending = {0};  // depths of the node records still to read, last first
  while (!pending.empty()) {
    const int depth = pending.back();
    pending.pop_back();
    if (at + record > bytes.size()) throw std::runtime_error(name + ": the data section ends before its last node");
    int children = 0;
    if (format == OctreeFormat::kBinary) {  // a child with both bits set is an inner node: a record follows
      for (std::size_t b = 0; b < 2; ++b) {
        const auto bits = static_cast<unsigned char>(bytes[at + b]);
        for (int i = 0; i < 4; ++i) children += ((bits >> (2 * i)) & 3) == 3;
      }
    } else {
      for (unsigned char mask = static_cast<unsigned char>(bytes[at + 4]); mask != 0; mask &= mask - 1) ++children;
    }
    at += record;
    if (children > 0 && depth + 1 > (format == OctreeFormat::kBinary ? kOctreeDepth - 1 : kOctreeDepth)) {
      throw std::runtime_error(name + ": a node lies deeper than the tree's " + std::to_string(kOctreeDepth) + " levels");
    }
    pending.insert(pending.end(), children, depth + 1);
  }
}

}  // namespace

Octree read_octree(std::istream& in, OctreeFormat format, const std::string& name) {
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  check_structure(bytes, format, name);
  std::istringstream stream(bytes);
  if (format == OctreeFormat::kBinary) {
    octomap::OcTree tree(0.1);
    if (!tree.readBinary(stream)) throw std::runtime_error(name + " is not a valid OctoMap .bt file");
    check_read(stream, tree.size(), declared_size(bytes), name);
    return from_octomap(tree);
  }
  std::unique_ptr<octomap::AbstractOcTree> any(octomap::AbstractOcTree::read(stream));
  const auto* tree = dynamic_cast<const octomap::OcTree*>(any.get());
  if (!tree) throw std::runtime_error(name + " is not an OctoMap .ot file holding an OcTree");
  check_read(stream, tree->size(), declared_size(bytes), name);
  return from_octomap(*tree);
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
