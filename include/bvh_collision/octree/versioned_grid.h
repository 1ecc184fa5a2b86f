// A grid of 32-bit cells written in place by one writer while its earlier versions stay readable,
// each costing memory only for the pages written since it was taken (the distance field's storage:
// a pinned world keeps its field at the price of what changed since, not of a copy).
//
// How. The cells live in one memory file (memfd). The writer writes the file through a shared
// mapping; a version is a private mapping of the same file, which reads the file's pages until a
// page is copied into it. Before the writer changes a page, every version still taken is made to
// copy it (madvise MADV_POPULATE_WRITE: the kernel's copy on write, with no write of ours to
// memory a reader reads), so a version keeps the values it had when taken. Lookups through a
// version are plain loads at the same flat addresses as before: no indirection is added.
//
// Where the kernel offers no memory file or no MADV_POPULATE_WRITE (before Linux 5.14), a version
// is a copy of the cells: the same answers, a whole grid of memory each.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace bvh_collision {

class VersionedGrid;

// One version's cells: read-only, unchanged for as long as it lives.
class GridVersion {
 public:
  GridVersion(const GridVersion&) = delete;
  GridVersion& operator=(const GridVersion&) = delete;
  ~GridVersion();
  const std::uint32_t* cells() const { return cells_; }
  // Memory only this version holds: the pages copied into it before the writer changed them (or
  // its whole copy, without a memory file).
  std::size_t own_bytes() const;
  // Its grid, whose writer may write the next version over this one's file (the writer's side is
  // shared by every version; this one keeps its values whatever is written).
  const std::shared_ptr<VersionedGrid>& grid() const { return grid_; }
  // Which version of its grid this is (the grid's head_version() while nothing was written since).
  std::uint64_t id() const { return id_; }

 private:
  friend class VersionedGrid;
  explicit GridVersion(std::shared_ptr<VersionedGrid> grid) : grid_(std::move(grid)) {}
  std::shared_ptr<VersionedGrid> grid_;  // the file outlives its versions
  std::uint32_t* cells_ = nullptr;       // the private mapping (or the copy)
  std::vector<std::uint32_t> copy_;      // without a memory file
  std::vector<bool> kept_;               // per page: copied into this mapping (guarded by the grid's mutex)
  std::size_t kept_pages_ = 0;
  std::uint64_t id_ = 0;
};

class VersionedGrid {
 public:
  // `cells` cells, each `fill`. Throws std::bad_alloc when even a plain buffer cannot be had.
  static std::shared_ptr<VersionedGrid> create(std::size_t cells, std::uint32_t fill);
  VersionedGrid(const VersionedGrid&) = delete;
  VersionedGrid& operator=(const VersionedGrid&) = delete;
  ~VersionedGrid();

  std::size_t cells() const { return cells_; }
  // The file's memory (the latest values), shared by every version that did not copy a page.
  std::size_t bytes() const { return pages_ * kPageBytes; }
  // Are versions private mappings of one file (false: each a copy)?
  bool shares_pages() const { return file_ >= 0; }

  // ---- The writer (one at a time: `writer()` is its lock) ----
  std::mutex& writer() { return write_mutex_; }
  // The latest values, to read and write in place.
  std::uint32_t* head() { return head_; }
  // Before head()[cell] changes: every version taken keeps its value (its page copied into it).
  void keep_before_write(std::size_t cell) {
    const std::size_t page = cell / kCellsPerPage;
    if (!kept_by_all_[page]) keep_page(page);
  }
  // A version of the values `grid`'s head() holds now; the next writes are kept from it.
  static std::shared_ptr<const GridVersion> take_version(const std::shared_ptr<VersionedGrid>& grid);
  // The version head() matches (the last taken), to tell whether a version may be written over.
  std::uint64_t head_version() const { return head_id_; }
  // Writing over `version` itself, with no new mapping and no page kept for it: allowed when it is
  // the latest version of this grid and `version` is its only holder (no reader can see the
  // writes). The pages written are kept from the other versions alive; end_writing_over() makes
  // the version the values written (it stays this grid's latest). False: not allowed, nothing done.
  bool begin_writing_over(const std::shared_ptr<const GridVersion>& version);
  void end_writing_over();
  // A write that did not finish (a page could not be kept): no version is the file's any more, so
  // none is written over again; the version being written over (if any) is no longer to be read.
  void abandon_head() {
    ++head_id_;
    written_over_ = nullptr;
  }
  // Page copies made into earlier versions since the grid was made (a page kept by two versions
  // counts twice; the writer's count).
  std::size_t kept_pages() const { return kept_pages_total_; }

  static constexpr std::size_t kPageBytes = 4096;
  static constexpr std::size_t kCellsPerPage = kPageBytes / sizeof(std::uint32_t);

 private:
  friend class GridVersion;
  VersionedGrid() = default;
  void keep_page(std::size_t page);
  void forget(GridVersion* version);

  std::size_t cells_ = 0, pages_ = 0;
  int file_ = -1;                       // the memory file, or -1: versions are copies
  std::uint32_t* head_ = nullptr;       // the shared mapping (or plain_)
  std::vector<std::uint32_t> plain_;    // without a memory file
  std::mutex write_mutex_;
  std::uint64_t head_id_ = 0;
  std::vector<bool> kept_by_all_;       // per page: already copied into every version taken
  std::size_t kept_pages_total_ = 0;
  mutable std::mutex versions_mutex_;   // guards versions_ and their kept pages
  std::vector<GridVersion*> versions_;  // the versions alive (a version's destructor removes it)
  const GridVersion* written_over_ = nullptr;  // between begin_ and end_writing_over: kept from no write
};

}  // namespace bvh_collision
