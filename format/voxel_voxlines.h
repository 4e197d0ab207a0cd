// The inverse of a .vxl's voxline table: for every voxel, the voxlines that pass through it, in streamline
// order. VXLN is in streamline order (spec §5.6), so without this a query about a few voxels must walk
// the whole table to learn which streamlines cross them; with it, the cost of a query is the voxlines of
// the voxels it touches, read in order beside the voxel's vertex block. An entry is 4 bytes: its streamline
// and three flags. Where its points lie in the block follows from the block itself (place_voxel_voxlines:
// the voxline ends of spec §5.4 and the depth of spec §6.5), so the list is read sequentially, never jumping
// back into VXLN or STRM.
//
// Files since 1.4 / 2.3 carry it (VXIX, spec §5.14): the writers fill it from their tables at the end
// (fill_voxel_index), or a streamed conversion as it makes them (VoxelIndexLists), and a reader maps it. For an older
// file the same lists are built once, in memory, when the first query needs them. The viewer's renderers find each
// vertex's streamline through it too.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

// VXIX's payload size for a file of these counts; 0 when it cannot have one (more than 2^29 streamlines).
std::uint64_t voxel_index_bytes(const MetaSection& meta);

// How fill_voxel_index reads the tables and writes the payload: a part at a time, so that a streamed conversion
// fills the index through bounded buffers rather than mappings of whole tables.
struct VoxelIndexIo {
  // VXLN entries [first, first + out.size()) and STRM entries [first, first + out.size()).
  std::function<void(std::uint64_t first, std::span<VoxlineEntry> out)> read_voxlines;
  std::function<void(std::uint64_t first, std::span<std::uint64_t> out)> read_streamline_table;
  // The payload's next bytes: called in payload order, each part following the last.
  std::function<void(std::span<const std::uint8_t> bytes)> write;
  // Sees voxline j before it is counted; throws for one that is damaged. Empty: the voxel must be in range.
  std::function<void(std::uint64_t j, const VoxlineEntry& e)> check;
  // Where the lists go when they are in memory already (voxline_count entries): sorted straight into it in one
  // range, and write() is given the list starts only.
  std::span<IndexedVoxline> in_place;
  // Memory of the caller's to sort the lists in, a range of voxels at a time (at most buffer_bytes of it), when
  // not in place; a voxel whose list alone is larger gets a buffer of its own. Empty: one is allocated.
  std::span<IndexedVoxline> buffer;
};

// Entries of VXLN and of STRM that fill_voxel_index reads at a time (8 MB each).
inline constexpr std::uint64_t kVoxelIndexPartEntries = 1 << 20;

// Fills a VXIX payload (spec §5.14) for a file of these counts from its STRM and VXLN, which must hold together:
// one pass to count each voxel's voxlines, then one per range of voxels whose lists fit `buffer_bytes` (a voxel
// larger than that alone). Each pass reads both tables in order, in parts of about 8 MB.
void fill_voxel_index(std::uint64_t voxel_count, std::uint64_t voxline_count, std::uint64_t streamline_count,
                      const VoxelIndexIo& io, std::uint64_t buffer_bytes);
// The list entry of voxel table entry `e` of streamline `s`, which is its streamline's first and/or last voxline.
inline IndexedVoxline indexed_voxline(std::uint64_t s, const VoxlineEntry& e, bool first, bool last) {
  std::uint32_t word = static_cast<std::uint32_t>(s);
  if (e.count_flags & kVoxlineSyntheticFirst) word |= IndexedVoxline::kSyntheticFirst;
  if (first) word |= IndexedVoxline::kFirstOfStreamline;
  if (last) word |= IndexedVoxline::kLastOfStreamline;
  return {word};
}

// VXIX's payload filled as a writer produces VXLN, streamline by streamline in order, when every voxel's list
// fits in memory at once (4 bytes a voxline): the same lists fill_voxel_index sorts, without reading the tables
// back.
class VoxelIndexLists {
 public:
  // For voxels of these voxline counts (`voxlines[v]`: voxel v's).
  explicit VoxelIndexLists(std::span<const std::uint64_t> voxlines);
  // Streamline s's voxlines, in order. False when one would overflow its voxel's list (other counts).
  bool add_streamline(std::uint64_t s, std::span<const VoxlineEntry> voxlines);
  // Whether every list is full.
  bool complete() const;
  // VXIX's payload: the list starts (voxel count + 1), then the lists.
  std::span<const std::uint64_t> starts() const { return first_; }
  std::span<const IndexedVoxline> lists() const { return {entries_.get(), static_cast<std::size_t>(first_.back())}; }
  // The memory it holds for these counts, with the counts it is made from.
  static std::uint64_t bytes(std::uint64_t voxel_count, std::uint64_t voxline_count) {
    return 24 * voxel_count + 8 + sizeof(IndexedVoxline) * voxline_count;
  }

 private:
  std::vector<std::uint64_t> first_, next_;  // where each voxel's list starts; where its next entry goes
  // Left uninitialised: every entry is written once before complete() holds (its pages are faulted in as the
  // lists fill, not all at once up front).
  std::unique_ptr<IndexedVoxline[]> entries_;
};

// The same from tables in memory into a whole payload of voxel_index_bytes(), in one range.
void fill_voxel_index_payload(std::span<std::uint8_t> payload, std::span<const std::uint64_t> strm,
                              std::span<const VoxlineEntry> voxlines);

class VoxelVoxlines {
 public:
  VoxelVoxlines(VoxelVoxlines&&) noexcept = default;  // a vector's move keeps its buffer: the spans stay valid
  VoxelVoxlines& operator=(VoxelVoxlines&&) noexcept = default;
  VoxelVoxlines(const VoxelVoxlines&) = delete;
  VoxelVoxlines& operator=(const VoxelVoxlines&) = delete;

  // The file's VXIX when it has one (nothing is read), else built from STRM and VXLN. Throws vxl::Error
  // (Input) naming the file and the byte offset when STRM or VXLN do not hold together (spec §5.6, §5.7).
  // std::nullopt for a file without VXIX of more than 2^29 streamlines.
  static std::optional<VoxelVoxlines> of_file(const VxlFile& file);
  // Always built from STRM and VXLN (`voxlines verify` compares it with VXIX).
  static std::optional<VoxelVoxlines> build(const VxlFile& file);

  // The voxlines of voxel `voxel`, in streamline order. From a file's VXIX their streamline numbers are as the
  // file says: place_voxel_voxlines checks them.
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

// One voxline of a voxel's list, placed in the voxel's block.
struct PlacedVoxline {
  std::uint32_t streamline = 0;
  std::uint32_t own = 0;           // its own points (spec §5.6)
  std::uint64_t first_vertex = 0;  // global index of the first of them
  std::uint32_t depth = 0;         // of its streamline (spec §6.5)
  bool synthetic_first = false, first_of_streamline = false, last_of_streamline = false;
  // Its vertices in the block: the own points and, unless it ends its streamline, the connecting vertex.
  std::uint32_t vertices() const { return own + (last_of_streamline ? 0 : 1); }
};

// Places voxel `voxel`'s list in its block, in list order, as spec §5.14 says: a voxline of depth d starts at
// that depth's cursor (spec §5.6, §5.12) and ends at the first voxline end from there (the packed words' end
// bit; with float32 positions, a vertex where no segment of order 0 starts). Only the voxlines of level `level`
// (its streamlines of depth >= level: the block's prefix a renderer draws at that level) are placed, and only
// that prefix is read, so a coarse level costs its own vertices, not the block's. `ends` is scratch. Throws
// vxl::Error (Input) naming the file when the list and the block disagree: a streamline past the count, a
// voxline past its depth's part of the block.
void place_voxel_voxlines(const VxlFile& file, const VoxelVoxlines& index, std::size_t voxel,
                          std::vector<std::uint8_t>& ends, std::vector<PlacedVoxline>& out, std::uint32_t level = 0);

class LevelVoxlines;

// The indexes of several files, each built on first use, once, by whichever thread asks first (the
// window's selection thread or its renderer); the others wait for it.
class VoxelVoxlinesCache {
 public:
  explicit VoxelVoxlinesCache(std::vector<const VxlFile*> files);
  ~VoxelVoxlinesCache();
  // File `file`'s index; null when the file is too large for one. Rethrows the build's error (and builds
  // again at the next call).
  const VoxelVoxlines* of(std::size_t file);
  // File `file`'s voxlines of level `level` placed (format/level_voxlines.h), made on first use, once; as `of`.
  const LevelVoxlines& level(std::size_t file, std::uint32_t level);

 private:
  struct Levels;  // per file: each level's, made once
  std::vector<const VxlFile*> files_;
  std::unique_ptr<std::once_flag[]> once_;
  std::vector<std::optional<VoxelVoxlines>> indexes_;
  std::unique_ptr<Levels[]> levels_;
};

}  // namespace vxl
