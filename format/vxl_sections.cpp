#include "format/vxl_sections.h"

#include <algorithm>
#include <cstring>

#include "format/base/checksum.h"
#include "format/base/parallel.h"
#include "format/voxel_voxlines.h"
#include "format/vxl_value_sets.h"

namespace vxl {

std::vector<std::uint8_t> encode_groups(std::span<const StreamlineGroup> groups) {
  std::vector<std::uint8_t> out;
  auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  std::uint32_t header[2] = {static_cast<std::uint32_t>(groups.size()), 0};
  put(header, sizeof header);
  for (const StreamlineGroup& g : groups) {
    std::uint32_t len = static_cast<std::uint32_t>(g.name.size());
    put(&len, 4);
    put(g.name.data(), g.name.size());
    out.resize(align_up(out.size(), 8), 0);
    std::uint64_t count = g.members.size();
    put(&count, 8);
    put(g.members.data(), g.members.size() * 8);
  }
  return out;
}

VxlSectionSizes section_sizes(const MetaSection& m, std::uint64_t order_bytes, std::uint64_t provenance_bytes,
                              std::uint64_t group_bytes, std::uint32_t vertex_value_sets,
                              std::uint32_t streamline_value_sets) {
  VxlSectionSizes s;
  s.directions = std::uint64_t(m.stored_order_count) * sizeof(DirectionEntry);
  if (m.order_set == static_cast<std::uint32_t>(OrderSet::Random)) s.voxel_directions = m.voxel_count * s.directions;
  s.voxels = std::uint64_t(m.voxel_count) * sizeof(VoxelEntry);
  if (m.level_count > 1) s.levels = std::uint64_t(m.voxel_count) * (m.level_count - 1) * sizeof(LevelEntry);
  s.positions = static_cast<PositionEncoding>(m.position_encoding);
  s.vertices = m.vertex_count * vertex_bytes(s.positions);
  s.orders = order_bytes;
  s.voxlines = m.voxline_count * sizeof(VoxlineEntry);
  s.streamlines = (m.streamline_count + 1) * sizeof(std::uint64_t);
  s.provenance = provenance_bytes;
  s.groups = group_bytes;
  s.voxel_index = voxel_index_bytes(m);
  s.streamline_lengths = m.streamline_count * sizeof(float);
  s.vertex_values = value_sets_bytes(vertex_value_sets, m.vertex_count);
  s.streamline_values = value_sets_bytes(streamline_value_sets, m.streamline_count);
  return s;
}

VxlLayout plan_vxl_layout(const VxlSectionSizes& sizes) {
  struct Planned {
    const char* id;
    std::uint32_t flags;
    std::uint64_t size;
    bool present;
  };
  // VDIR is required: a reader that cannot use per-voxel directions would pick wrong orders, so it must
  // refuse the file (spec §4, §10).
  const Planned planned[] = {
      {"META", kSectionRequired, sizeof(MetaSection), true},
      {"DIRS", kSectionRequired, sizes.directions, true},
      {"VDIR", kSectionRequired, sizes.voxel_directions.value_or(0), sizes.voxel_directions.has_value()},
      {"VOXT", kSectionRequired, sizes.voxels, true},
      // Required: a reader that ignored it would misread the orders of every voxel but the first level's.
      {"LODS", kSectionRequired, sizes.levels, sizes.levels > 0},
      {"VERT", kSectionRequired, sizes.vertices, true},
      // Bit-packed orders (spec §5.5) under a new id: a reader of ORDR's whole-byte entries refuses the file.
      {"ORDB", kSectionRequired, sizes.orders, true},
      {"VXLN", kSectionRequired, sizes.voxlines, true},
      {"STRM", kSectionRequired, sizes.streamlines, true},
      // Optional: a reader without it builds the same lists from VXLN and STRM (spec §5.14).
      {"VXIX", 0, sizes.voxel_index, sizes.voxel_index > 0},
      // Optional: a reader without it measures the streamlines from their points (spec §5.15).
      {"SLEN", 0, sizes.streamline_lengths, sizes.streamline_lengths > 0},
      {"PROV", 0, sizes.provenance, true},
      {"GRPS", 0, sizes.groups, sizes.groups > 0},
      // Optional: a reader that does not know them still draws the picture, in the other colour modes.
      {"VVAL", 0, sizes.vertex_values, sizes.vertex_values > 0},
      {"SVAL", 0, sizes.streamline_values, sizes.streamline_values > 0},
      // Optional (1.3 / 2.2, spec §10): a reader that skips it loses the TRX dpg rows only.
      {"GDAT", 0, sizes.group_values, sizes.group_values > 0},
  };
  std::size_t present = 0;
  for (const Planned& p : planned) present += p.present;

  VxlLayout layout;
  std::uint64_t position = align_up(sizeof(FileHeader) + present * sizeof(SectionEntry), kVxlAlignment);
  for (const Planned& p : planned) {
    if (!p.present) continue;
    SectionEntry e{};
    std::memcpy(e.id, p.id, 4);
    e.flags = p.flags;
    e.offset = position;
    e.size = p.size;
    layout.table.push_back(e);
    position = align_up(position + p.size, kVxlAlignment);
  }
  layout.file_size = position;
  return layout;
}

std::vector<std::uint8_t> vxl_header_bytes(std::span<const SectionEntry> table, std::uint64_t file_size,
                                           PositionEncoding positions) {
  FileHeader h{};
  std::memcpy(h.magic, kVxlMagic.data(), 8);
  const bool packed = positions == PositionEncoding::Packed;
  // The lowest version that holds what is written (spec §10).
  const bool has_levels =
      std::any_of(table.begin(), table.end(), [](const SectionEntry& e) { return std::memcmp(e.id, "LODS", 4) == 0; });
  h.version_major = packed || has_levels ? kVxlVersionMajorPackedPositions : kVxlVersionMajor;
  const bool has_vdir =
      std::any_of(table.begin(), table.end(), [](const SectionEntry& e) { return std::memcmp(e.id, "VDIR", 4) == 0; });
  const bool has_values = std::any_of(table.begin(), table.end(), [](const SectionEntry& e) {
    return std::memcmp(e.id, "VVAL", 4) == 0 || std::memcmp(e.id, "SVAL", 4) == 0;
  });
  const bool has_group_values =
      std::any_of(table.begin(), table.end(), [](const SectionEntry& e) { return std::memcmp(e.id, "GDAT", 4) == 0; });
  const bool has_bit_orders =
      std::any_of(table.begin(), table.end(), [](const SectionEntry& e) { return std::memcmp(e.id, "ORDB", 4) == 0; });
  const bool has_lengths =
      std::any_of(table.begin(), table.end(), [](const SectionEntry& e) { return std::memcmp(e.id, "SLEN", 4) == 0; });
  if (h.version_major == kVxlVersionMajorPackedPositions)
    h.version_minor = has_lengths        ? kVxlVersionMinorLengths2
                      : has_bit_orders   ? kVxlVersionMinorBitOrders2
                      : has_group_values ? kVxlVersionMinorGroupValues2
                      : has_levels       ? kVxlVersionMinorLevels
                                         : 0;
  else
    h.version_minor = has_lengths        ? kVxlVersionMinorLengths1
                      : has_bit_orders   ? kVxlVersionMinorBitOrders1
                      : has_group_values ? kVxlVersionMinorGroupValues1
                      : has_values       ? kVxlVersionMinorValueSets
                      : has_vdir         ? kVxlVersionMinorVoxelDirections
                                         : kVxlVersionMinor;
  h.header_size = sizeof(FileHeader);
  h.file_size = file_size;
  h.section_table_offset = sizeof(FileHeader);
  h.section_count = static_cast<std::uint32_t>(table.size());
  h.flags = 0;
  h.header_checksum = 0;  // covered with this field zero (spec §3)
  std::vector<std::uint8_t> bytes(sizeof h + table.size_bytes());
  std::memcpy(bytes.data(), &h, sizeof h);
  std::memcpy(bytes.data() + sizeof h, table.data(), table.size_bytes());
  h.header_checksum = xxh3_64(bytes.data(), bytes.size());
  std::memcpy(bytes.data(), &h, sizeof h);
  return bytes;
}

}  // namespace vxl
