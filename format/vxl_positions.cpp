#include "format/vxl_positions.h"

#include <algorithm>
#include <cmath>

namespace vxl {

const char* position_encoding_name(PositionEncoding e) { return e == PositionEncoding::Packed ? "packed" : "float32"; }

std::optional<PositionEncoding> parse_position_encoding(std::string_view name) {
  if (name == "packed") return PositionEncoding::Packed;
  if (name == "float32") return PositionEncoding::Float32;
  return std::nullopt;
}

VertexPacker::VertexPacker(const VoxelEntry& voxel) {
  for (int c = 0; c < 3; ++c) {
    const float extent = voxel.tight_max[c] - voxel.tight_min[c];
    lo_[c] = voxel.tight_min[c];
    step_[c] = extent / static_cast<float>(kPackedSteps);
  }
}

float VertexPacker::decode_axis(int c, std::uint32_t q) const {
  const float offset = static_cast<float>(q) * step_[c];  // rounded on its own: no fused multiply-add
  return lo_[c] + offset;
}

void VertexPacker::decode_axis_table(int c, std::span<float, kPackedSteps + 1> table) const {
  const float lo = lo_[c], step = step_[c];
  for (std::uint32_t q = 0; q <= kPackedSteps; ++q) table[q] = lo + static_cast<float>(q) * step;  // as decode_axis
}

namespace {

// One coordinate's quantum. Here, not a member, so that the loops of words() and pack() inline it (as a
// call per vertex it took a quarter of packing's time).
inline std::uint32_t quantise_axis(float lo, float step, float x) {
  if (!(step > 0)) return 0;
  const double t = (double(x) - double(lo)) / double(step);
  // t + 0.5 > 0 here, where truncation is floor: no floor() library call per coordinate (the baseline
  // x86-64 ISA has no rounding instruction), which took more than half of packing's time. (A product with
  // 1 / step, divided only next to a half-step, measured slower still: the three divisions pipeline.)
  return t <= 0 ? 0 : t >= kPackedSteps ? kPackedSteps : static_cast<std::uint32_t>(t + 0.5);
}

}  // namespace

std::uint32_t VertexPacker::word(const float* xyz) const {
  return quantise_axis(lo_[0], step_[0], xyz[0]) | quantise_axis(lo_[1], step_[1], xyz[1]) << 10 |
         quantise_axis(lo_[2], step_[2], xyz[2]) << 20;
}

std::uint32_t VertexPacker::pack(float* xyz) const {
  const std::uint32_t packed = word(xyz);
  for (int c = 0; c < 3; ++c) xyz[c] = decode_axis(c, (packed >> (10 * c)) & kPackedAxisMask);
  return packed;
}

void VertexPacker::pack(float* xyz, std::uint64_t count, std::uint32_t* packed) const {
  for (std::uint64_t i = 0; i < count; ++i) packed[i] = pack(xyz + 3 * i);
}

void VertexPacker::words(const float* xyz, std::uint64_t count, std::uint32_t* packed) const {
  if (!(step_[0] > 0 && step_[1] > 0 && step_[2] > 0)) {  // a flat voxel: quantise_axis's own test
    for (std::uint64_t i = 0; i < count; ++i, xyz += 3) packed[i] = word(xyz);
    return;
  }
  // x and y as one pair of lanes (each instruction does the same IEEE operation on both), z alone: the divisions
  // are what packing waits on, and a pair divides as fast as one. The clamps as in quantise_axis: t <= 0 gives 0
  // either way, t >= kPackedSteps gives kPackedSteps.
  using Pair = double __attribute__((vector_size(16)));
  using Quanta = std::int32_t __attribute__((vector_size(8)));
  const Pair lo_xy = {double(lo_[0]), double(lo_[1])}, step_xy = {double(step_[0]), double(step_[1])};
  const Pair zero = {0.0, 0.0}, top = {double(kPackedSteps), double(kPackedSteps)}, half = {0.5, 0.5};
  const double lo_z = lo_[2], step_z = step_[2];
  for (std::uint64_t i = 0; i < count; ++i, xyz += 3) {
    Pair t = (Pair{double(xyz[0]), double(xyz[1])} - lo_xy) / step_xy;
    t = t < zero ? zero : t;
    t = t > top ? top : t;
    const Quanta q = __builtin_convertvector(t + half, Quanta);
    const double tz = std::min(std::max((double(xyz[2]) - lo_z) / step_z, 0.0), double(kPackedSteps));
    packed[i] = std::uint32_t(q[0]) | std::uint32_t(q[1]) << 10 | static_cast<std::uint32_t>(tz + 0.5) << 20;
  }
}

void VertexPacker::decode(const std::uint32_t* packed, std::uint64_t count, float* xyz) const {
  // The bounds in locals: `xyz` may alias the members as far as the compiler knows, which would reload them
  // for every coordinate. The same arithmetic as decode_axis.
  const float lo_x = lo_[0], lo_y = lo_[1], lo_z = lo_[2], step_x = step_[0], step_y = step_[1], step_z = step_[2];
  for (std::uint64_t i = 0; i < count; ++i, xyz += 3) {
    const std::uint32_t w = packed[i];
    const float dx = static_cast<float>(w & kPackedAxisMask) * step_x;
    const float dy = static_cast<float>((w >> 10) & kPackedAxisMask) * step_y;
    const float dz = static_cast<float>((w >> 20) & kPackedAxisMask) * step_z;
    xyz[0] = lo_x + dx;
    xyz[1] = lo_y + dy;
    xyz[2] = lo_z + dz;
  }
}

void pack_block(const VoxelEntry& voxel, float* xyz, std::uint32_t count, std::uint32_t* packed) {
  VertexPacker(voxel).pack(xyz, count, packed);
}

void unpack_block(const VoxelEntry& voxel, const std::uint32_t* packed, std::uint64_t count, float* xyz) {
  VertexPacker(voxel).decode(packed, count, xyz);
}

double packed_error_bound(const VoxelEntry& voxel) {
  double bound = 0;
  for (int c = 0; c < 3; ++c) {
    const double lo = voxel.tight_min[c], hi = voxel.tight_max[c];
    bound = std::max(bound, (hi - lo) * (1.0 / 2046 + std::ldexp(1.0, -21)) +
                                std::ldexp(1.0, -23) * std::max(std::abs(lo), std::abs(hi)));
  }
  return bound;
}

}  // namespace vxl
