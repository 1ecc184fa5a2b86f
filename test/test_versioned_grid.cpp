// VersionedGrid (octree/versioned_grid.h): versions keep their values while the head is written,
// and hold memory only for the pages written since; the kernel's own count of each version's
// private pages (/proc/self/smaps) is the oracle for the memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "bvh_collision/octree/versioned_grid.h"

namespace bvh_collision {
namespace {

// The kernel's "Anonymous" kilobytes (pages copied into a private file mapping) of the mapping
// that starts at `address`; -1 when no mapping starts there.
long anonymous_kb(const void* address) {
  std::ifstream smaps("/proc/self/smaps");
  std::ostringstream start;
  start << std::hex << reinterpret_cast<std::uintptr_t>(address) << "-";
  bool inside = false;
  for (std::string line; std::getline(smaps, line);) {
    // A mapping's first line starts "<start>-<end> perms ...": its first word is hex digits and a dash.
    const std::string word = line.substr(0, line.find(' '));
    const bool header = word.find('-') != std::string::npos &&
                        std::all_of(word.begin(), word.end(), [](char c) { return c == '-' || std::isxdigit(c); });
    if (header) {
      inside = line.rfind(start.str(), 0) == 0;
      continue;
    }
    if (inside && line.rfind("Anonymous:", 0) == 0) return std::stol(line.substr(10));
  }
  return -1;
}

void write(VersionedGrid& grid, std::size_t cell, std::uint32_t value) {
  grid.keep_before_write(cell);
  grid.head()[cell] = value;
}

TEST(VersionedGrid, EachVersionKeepsItsValuesAndHoldsOnlyThePagesWrittenSince) {
  const std::size_t cells = 300000;  // 293 pages
  const std::shared_ptr<VersionedGrid> grid = VersionedGrid::create(cells, 7);
  for (std::size_t i = 0; i < cells; ++i) grid->head()[i] = static_cast<std::uint32_t>(i);
  std::vector<std::vector<std::uint32_t>> expected{std::vector<std::uint32_t>(grid->head(), grid->head() + cells)};
  std::vector<std::shared_ptr<const GridVersion>> versions{VersionedGrid::take_version(grid)};
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<std::size_t> any(0, cells - 1);
  std::vector<std::size_t> pages_written(1, 0);
  for (int round = 1; round <= 4; ++round) {
    std::vector<bool> page(grid->bytes() / VersionedGrid::kPageBytes, false);
    for (int k = 0; k < 40; ++k) {  // a few runs of cells, as a cloud's blocks are
      const std::size_t first = any(rng);
      for (std::size_t i = first; i < std::min(cells, first + 200); ++i) {
        write(*grid, i, static_cast<std::uint32_t>(1000000 * round + i));
        page[i / VersionedGrid::kCellsPerPage] = true;
      }
    }
    pages_written.push_back(static_cast<std::size_t>(std::count(page.begin(), page.end(), true)));
    expected.emplace_back(grid->head(), grid->head() + cells);
    versions.push_back(VersionedGrid::take_version(grid));
  }
  for (std::size_t v = 0; v < versions.size(); ++v) {
    EXPECT_TRUE(std::equal(expected[v].begin(), expected[v].end(), versions[v]->cells())) << "version " << v;
  }
  if (!grid->shares_pages()) GTEST_SKIP() << "no memory file here: every version is a copy (checked above)";
  // The newest holds nothing of its own; each older one the pages written after it (a page written
  // in several rounds once), never a whole grid.
  EXPECT_EQ(versions.back()->own_bytes(), 0u);
  for (std::size_t v = 0; v + 1 < versions.size(); ++v) {
    const std::size_t own = versions[v]->own_bytes();
    EXPECT_GE(own, pages_written[v + 1] * VersionedGrid::kPageBytes) << "version " << v;
    EXPECT_LT(own * 2, grid->bytes()) << "version " << v;
    // The kernel's count of the pages copied into this version's mapping equals ours.
    EXPECT_EQ(anonymous_kb(versions[v]->cells()), static_cast<long>(own / 1024)) << "version " << v;
  }
  EXPECT_EQ(anonymous_kb(versions.back()->cells()), 0);
  // A version let go gives its pages back and is kept from no more.
  const std::size_t kept = grid->kept_pages();
  versions.erase(versions.begin(), versions.end() - 1);
  write(*grid, 0, 5);
  EXPECT_EQ(grid->kept_pages(), kept + 1);  // into the one version left
  EXPECT_EQ(versions.back()->own_bytes(), VersionedGrid::kPageBytes);
  EXPECT_EQ(versions.back()->cells()[0], expected.back()[0]);
}

// Readers on other threads read a version while the writer writes the pages it maps: every value
// they read is the version's (under the sanitizers, also where a read met a write).
TEST(VersionedGrid, ReadersOfAVersionNeverSeeTheWriter) {
  const std::size_t cells = 200000;
  const std::shared_ptr<VersionedGrid> grid = VersionedGrid::create(cells, 1);
  const std::shared_ptr<const GridVersion> version = VersionedGrid::take_version(grid);
  std::atomic<bool> wrong{false};
  std::vector<std::thread> readers;
  for (int t = 0; t < 2; ++t) {
    readers.emplace_back([&] {
      for (int pass = 0; pass < 50; ++pass) {
        for (std::size_t i = 0; i < cells; i += 97) {
          if (version->cells()[i] != 1) wrong = true;
        }
      }
    });
  }
  for (std::size_t i = 0; i < cells; i += 13) write(*grid, i, 2);
  for (auto& r : readers) r.join();
  EXPECT_FALSE(wrong);
  EXPECT_EQ(grid->head()[13], 2u);
  EXPECT_EQ(version->cells()[13], 1u);
}

}  // namespace
}  // namespace bvh_collision
