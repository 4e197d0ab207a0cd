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

namespace {

// One axis of spec §5.4: value = lo + q * step, in binary32.
struct PackedAxis {
  float lo, step;
  float decode(std::uint32_t q) const {
    const float offset = static_cast<float>(q) * step;  // rounded on its own: no fused multiply-add
    return lo + offset;
  }
};

PackedAxis axis_of(const VoxelEntry& v, int c) {
  const float extent = v.tight_max[c] - v.tight_min[c];
  return {v.tight_min[c], extent / static_cast<float>(kPackedSteps)};
}

}  // namespace

void pack_block(const VoxelEntry& voxel, float* xyz, std::uint32_t count, std::uint32_t* packed) {
  PackedAxis axes[3];
  for (int c = 0; c < 3; ++c) axes[c] = axis_of(voxel, c);
  for (std::uint32_t i = 0; i < count; ++i) {
    std::uint32_t word = 0;
    for (int c = 0; c < 3; ++c) {
      float& x = xyz[3 * i + c];
      std::uint32_t q = 0;
      if (axes[c].step > 0) {
        const double t = (double(x) - double(axes[c].lo)) / double(axes[c].step);
        q = t <= 0 ? 0 : t >= kPackedSteps ? kPackedSteps : static_cast<std::uint32_t>(std::floor(t + 0.5));
      }
      word |= q << (10 * c);
      x = axes[c].decode(q);
    }
    packed[i] = word;
  }
}

void unpack_block(const VoxelEntry& voxel, const std::uint32_t* packed, std::uint64_t count, float* xyz) {
  PackedAxis axes[3];
  for (int c = 0; c < 3; ++c) axes[c] = axis_of(voxel, c);
  for (std::uint64_t i = 0; i < count; ++i)
    for (int c = 0; c < 3; ++c) xyz[3 * i + c] = axes[c].decode((packed[i] >> (10 * c)) & kPackedAxisMask);
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
