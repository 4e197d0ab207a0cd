// Writes a complete .vxl file (spec §2–§5) in place: the section sizes are planned first, the output
// file is sized and memory-mapped, the caller fills every payload directly in the mapping, and commit()
// adds the checksums, the section table and the header and links the file into place (AtomicOutputFile),
// so a partial file never appears. Writing in place avoids building the sections in memory and copying
// them into the page cache: the output is the largest thing the converter makes.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "format/base/atomic_output.h"
#include "format/streamline_group.h"
#include "format/vxl_group_values.h"
#include "format/vxl_layout.h"
#include "format/vxl_levels.h"
#include "format/vxl_positions.h"

namespace vxl {

// Payload sizes in bytes, one per section, in file order (spec §4). They fix the whole layout.
struct VxlSectionSizes {
  std::uint64_t directions = 0;
  std::optional<std::uint64_t> voxel_directions;  // VDIR; only with order set random (spec §5.10)
  std::uint64_t voxels = 0, vertices = 0, orders = 0, voxlines = 0, streamlines = 0;
  std::uint64_t levels = 0;  // LODS (spec §5.12); 0: absent (one level)
  std::uint64_t provenance = 0;
  std::uint64_t groups = 0;                                // 0: no GRPS section
  std::uint64_t group_values = 0;                          // GDAT (spec §5.13); 0: absent
  std::uint64_t vertex_values = 0, streamline_values = 0;  // VVAL, SVAL (spec §5.11); 0: absent
  std::uint64_t voxel_index = 0;                           // VXIX (spec §5.14); 0: absent
  std::uint64_t streamline_lengths = 0;                    // SLEN (spec §5.15); 0: absent (no streamlines)
  PositionEncoding positions = PositionEncoding::Float32;  // how VERT holds them (spec §5.4); sets the version
};

// The sizes spec §5 gives for the counts in `meta` (stored_order_count, position_encoding and level_count
// included; a VDIR section when order_set is random; a LODS section when level_count > 1; VVAL / SVAL sections holding
// that many value sets, none when 0).
VxlSectionSizes section_sizes(const MetaSection& meta, std::uint64_t order_bytes, std::uint64_t provenance_bytes,
                              std::uint64_t group_bytes, std::uint32_t vertex_value_sets = 0,
                              std::uint32_t streamline_value_sets = 0);

// The section table (offsets and sizes; checksums left zero) and the file size for these payloads: header
// and table first, then each payload in file order at a multiple of 64 (spec §2, §4). VDIR only when
// sizes.voxel_directions is set, GRPS only when sizes.groups > 0. Shared by VxlWriter and VxlStreamWriter, so that both
// lay out a file alike.
struct VxlLayout {
  std::vector<SectionEntry> table;
  std::uint64_t file_size = 0;
};
VxlLayout plan_vxl_layout(const VxlSectionSizes& sizes);

// The bytes of the header and the section table (spec §3, §4), once every checksum in `table` is set.
// The version is the lowest that holds what is written (spec §10): major 2 with packed positions or LODS,
// else 1; minor 4 (2.x) or 5 (1.x) with SLEN, 3 or 4 with ORDB, else the older rules (GDAT, LODS, VVAL/SVAL,
// VDIR).
std::vector<std::uint8_t> vxl_header_bytes(std::span<const SectionEntry> table, std::uint64_t file_size,
                                           PositionEncoding positions);

// The sections the writers fill, in file order (spec §4), and their ids; VDIR, LODS, VXIX, SLEN, GRPS, VVAL, SVAL
// and GDAT are optional. The writers fill VXIX themselves from VXLN and STRM (fill_voxel_index). One list for both
// writers (VxlWriter, VxlStreamWriter), so that they lay out a file alike.
struct VxlSections {
  enum Index : std::size_t {
    kMeta,
    kDirs,
    kVdir,
    kVoxt,
    kLods,
    kVert,
    kOrdb,
    kVxln,
    kStrm,
    kVxix,
    kSlen,
    kProv,
    kGrps,
    kVval,
    kSval,
    kGdat,
    kCount
  };
  static constexpr const char* kIds[kCount] = {"META", "DIRS", "VDIR", "VOXT", "LODS", "VERT", "ORDB", "VXLN",
                                               "STRM", "VXIX", "SLEN", "PROV", "GRPS", "VVAL", "SVAL", "GDAT"};
};

class VxlWriter : public VxlSections {
 public:
  // Creates the output at `path`, sized and mapped for these payloads. Throws vxl::Error (Output).
  VxlWriter(const std::string& path, const VxlSectionSizes& sizes);
  VxlWriter(const VxlWriter&) = delete;
  VxlWriter& operator=(const VxlWriter&) = delete;

  // Writable payloads inside the mapping. They read as zero until written; a payload the caller does
  // not fill completely keeps zeros, and the padding between payloads stays zero (spec §2).
  void set_meta(const MetaSection& meta);  // zeroes the reserved bytes
  std::span<DirectionEntry> directions() { return typed<DirectionEntry>(kDirs); }
  // voxel_count x K entries; empty when there is no VDIR section.
  std::span<DirectionEntry> voxel_directions() { return typed<DirectionEntry>(kVdir); }
  std::span<VoxelEntry> voxels() { return typed<VoxelEntry>(kVoxt); }
  // voxel_count x (level_count - 1) entries; empty when there is no LODS section.
  std::span<LevelEntry> levels() { return typed<LevelEntry>(kLods); }
  // VERT as float32 triples, or as packed words (spec §5.4): the one the sizes were planned for, the
  // other empty.
  std::span<float> float_vertices() {
    return positions_ == PositionEncoding::Float32 ? typed<float>(kVert) : std::span<float>{};
  }
  std::span<std::uint32_t> packed_vertices() {
    return positions_ == PositionEncoding::Packed ? typed<std::uint32_t>(kVert) : std::span<std::uint32_t>{};
  }
  std::span<std::uint8_t> orders() { return payload(kOrdb); }
  std::span<VoxlineEntry> voxlines() { return typed<VoxlineEntry>(kVxln); }
  std::span<std::uint64_t> streamline_first_voxline() { return typed<std::uint64_t>(kStrm); }
  // SLEN: each streamline's length (format/streamline_length.h); empty when the file has no streamlines.
  std::span<float> streamline_lengths() { return typed<float>(kSlen); }
  std::span<std::uint8_t> provenance() { return payload(kProv); }
  std::span<std::uint8_t> groups() { return payload(kGrps); }  // empty when there is no GRPS section
  // The whole mapped file (header and table still unwritten), for prefaulting several payloads at once.
  std::span<std::uint8_t> file() { return file_; }

  // Checksums VERT now, for a caller whose vertices are final before it fills the rest (the unpacker
  // hashes them beside its order building instead of at the end). The vertices must not change
  // afterwards; commit() then leaves VERT's checksum as it is.
  void checksum_vertices_now();
  // Writes the whole 4 KiB blocks of `bytes` (a part of file()) to the disk now, e.g. on another thread while
  // other sections are filled (AtomicOutputFile::write_mapped_now); they must be final.
  void write_now(std::span<const std::uint8_t> bytes);
  // VVAL and SVAL payloads (vxl_value_sets.h: layout_value_sets, finish_value_sets); empty when absent.
  std::span<std::uint8_t> vertex_values() { return payload(kVval); }
  std::span<std::uint8_t> streamline_values() { return payload(kSval); }
  std::span<std::uint8_t> group_values() { return payload(kGdat); }  // empty when there is no GDAT section

  // Fills VXIX from VXLN and STRM (which must be final), checksums every payload (sections spread over
  // up to `threads` threads; 0: all hardware threads), writes the section table and the header, unmaps and
  // links the file into place. The spans above
  // are invalid afterwards. Without commit() the destructor discards the file.
  void commit(unsigned threads = 0);

 private:
  SectionEntry* entry(Index i);  // null for an optional section that is absent
  std::span<std::uint8_t> payload(Index i);
  template <typename T>
  std::span<T> typed(Index i) {
    std::span<std::uint8_t> p = payload(i);
    return {reinterpret_cast<T*>(p.data()), p.size() / sizeof(T)};  // payloads are 64-byte aligned
  }

  AtomicOutputFile out_;
  std::vector<SectionEntry> table_;  // in Index order, optional sections only when present
  PositionEncoding positions_;
  bool vertices_checksummed_ = false;
  std::span<std::uint8_t> file_;
};

// The GRPS payload (spec §5.9), exposed for tests.
std::vector<std::uint8_t> encode_groups(std::span<const StreamlineGroup> groups);

}  // namespace vxl
