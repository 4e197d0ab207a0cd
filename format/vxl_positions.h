// Vertex positions of spec §5.4 in their two encodings: float32 (exact, 12 bytes per vertex) or packed
// (4 bytes: 10 bits per axis of fixed point across the voxel's tight bounds, plus a voxline-end bit).
//
// Packed positions are decoded as lo + q * step in binary32, the multiply and the add rounded apart
// (the project is compiled without floating-point contraction), so that every reader — the
// converter building orders, verify checking them, the viewer — sees the same coordinates.
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "format/vxl_layout.h"

namespace vxl {

enum class PositionEncoding : std::uint32_t { Float32 = 0, Packed = 1 };

inline constexpr std::uint32_t kPackedSteps = 1023;           // 10 bits: q in 0..1023 across [lo, hi]
inline constexpr std::uint32_t kPackedAxisMask = 0x3FFu;      // bits 0-9 x, 10-19 y, 20-29 z
inline constexpr std::uint32_t kPackedVoxlineEnd = 1u << 30;  // the last vertex of its voxline
inline constexpr std::uint32_t kPackedReservedBit = 1u << 31;

constexpr std::uint64_t vertex_bytes(PositionEncoding e) { return e == PositionEncoding::Packed ? 4 : 12; }
const char* position_encoding_name(PositionEncoding e);  // "packed" or "float32"
std::optional<PositionEncoding> parse_position_encoding(std::string_view name);

// One voxel's quantisation (spec §5.4), for writers that pack a block a few vertices at a time.
class VertexPacker {
 public:
  explicit VertexPacker(const VoxelEntry& voxel);  // the voxel's tight bounds must be set
  // The packed word of one vertex (end bit clear); replaces its coordinates by what the word decodes to.
  std::uint32_t pack(float* xyz) const;
  void pack(float* xyz, std::uint64_t count, std::uint32_t* packed) const;
  // The same words, leaving the coordinates as they are.
  void words(const float* xyz, std::uint64_t count, std::uint32_t* packed) const;
  // 3 * count floats from `count` words (their end bits ignored).
  void decode(const std::uint32_t* packed, std::uint64_t count, float* xyz) const;
  // Axis c's coordinate for quantum q (0..kPackedSteps), as decode() gives it.
  float decode_axis(int c, std::uint32_t q) const;
  // decode_axis(c, q) for every q, in one call: a voxel's table is filled by one loop, not 1024 calls.
  void decode_axis_table(int c, std::span<float, kPackedSteps + 1> table) const;
  // One word's 3 floats, as decode() gives them; inline for loops that decode only some of a block's words.
  void decode_word(std::uint32_t w, float* xyz) const {
    xyz[0] = lo_[0] + static_cast<float>(w & kPackedAxisMask) * step_[0];  // each product rounded: no fused add
    xyz[1] = lo_[1] + static_cast<float>((w >> 10) & kPackedAxisMask) * step_[1];
    xyz[2] = lo_[2] + static_cast<float>((w >> 20) & kPackedAxisMask) * step_[2];
  }

 private:
  std::uint32_t word(const float* xyz) const;
  float lo_[3], step_[3];
};

// Quantises one voxel's block: writes each vertex's packed word (end bit clear) into `packed` and replaces
// its coordinates in `xyz` by the values the word decodes to. The voxel's tight bounds must hold the block.
void pack_block(const VoxelEntry& voxel, float* xyz, std::uint32_t count, std::uint32_t* packed);

// Decodes `count` packed words of `voxel`'s block into 3 * count floats.
void unpack_block(const VoxelEntry& voxel, const std::uint32_t* packed, std::uint64_t count, float* xyz);

// The largest distance, per axis, between a vertex of this voxel and its packed decoding (spec §5.4):
// (hi - lo) * (1/2046 + 2^-21) + 2^-23 * max(|lo|, |hi|) over the voxel's tight bounds, in mm.
double packed_error_bound(const VoxelEntry& voxel);

}  // namespace vxl
