// A .vxl file's layout (spec §2–§5): the payload sizes the counts give, where each section goes, the header and
// section table's bytes, and the GRPS payload. VxlStreamWriter (vxl_stream_writer.h) writes files by it.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

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
// sizes.voxel_directions is set, GRPS only when sizes.groups > 0.
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
// and GDAT are optional. VxlStreamWriter fills VXIX itself from VXLN and STRM where asked (append_voxel_index).
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

// The GRPS payload (spec §5.9), exposed for tests.
std::vector<std::uint8_t> encode_groups(std::span<const StreamlineGroup> groups);

}  // namespace vxl
