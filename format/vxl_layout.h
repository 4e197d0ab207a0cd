// On-disk structures of the .vxl format, versions 1.0 to 2.4 (spec/vxl-format.md is the reference; section
// numbers below point into it). All little-endian; every struct's layout is pinned by static_asserts so
// a file can be used in place after mmap.
#pragma once

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

namespace vxl {

// Whether n bytes are all zero, as reserved fields and padding must be.
inline bool all_zero(const std::uint8_t* p, std::uint64_t n) {
  for (std::uint64_t i = 0; i < n; ++i)
    if (p[i] != 0) return false;
  return true;
}

static_assert(std::endian::native == std::endian::little, "the .vxl format is read in place: little-endian hosts only");

inline constexpr std::array<std::uint8_t, 8> kVxlMagic = {0x89, 'V', 'X', 'L', '\r', '\n', 0x1A, '\n'};
inline constexpr std::uint16_t kVxlVersionMajor = 1;
inline constexpr std::uint16_t kVxlVersionMinor = 0;
// Files with per-voxel directions (VDIR, spec §5.10) are version 1.1; files with value sets (VVAL, SVAL,
// spec §5.11) are 1.2; all others stay 1.0; files with packed positions (spec §5.4) are 2.0 (spec §10).
inline constexpr std::uint16_t kVxlVersionMinorVoxelDirections = 1;
inline constexpr std::uint16_t kVxlVersionMinorValueSets = 2;
inline constexpr std::uint16_t kVxlVersionMajorPackedPositions = 2;
// Files with levels of detail (LODS, spec §5.12) are 2.1, with either position encoding.
inline constexpr std::uint16_t kVxlVersionMinorLevels = 1;
// Files with values per group (GDAT, spec §5.13) are 1.3 when they would otherwise be 1.x, 2.2 when 2.x.
inline constexpr std::uint16_t kVxlVersionMinorGroupValues1 = 3;
inline constexpr std::uint16_t kVxlVersionMinorGroupValues2 = 2;
// Files whose orders are bit-packed (ORDB instead of ORDR, spec §5.5), with or without the voxel index
// (VXIX, spec §5.14), are 1.4 when they would otherwise be 1.x, 2.3 when 2.x.
inline constexpr std::uint16_t kVxlVersionMinorBitOrders1 = 4;
inline constexpr std::uint16_t kVxlVersionMinorBitOrders2 = 3;
// Files with per-streamline lengths (SLEN, spec §5.15) are 1.5 when they would otherwise be 1.x, 2.4 when 2.x.
inline constexpr std::uint16_t kVxlVersionMinorLengths1 = 5;
inline constexpr std::uint16_t kVxlVersionMinorLengths2 = 4;
inline constexpr std::uint64_t kVxlAlignment = 64;
inline constexpr std::uint32_t kVxlMaxSections = 64;
inline constexpr std::uint32_t kVxlMaxStoredOrders = 64;
inline constexpr std::uint32_t kU16OrderMaxVertices = 65536;     // u16 entries when vertex_count <= this
inline constexpr std::uint32_t kU24OrderMaxVertices = 1u << 24;  // else u24 entries when <= this, else u32

// §3
struct FileHeader {
  std::uint8_t magic[8];
  std::uint16_t version_major;
  std::uint16_t version_minor;
  std::uint32_t header_size;
  std::uint64_t file_size;
  std::uint64_t section_table_offset;
  std::uint32_t section_count;
  std::uint32_t flags;
  std::uint64_t header_checksum;
  std::uint8_t reserved[16];
};
static_assert(sizeof(FileHeader) == 64);
static_assert(offsetof(FileHeader, header_checksum) == 40);

// §4
struct SectionEntry {
  char id[4];
  std::uint32_t flags;
  std::uint64_t offset;
  std::uint64_t size;
  std::uint64_t checksum;
};
static_assert(sizeof(SectionEntry) == 32);
inline constexpr std::uint32_t kSectionRequired = 1u;

constexpr std::uint32_t section_id(const char (&s)[5]) {
  return std::uint32_t(std::uint8_t(s[0])) | std::uint32_t(std::uint8_t(s[1])) << 8 |
         std::uint32_t(std::uint8_t(s[2])) << 16 | std::uint32_t(std::uint8_t(s[3])) << 24;
}

// §5.1
enum class OrderSet : std::uint32_t { Axis = 0, AxisDiag = 1, Random = 2 };

struct MetaSection {
  std::uint64_t streamline_count;
  std::uint64_t point_count;
  std::uint64_t vertex_count;
  std::uint64_t segment_count;
  std::uint64_t voxline_count;
  std::uint64_t synthetic_point_count;
  std::uint32_t voxel_count;
  std::uint32_t stored_order_count;
  double voxel_size;
  double grid_origin[3];
  std::int32_t grid_dims[3];
  std::uint32_t order_set;
  double bounds_min[3];
  double bounds_max[3];
  std::uint32_t position_encoding;  // PositionEncoding (vxl_positions.h); 0 in every 1.x file
  std::uint32_t level_count;        // levels of detail (vxl_levels.h), since 2.1; 0 before (one level)
  std::uint8_t reserved[96];
};
static_assert(sizeof(MetaSection) == 256);
static_assert(offsetof(MetaSection, voxel_size) == 56);
static_assert(offsetof(MetaSection, grid_dims) == 88);
static_assert(offsetof(MetaSection, order_set) == 100);
static_assert(offsetof(MetaSection, bounds_min) == 104);
static_assert(offsetof(MetaSection, position_encoding) == 152);
static_assert(offsetof(MetaSection, level_count) == 156);
static_assert(offsetof(MetaSection, reserved) == 160);

// §5.2
struct DirectionEntry {
  float xyz[3];
  std::uint32_t reserved;
};
static_assert(sizeof(DirectionEntry) == 16);

// §5.3
struct VoxelEntry {
  std::int32_t coord[3];
  std::uint32_t flags;  // bits 0-1: order entry width code (0: u16, 1: u24, 2: u32)
  float tight_min[3];
  float tight_max[3];
  std::uint64_t vertex_first;
  std::uint32_t vertex_count;
  std::uint32_t segment_count;
  std::uint64_t order_offset;
};
static_assert(sizeof(VoxelEntry) == 64);
static_assert(offsetof(VoxelEntry, vertex_first) == 40);
inline constexpr std::uint32_t kVoxelOrderWidthMask = 3u;

// Bytes per order entry of an ORDR section for a voxel of this many vertices (spec §5.5), and its flags code
// (the same in every file: the renderer uploads entries of voxels in the u16 class at 16 bits).
constexpr std::uint32_t order_entry_width(std::uint32_t vertex_count) {
  return vertex_count <= kU16OrderMaxVertices ? 2 : vertex_count <= kU24OrderMaxVertices ? 3 : 4;
}
constexpr std::uint32_t order_width_code(std::uint32_t vertex_count) { return order_entry_width(vertex_count) - 2; }

// How a file stores its order entries (spec §5.5): whole bytes (ORDR, files before 1.4 / 2.3) or as few bits
// as the block needs (ORDB).
enum class OrderPacking : std::uint8_t { Bytes, Bits };

// Bits per order entry of a block (or level prefix) of `vertex_count` vertices: entries are below
// vertex_count − 1, so ORDB stores the bits of vertex_count − 1 (at least one).
constexpr std::uint32_t order_entry_bits(std::uint32_t vertex_count, OrderPacking packing) {
  if (packing == OrderPacking::Bytes) return 8 * order_entry_width(vertex_count);
  return vertex_count <= 2 ? 1u : static_cast<std::uint32_t>(std::bit_width(vertex_count - 1));
}
// Bytes of one order array of `count` entries of `bits` bits; each array starts on a byte.
constexpr std::uint64_t order_array_bytes(std::uint64_t count, std::uint32_t bits) { return (count * bits + 7) / 8; }

// §5.6
struct VoxlineEntry {
  std::uint32_t voxel;
  std::uint32_t count_flags;  // bits 0-30 own point count; bit 31 first point synthetic
};
static_assert(sizeof(VoxlineEntry) == 8);
inline constexpr std::uint32_t kVoxlineSyntheticFirst = 0x80000000u;
inline constexpr std::uint32_t kVoxlineCountMask = 0x7FFFFFFFu;

// §5.14: one entry of a voxel's list of voxlines in VXIX: its streamline and three flags. Its points are found in
// the block (format/voxel_voxlines.h: the voxline ends, the depth from the streamline).
struct IndexedVoxline {
  std::uint32_t word;

  static constexpr std::uint32_t kStreamlineMask = (1u << 29) - 1;  // bits 0–28
  static constexpr std::uint32_t kSyntheticFirst = 1u << 29;        // its first own point is synthetic (spec §6.3)
  static constexpr std::uint32_t kFirstOfStreamline = 1u << 30;     // the streamline's first voxline
  static constexpr std::uint32_t kLastOfStreamline = 1u << 31;      // no connecting vertex follows it
  std::uint32_t streamline() const { return word & kStreamlineMask; }
};
static_assert(sizeof(IndexedVoxline) == 4);

constexpr std::uint64_t align_up(std::uint64_t x, std::uint64_t a) { return (x + a - 1) / a * a; }

// Bytes taken by one voxel's K orders of n segments, including the padding to 4 bytes (§5.5).
constexpr std::uint64_t voxel_orders_size(std::uint32_t vertex_count, std::uint32_t segment_count, std::uint32_t k,
                                          OrderPacking packing) {
  return align_up(k * order_array_bytes(segment_count, order_entry_bits(vertex_count, packing)), 4);
}

}  // namespace vxl
