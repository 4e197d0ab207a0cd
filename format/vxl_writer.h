// Writes a complete .vxl file (spec §2–§5) from in-memory sections: payloads first, then the section
// table and header with their checksum, into an AtomicOutputFile, so a partial file never appears.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "vxl_layout.h"

namespace vxl {

struct GroupContent {
  std::string name;
  std::vector<std::uint64_t> members;  // strictly increasing streamline indices
};

// Everything a .vxl holds. The caller fills `meta` (counts must match the spans; reserved bytes are
// zeroed by the writer) and guarantees the invariants of spec §5 (the reader re-checks them).
struct VxlContent {
  MetaSection meta{};
  std::span<const DirectionEntry> directions;
  std::span<const VoxelEntry> voxels;
  std::span<const float> vertices;  // 3 * vertex_count
  std::span<const std::uint8_t> orders;
  std::span<const VoxlineEntry> voxlines;
  std::span<const std::uint64_t> streamline_first_voxline;  // N + 1
  std::string provenance_json;
  std::span<const GroupContent> groups;  // GRPS is written only when non-empty
};

// Throws vxl::Error (Output) naming the path.
void write_vxl(const std::string& path, const VxlContent& content);

// The GRPS payload (spec §5.9), exposed for tests.
std::vector<std::uint8_t> encode_groups(std::span<const GroupContent> groups);

}  // namespace vxl
