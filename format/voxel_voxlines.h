// The inverse of a .vxl's voxline table: for every voxel, the voxlines that pass through it, in streamline
// order. VXLN is in streamline order (spec §5.6), so without this a query about a few voxels must walk
// the whole table to learn which streamlines cross them; with it, the cost of a query is the voxlines of
// the voxels it touches, read in order beside the voxel's vertex block. Each entry carries what a query
// needs of its voxline (streamline, point count, flags, depth), so that a voxel's list is read
// sequentially, never jumping back into VXLN or STRM: 8 bytes a voxline plus 8 a voxel.
//
// Files since 1.4 / 2.3 carry it (VXIX, spec §5.14): the writers fill it from their tables at the end
// (fill_voxel_index), and a reader maps it. For an older file it is built once, in one pass over VXLN and
// STRM (a counting sort), when the first query needs it. The viewer's renderers find each vertex's
// streamline through it too.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

// VXIX's payload size for a file of these counts; 0 when it cannot have one (2^32 streamlines or more).
std::uint64_t voxel_index_bytes(const MetaSection& meta);

// Fills a VXIX payload (`first`: voxel_count + 1 list starts, then `entries`: one per voxline) from a
// writer's own tables, STRM and VXLN, with `level_count` levels of detail. Throws vxl::Error (Unsupported,
// naming `path`) for a voxline of 2^26 own points or more, which an entry cannot count.
void fill_voxel_index(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
                      std::uint32_t level_count, std::span<std::uint64_t> first, std::span<IndexedVoxline> entries,
                      unsigned threads, const std::string& path);
// The same into a whole VXIX payload of voxel_index_bytes() (8-byte aligned), as the writers hold it.
void fill_voxel_index_payload(std::span<std::uint8_t> payload, std::span<const std::uint64_t> strm,
                              std::span<const VoxlineEntry> voxlines, std::uint32_t level_count, unsigned threads,
                              const std::string& path);

class VoxelVoxlines {
 public:
  VoxelVoxlines(VoxelVoxlines&&) noexcept = default;  // a vector's move keeps its buffer: the spans stay valid
  VoxelVoxlines& operator=(VoxelVoxlines&&) noexcept = default;
  VoxelVoxlines(const VoxelVoxlines&) = delete;
  VoxelVoxlines& operator=(const VoxelVoxlines&) = delete;
  // The file's VXIX when it has one (nothing is read), else built from STRM and VXLN. Throws vxl::Error
  // (Input) naming the file and the byte offset when STRM or VXLN do not hold together (spec §5.6, §5.7).
  // std::nullopt for a file without VXIX that this index cannot hold: 2^32 streamlines or more, or a
  // voxline of 2^26 points or more.
  static std::optional<VoxelVoxlines> of_file(const VxlFile& file, unsigned threads = 0);
  // Always built from STRM and VXLN (`voxlines verify` compares it with VXIX).
  static std::optional<VoxelVoxlines> build(const VxlFile& file, unsigned threads = 0);

  // The voxlines of voxel `voxel`, in streamline order. From a file's VXIX their streamline numbers and counts
  // are as the file says: a user checks the numbers against the streamline count and the counts against the
  // voxel's block.
  std::span<const IndexedVoxline> of_voxel(std::size_t voxel) const {
    return {entries_.data() + first_[voxel], entries_.data() + first_[voxel + 1]};
  }
  // The memory it holds: 0 when it is the file's.
  std::uint64_t bytes() const { return owned_entries_.size() * sizeof(IndexedVoxline) + owned_first_.size() * 8; }
  bool from_file() const { return owned_first_.empty(); }

 private:
  VoxelVoxlines() = default;
  std::span<const std::uint64_t> first_;  // voxel_count + 1: where each voxel's list starts in entries_
  std::span<const IndexedVoxline> entries_;
  std::vector<std::uint64_t> owned_first_;  // when built
  std::vector<IndexedVoxline> owned_entries_;
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
