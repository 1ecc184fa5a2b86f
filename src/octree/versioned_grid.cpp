// VersionedGrid (octree/versioned_grid.h): the memory file, its versions, the pages kept.
#include "bvh_collision/octree/versioned_grid.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <new>

namespace bvh_collision {
namespace {

// Does this kernel make a private mapping of a memory file copy a page on request? (Linux 5.14.)
bool kernel_keeps_pages() {
  static const bool supported = [] {
    const int fd = memfd_create("bvh_collision_probe", MFD_CLOEXEC);
    if (fd < 0) return false;
    bool ok = false;
    if (ftruncate(fd, VersionedGrid::kPageBytes) == 0) {
      void* p = mmap(nullptr, VersionedGrid::kPageBytes, PROT_READ | PROT_WRITE, MAP_PRIVATE, fd, 0);
      if (p != MAP_FAILED) {
        ok = madvise(p, VersionedGrid::kPageBytes, MADV_POPULATE_WRITE) == 0;
        munmap(p, VersionedGrid::kPageBytes);
      }
    }
    close(fd);
    return ok;
  }();
  return supported;
}

}  // namespace

std::shared_ptr<VersionedGrid> VersionedGrid::create(std::size_t cells, std::uint32_t fill) {
  std::shared_ptr<VersionedGrid> grid(new VersionedGrid());
  grid->cells_ = cells;
  grid->pages_ = std::max<std::size_t>(1, (cells + kCellsPerPage - 1) / kCellsPerPage);
  if (kernel_keeps_pages()) {
    const int fd = memfd_create("bvh_collision_grid", MFD_CLOEXEC);
    if (fd >= 0 && ftruncate(fd, static_cast<off_t>(grid->bytes())) == 0) {
      void* p = mmap(nullptr, grid->bytes(), PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
      if (p != MAP_FAILED) {
        grid->file_ = fd;
        grid->head_ = static_cast<std::uint32_t*>(p);
      }
    }
    if (grid->file_ < 0 && fd >= 0) close(fd);
  }
  if (grid->file_ < 0) {
    grid->plain_.resize(cells);
    grid->head_ = grid->plain_.data();
  }
  std::fill_n(grid->head_, cells, fill);
  // Without a file every version is a copy: nothing needs keeping.
  grid->kept_by_all_.assign(grid->pages_, grid->file_ < 0);
  return grid;
}

VersionedGrid::~VersionedGrid() {
  if (file_ >= 0) {
    munmap(head_, bytes());
    close(file_);
  }
}

std::shared_ptr<const GridVersion> VersionedGrid::take_version(const std::shared_ptr<VersionedGrid>& grid) {
  std::shared_ptr<GridVersion> v(new GridVersion(grid));
  const std::size_t bytes = grid->bytes();
  if (grid->file_ >= 0) {
    void* p = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE, grid->file_, 0);
    if (p != MAP_FAILED) {
      v->cells_ = static_cast<std::uint32_t*>(p);
      madvise(p, bytes, MADV_POPULATE_READ);  // map every page now, not at a query's first reads
    }
  }
  if (v->cells_ == nullptr) {  // no file (or no mapping left): a copy
    v->copy_.assign(grid->head_, grid->head_ + grid->cells_);
    v->cells_ = v->copy_.data();
  }
  v->kept_.assign(grid->pages_, !v->copy_.empty() || grid->cells_ == 0);
  v->id_ = ++grid->head_id_;
  {
    std::lock_guard<std::mutex> lock(grid->versions_mutex_);
    grid->versions_.push_back(v.get());
  }
  // The new version reads the file: every page written from now on is kept from it.
  if (grid->file_ >= 0 && v->copy_.empty()) std::fill(grid->kept_by_all_.begin(), grid->kept_by_all_.end(), false);
  return v;
}

void VersionedGrid::keep_page(std::size_t page) {
  std::lock_guard<std::mutex> lock(versions_mutex_);
  for (GridVersion* v : versions_) {
    if (v->kept_[page] || v == written_over_) continue;
    // The kernel copies the file's page into the version's mapping (nothing of ours writes it).
    if (madvise(v->cells_ + page * kCellsPerPage, kPageBytes, MADV_POPULATE_WRITE) != 0) throw std::bad_alloc();
    v->kept_[page] = true;
    ++v->kept_pages_;
    ++kept_pages_total_;  // (a page copied: into one version)
  }
  kept_by_all_[page] = true;
}

bool VersionedGrid::begin_writing_over(const std::shared_ptr<const GridVersion>& version) {
  if (!version || version->grid_.get() != this || version->id_ != head_id_ || version.use_count() != 1 ||
      !version->copy_.empty() || file_ < 0) {
    return false;
  }
  written_over_ = version.get();
  return true;
}

void VersionedGrid::end_writing_over() {
  // (The version is this grid's: its id is the grid's to give; no reader holds it.)
  const_cast<GridVersion*>(written_over_)->id_ = ++head_id_;
  written_over_ = nullptr;
  std::fill(kept_by_all_.begin(), kept_by_all_.end(), false);
}

void VersionedGrid::forget(GridVersion* version) {
  std::lock_guard<std::mutex> lock(versions_mutex_);
  versions_.erase(std::remove(versions_.begin(), versions_.end(), version), versions_.end());
}

GridVersion::~GridVersion() {
  grid_->forget(this);
  if (copy_.empty() && cells_ != nullptr) munmap(cells_, grid_->bytes());
}

std::size_t GridVersion::own_bytes() const {
  if (!copy_.empty()) return copy_.size() * sizeof(std::uint32_t);
  std::lock_guard<std::mutex> lock(grid_->versions_mutex_);
  return kept_pages_ * VersionedGrid::kPageBytes;
}

}  // namespace bvh_collision
