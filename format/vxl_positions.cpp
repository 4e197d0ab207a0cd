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
    inverse_step_[c] = step_[c] > 0 ? 1.0 / double(step_[c]) : 0.0;
  }
}

float VertexPacker::decode_axis(int c, std::uint32_t q) const {
  const float offset = static_cast<float>(q) * step_[c];  // rounded on its own: no fused multiply-add
  return lo_[c] + offset;
}

std::uint32_t VertexPacker::quantise(int c, float x) const {
  if (!(step_[c] > 0)) return 0;
  const double t = (double(x) - double(lo_[c])) / double(step_[c]);
  // t + 0.5 > 0 here, where truncation is floor: no floor() library call per coordinate (the baseline
  // x86-64 ISA has no rounding instruction).
  return t <= 0 ? 0 : t >= kPackedSteps ? kPackedSteps : static_cast<std::uint32_t>(t + 0.5);
}

// The spec's q = round((x - lo) / step) clamped to 0 ... 1023 is trunc(clamp(t + 0.5, 0, 1023)), here with
// t by a multiplication by the inverse step instead of the quotient, branch-free: the product is within
// a few units in the last place of the quotient, which can only change q where t + 0.5 lies that close to
// an integer. There (and at the clamps) quantise() divides. Dividing cost about a quarter of the
// streaming conversion's placing pass.
std::uint32_t VertexPacker::word(const float* xyz) const {
  std::uint32_t word = 0;
  bool near_integer = false;
  for (int c = 0; c < 3; ++c) {
    const double f = std::clamp((double(xyz[c]) - double(lo_[c])) * inverse_step_[c] + 0.5, 0.0, double(kPackedSteps));
    const std::uint32_t q = static_cast<std::uint32_t>(f);
    const double fraction = f - double(q);
    near_integer |= fraction < 1e-9 || fraction > 1 - 1e-9;
    word |= q << (10 * c);
  }
  if (near_integer) word = quantise(0, xyz[0]) | quantise(1, xyz[1]) << 10 | quantise(2, xyz[2]) << 20;
  return word;
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
  for (std::uint64_t i = 0; i < count; ++i) packed[i] = word(xyz + 3 * i);
}

void VertexPacker::decode(const std::uint32_t* packed, std::uint64_t count, float* xyz) const {
  for (std::uint64_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c) xyz[3 * i + c] = decode_axis(c, (packed[i] >> (10 * c)) & kPackedAxisMask);
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
