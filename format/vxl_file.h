// Read-only, memory-mapped .vxl file.
//
// open() validates everything the viewer relies on — header, section table, section sizes against the
// counts, every voxel's vertex and order ranges — in O(voxels), never O(points) (spec §7). After a
// successful open, the per-voxel ranges can be used without further checks. Order *entries*, voxlines
// and the streamline table are checked by whoever walks them (walk_streamlines, verify_vxl, the
// renderer's upload), because checking them here would cost O(points).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "format/base/mapped_file.h"
#include "format/streamline_group.h"
#include "format/vxl_group_values.h"
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"
#include "format/vxl_value_sets.h"

namespace vxl {

// One stored order of one voxel: n block-local vertex indices of `bits` bits each, packed from the first byte's
// lowest bit up (little-endian; an ORDR file's 2, 3 or 4 bytes are the same with 16, 24 or 32 bits).
struct OrderView {
  const std::uint8_t* data = nullptr;
  std::uint32_t count = 0;
  std::uint32_t bits = 16;
  std::uint32_t operator[](std::uint32_t i) const {
    const std::uint64_t bit = std::uint64_t(bits) * i;
    const std::uint64_t byte = bit >> 3, size = order_array_bytes(count, bits);
    // Up to 39 bits from `byte` on; never a byte past the array, which may end the section.
    std::uint64_t word = 0;
    std::memcpy(&word, data + byte, std::min<std::uint64_t>(8, size - byte));
    return static_cast<std::uint32_t>((word >> (bit & 7)) & ((std::uint64_t(1) << bits) - 1));
  }
};

// Whether voxel `v`'s tight bounds on axis `c` lie where every writer puts them: within the file's bounds,
// and at most a step (shorter than a voxel edge: longer ones are split at the faces) outside the voxel's
// cell, half an edge more of slack for rounding. A file that moves them is drawn where its lines are not.
bool tight_bounds_in_place(const MetaSection& meta, const VoxelEntry& v, int c);
// The grid as every writer lays it out (spec §6.1): its origin at bounds_min, grid_dims cells of voxel_size
// covering the bounds, one voxel edge of slack for rounding. A file whose bounds, origin, size or
// dimensions were changed would be drawn far from its lines, or not at all. Throws vxl::Error (Input)
// naming `path` and the field's offset from `meta_at`.
void check_grid_geometry(const MetaSection& meta, const std::string& path, std::optional<std::uint64_t> meta_at);
// The order set as spec §5.3 defines them: axis (0) stores 3 directions, axis+diag (1) 7, random (2) any
// 1..64; another set is unknown. Throws vxl::Error (Input) naming `path` and the field's offset.
void check_order_set(const MetaSection& meta, const std::string& path, std::uint64_t meta_at);
// Voxel `index`'s LODS entries (`row`, at `lods_at` in the file): each level a prefix of the finer one's vertices,
// with fewer segments than vertices (spec §5.12). Throws vxl::Error (Input) naming `path` and the entry's offset.
void check_levels_nested(const VoxelEntry& v, std::span<const LevelEntry> row, std::size_t index,
                         const std::string& path, std::uint64_t lods_at);
// What is wrong, for an error message: voxel `index`'s bounds on `c` and its cell's.
std::string misplaced_voxel(const MetaSection& meta, const VoxelEntry& v, std::size_t index, int c);

class VxlFile {
 public:
  // Maps and validates; throws vxl::Error (Input, or Unsupported for a newer major version / unknown
  // required section) naming the file and the byte offset of the problem.
  static VxlFile open(const std::string& path);
  // The same for a file's bytes already in memory (MappedFile::adopt: held, then freed with std::free).
  static VxlFile open(MappedFile bytes);
  // Spec §7 steps 1 and 2 alone, for a reader that fetches a file by byte ranges (vxl_fetch_plan.h): the header
  // and the section table, checked as open() checks them, from the first bytes of a file of `file_size` bytes.
  // Throws vxl::Error as open() does, and when `first` ends before the section table does.
  static std::vector<SectionEntry> read_section_table(const std::string& path, std::span<const std::uint8_t> first,
                                                      std::uint64_t file_size);

  const std::string& path() const { return file_.path(); }
  std::span<const std::uint8_t> bytes() const { return file_.bytes(); }
  // MappedFile::release_resident_pages: a pass through the whole file keeps its resident size bounded.
  void release_resident_pages() const { file_.release_resident_pages(); }
  // MappedFile::will_need: bytes about to be read, asked of the disk at once.
  void will_need(std::uint64_t offset, std::uint64_t size) const { file_.will_need(offset, size); }
  const FileHeader& header() const { return header_; }
  std::span<const SectionEntry> sections() const { return sections_; }
  const SectionEntry* find_section(std::uint32_t id) const;
  // The section's checksum against its bytes (XXH3_64; once per section and file: a later call costs nothing).
  // For a reader that trusts a section's values beyond what open() checks, as a selection trusts VXIX and SLEN.
  // Throws vxl::Error (Input) naming the section and its offset. Nothing when the file lacks the section.
  void check_section_checksum(std::uint32_t id) const;

  const MetaSection& meta() const { return meta_; }
  std::span<const DirectionEntry> directions() const { return directions_; }
  // VDIR (spec §5.10): voxel_count x K entries, empty when the file has one direction set for all voxels.
  std::span<const DirectionEntry> voxel_directions() const { return voxel_directions_; }
  // The K directions voxel `voxel`'s orders are sorted by: its VDIR entries, or DIRS.
  std::span<const DirectionEntry> directions_of(std::size_t voxel) const {
    if (voxel_directions_.empty()) return directions_;
    return voxel_directions_.subspan(voxel * directions_.size(), directions_.size());
  }
  std::span<const VoxelEntry> voxels() const { return voxels_; }
  // Levels of detail (spec §5.12): 1 when the file has no LODS section. Level 0 is all streamlines.
  std::uint32_t level_count() const { return std::max<std::uint32_t>(1, meta_.level_count); }
  // Voxel `voxel`'s LODS entries (level_count - 1 of them: levels 1, 2, ...).
  std::span<const LevelEntry> levels_of(std::size_t voxel) const {
    const std::size_t per_voxel = level_count() - 1;
    return levels_.subspan(voxel * per_voxel, per_voxel);
  }
  // The vertices (a prefix of the block) and segments of level `level` of voxel `voxel`.
  LevelEntry level(std::size_t voxel, std::uint32_t level) const {
    return voxel_level(voxels_[voxel], levels_of(voxel), level);
  }
  // VERT (spec §5.4): float32 triples (3 * vertex_count) or packed words (vertex_count), by encoding; the
  // span of the other encoding is empty. read_vertices decodes either.
  PositionEncoding position_encoding() const { return static_cast<PositionEncoding>(meta_.position_encoding); }
  std::span<const float> float_vertices() const { return float_vertices_; }
  std::span<const std::uint32_t> packed_vertices() const { return packed_vertices_; }
  // Vertices [first, first + count) of voxel `voxel`'s block (global indices), as 3 * count floats.
  void read_vertices(std::size_t voxel, std::uint64_t first, std::uint64_t count, float* xyz) const;
  // Every vertex, decoded (3 * vertex_count floats): for tools and tests; the viewer reads by voxel.
  std::vector<float> all_vertices() const;
  // The orders' payload (ORDB, or ORDR in files before 1.4 / 2.3), how it stores entries and where it starts.
  std::span<const std::uint8_t> order_bytes() const { return orders_; }
  OrderPacking order_packing() const { return order_packing_; }
  std::uint64_t orders_offset() const;
  // Stored order k of voxel `voxel` at level `level` (0: full detail).
  OrderView order(std::size_t voxel, std::uint32_t k, std::uint32_t level = 0) const;
  std::span<const VoxlineEntry> voxlines() const { return voxlines_; }
  std::span<const std::uint64_t> streamline_first_voxline() const { return strm_; }
  // open() leaves STRM and VXLN unread (it stays O(voxels)): whoever walks them checks what it reads with
  // these, so that a damaged table gets the same error, naming the same byte, whoever finds it.
  // The whole streamline table: starts at voxline 0, never decreases, ends at the voxline count.
  void check_streamline_table() const;
  // Streamline s's run of voxlines, for a walker that reads some streamlines only.
  void check_streamline_run(std::uint64_t s) const {
    if ((s == 0 && strm_[0] != 0) || strm_[s + 1] < strm_[s] || strm_[s + 1] > voxlines_.size())
      fail_streamline_table(s == 0 && strm_[0] != 0 ? 0 : s + 1);
  }
  // Voxline j: its voxel exists and it has points.
  void check_voxline(std::uint64_t j) const {
    const VoxlineEntry& e = voxlines_[j];
    if (e.voxel >= voxels_.size() || (e.count_flags & kVoxlineCountMask) == 0) fail_voxline(j);
  }
  // VXIX (spec §5.14), empty when the file has none: per voxel, where its list of voxlines starts
  // (voxel_count + 1 entries; open() has checked that they rise to the voxline count), then the lists'
  // entries (format/voxel_voxlines.h reads them; their contents are checked by whoever uses them).
  std::span<const std::uint64_t> voxel_index_first() const { return voxel_index_first_; }
  std::span<const IndexedVoxline> voxel_index_entries() const { return voxel_index_entries_; }
  // SLEN (spec §5.15), empty when the file has none: each streamline's length in mm (open() has checked the
  // size only: a user checks the values it reads, as format/streamline_length.h's stored_length does).
  std::span<const float> streamline_lengths() const { return streamline_lengths_; }
  std::string_view provenance_json() const { return provenance_; }
  // Where PROV starts in the file (0 when the file has none).
  std::uint64_t provenance_offset() const;
  // Parses GRPS (empty when absent; open() has checked its structure and names); throws vxl::Error when a
  // member is out of range or out of order.
  std::vector<StreamlineGroup> groups() const;
  // GDAT: values per group (TRX dpg), checked by open() against the groups; empty when absent.
  const std::vector<GroupValues>& group_values() const { return group_values_; }
  // VVAL: per-vertex value sets (vertex_count values each); SVAL: per-streamline ones. Empty when absent.
  const ValueSets& vertex_values() const { return vertex_values_; }
  const ValueSets& streamline_values() const { return streamline_values_; }

 private:
  explicit VxlFile(MappedFile file) : file_(std::move(file)), file_size_(file_.size()) {}
  void validate();
  [[noreturn]] void fail_streamline_table(std::uint64_t entry) const;
  [[noreturn]] void fail_voxline(std::uint64_t j) const;
  void validate_header();
  void validate_section_table();
  void validate_meta_and_sizes();
  void validate_meta_fields(std::uint64_t meta_at) const;
  void validate_voxel_table();
  void validate_voxel_index(std::span<const std::uint8_t> vxix);
  // Walks GRPS (spec §5.9) checking its structure and names (valid UTF-8, no NUL) but not the members:
  // O(groups). `visit` gets each group's name and where its `count` members start in the section.
  void walk_groups(
      const std::function<void(std::string_view name, std::uint64_t members_at, std::uint64_t count)>& visit) const;

  MappedFile file_;
  std::uint64_t file_size_ = 0;  // file_.size(), or more where file_ holds only its first bytes (read_section_table)
  // Per section table entry: 1 once check_section_checksum has found it whole.
  std::unique_ptr<std::atomic<std::uint8_t>[]> checksum_checked_;
  FileHeader header_{};
  std::span<const SectionEntry> sections_;
  MetaSection meta_{};
  std::span<const DirectionEntry> directions_;
  std::span<const DirectionEntry> voxel_directions_;
  std::span<const VoxelEntry> voxels_;
  std::span<const LevelEntry> levels_;
  std::span<const float> float_vertices_;
  std::span<const std::uint32_t> packed_vertices_;
  std::span<const std::uint8_t> orders_;
  OrderPacking order_packing_ = OrderPacking::Bits;
  std::span<const VoxlineEntry> voxlines_;
  std::span<const std::uint64_t> voxel_index_first_;
  std::span<const IndexedVoxline> voxel_index_entries_;
  std::span<const float> streamline_lengths_;
  std::span<const std::uint64_t> strm_;
  std::string_view provenance_;
  std::span<const std::uint8_t> groups_;
  ValueSets vertex_values_, streamline_values_;
  std::vector<GroupValues> group_values_;
};

std::string section_name(std::uint32_t id);

}  // namespace vxl
