// Quantisation of positions on the package's grid and the linear predictor along streamlines
// (spec/vxlz-package-v2.md §5.1, §5.2, §6). Shared by the packer and the unpacker, which must agree on
// every bit.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "format/vxlz_layout.h"

namespace vxl {

class Quantizer {
 public:
  explicit Quantizer(const PackSection& p)
      : origin_{p.quant_origin[0], p.quant_origin[1], p.quant_origin[2]},
        quantum_(p.quantum),
        max_value_((1u << p.quantization_bits) - 1) {}

  std::uint32_t max_value() const { return max_value_; }

  // §5.1: round half up on the grid (p >= origin, so half up is half away from zero), clamped.
  std::int32_t quantize(float p, int c) const {
    const double k = std::floor((double(p) - origin_[c]) / quantum_ + 0.5);
    return static_cast<std::int32_t>(std::clamp(k, 0.0, double(max_value_)));
  }

  // §6: one binary64 multiply, one binary64 add, one rounding to binary32. (Never contracted into a fused
  // multiply-add, which would change the last bit: the project is compiled with -ffp-contract=off.)
  float dequantize(std::int64_t k, int c) const {
    const double scaled = double(k) * quantum_;
    return static_cast<float>(origin_[c] + scaled);
  }

 private:
  std::array<double, 3> origin_;
  double quantum_;
  std::uint32_t max_value_;
};

// The bound of §6: q/2 + 2^-23 * M, M the largest magnitude in the quantisation cube; the first term is 0
// when the range is 0 (every point is the origin, which decodes exactly).
inline double vxlz_error_bound(const double origin[3], double range, double quantum) {
  double m = 0;
  for (int c = 0; c < 3; ++c) m = std::max({m, std::abs(origin[c]), std::abs(origin[c] + range)});
  return (range > 0 ? quantum / 2 : 0.0) + std::ldexp(m, -23);
}

// §5.2, predictor 1, used point by point inside one chunk: reset() at the chunk's start,
// start_streamline() before a streamline's first point, then predict() and push() for every point.
// Written as "previous point + slope", the slope being the last step of the current streamline once it
// has two points in the chunk and 0 before: the same prediction as the spec's cases, without branches.
class LinearPredictor {
 public:
  void reset() {
    previous_ = slope_ = {0, 0, 0};
    first_ = true;
  }
  void start_streamline() {
    slope_ = {0, 0, 0};
    first_ = true;
  }
  std::int64_t predict(int c) const { return previous_[c] + slope_[c]; }
  void push(const std::array<std::int64_t, 3>& k) {
    for (int c = 0; c < 3; ++c) {
      slope_[c] = first_ ? 0 : k[c] - previous_[c];
      previous_[c] = k[c];
    }
    first_ = false;
  }

 private:
  std::array<std::int64_t, 3> previous_{}, slope_{};
  bool first_ = true;
};

}  // namespace vxl
