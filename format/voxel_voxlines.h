// The inverse of a .vxl's voxline table: for every voxel, the voxlines that pass through it, in streamline
// order. VXLN is in streamline order (spec §5.6), so without this a query about a few voxels must walk
// the whole table to learn which streamlines cross them; with it, the cost of a query is the voxlines of
// the voxels it touches, read in order beside the voxel's vertex block. Each entry carries what a query
// needs of its voxline (streamline, point count, flags, depth), so that a voxel's list is read
// sequentially, never jumping back into VXLN or STRM: 8 bytes a voxline plus 8 a voxel, built once per
// file in one pass over both tables (a counting sort) and reused by every query. The viewer builds it
// when the first region appears, so that a region moved across a large file is re-selected from the
// voxels it touches alone; its renderers find each vertex's streamline through it too.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

struct IndexedVoxline {
  std::uint32_t streamline;
  std::uint32_t bits;  // own point count (bits 0–25), flags (26–28), depth of the streamline (29–31)

  static constexpr std::uint32_t kCountMask = (1u << 26) - 1;
  static constexpr std::uint32_t kSyntheticFirst = 1u << 26;     // its first own point is synthetic (spec §6.3)
  static constexpr std::uint32_t kFirstOfStreamline = 1u << 27;  // the streamline's first voxline
  static constexpr std::uint32_t kLastOfStreamline = 1u << 28;   // no connecting vertex follows it
  std::uint32_t own() const { return bits & kCountMask; }
  std::uint32_t depth() const { return bits >> 29; }
};
static_assert(sizeof(IndexedVoxline) == 8);

class VoxelVoxlines {
 public:
  // Throws vxl::Error (Input) naming the file and the byte offset when STRM or VXLN do not hold together
  // (spec §5.6, §5.7). std::nullopt for a file this index cannot hold: 2^32 streamlines or more, or a
  // voxline of 2^26 points or more.
  static std::optional<VoxelVoxlines> build(const VxlFile& file, unsigned threads = 0);

  // The voxlines of voxel `voxel`, in streamline order.
  std::span<const IndexedVoxline> of_voxel(std::size_t voxel) const {
    return {entries_.data() + first_[voxel], entries_.data() + first_[voxel + 1]};
  }
  std::uint64_t bytes() const { return entries_.size() * sizeof(IndexedVoxline) + first_.size() * 8; }

 private:
  std::vector<std::uint64_t> first_;  // voxel_count + 1: where each voxel's list starts in entries_
  std::vector<IndexedVoxline> entries_;
};

// The indexes of several files, each built on first use, once, by whichever thread asks first (the
// window's selection thread or its renderer); the others wait for it.
class VoxelVoxlinesCache {
 public:
  explicit VoxelVoxlinesCache(std::vector<const VxlFile*> files);
  // File `file`'s index; null when the file is too large for one. Rethrows the build's error (and builds
  // again at the next call).
  const VoxelVoxlines* of(std::size_t file);

 private:
  std::vector<const VxlFile*> files_;
  std::unique_ptr<std::once_flag[]> once_;
  std::vector<std::optional<VoxelVoxlines>> indexes_;
};

}  // namespace vxl
