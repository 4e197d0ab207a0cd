#include "format/vxlz_shipping_order.h"

#include <algorithm>
#include <utility>

#include "format/vxl_levels.h"

namespace vxl {

ShippingOrder shipping_order(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
                             std::span<const std::uint8_t> depths) {
  const std::uint64_t n = strm.empty() ? 0 : strm.size() - 1;
  ShippingOrder order;
  order.streamlines.resize(n);
  if (depths.empty()) {
    for (std::uint64_t s = 0; s < n; ++s) order.streamlines[s] = s;
  } else {
    // A counting sort by depth, deepest first, each depth in streamline order.
    std::uint64_t start[256] = {};
    for (std::uint64_t s = 0; s < n; ++s) ++start[255 - depths[s]];
    std::uint64_t sum = 0;
    for (std::uint64_t& c : start) sum += std::exchange(c, sum);
    for (std::uint64_t s = 0; s < n; ++s) order.streamlines[start[255 - depths[s]]++] = s;
  }
  order.first_point.resize(n + 1);
  order.first_point[0] = 0;
  for (std::uint64_t p = 0; p < n; ++p) {
    std::uint64_t points = 0;
    const std::uint64_t s = order.streamlines[p];
    for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) points += voxlines[j].count_flags & kVoxlineCountMask;
    order.first_point[p + 1] = order.first_point[p] + points;
  }
  return order;
}

std::vector<std::uint8_t> shipped_depths(const PackSection& pack, std::uint64_t streamline_count) {
  if (pack.predictor != kVxlzPredictorLinearLevelOrder) return {};
  std::vector<std::uint8_t> depths(streamline_count);
  for (std::uint64_t s = 0; s < streamline_count; ++s)
    depths[s] = static_cast<std::uint8_t>(streamline_depth(s, pack.level_count));
  return depths;
}

ShippedVoxlineCursor::ShippedVoxlineCursor(const ShippingOrder& order, std::span<const std::uint64_t> strm,
                                           std::span<const VoxlineEntry> voxlines, std::uint64_t point)
    : order_(order), strm_(strm), voxlines_(voxlines) {
  if (order.streamlines.empty()) return;
  // The last streamline whose first point is at or before `point` (empty ones share their successor's).
  position_ =
      static_cast<std::uint64_t>(std::upper_bound(order.first_point.begin(), order.first_point.end() - 1, point) -
                                 order.first_point.begin()) -
      1;
  voxline_ = strm_[order_.streamlines[position_]];
  in_voxline_ = point - order.first_point[position_];
  settle();
}

void ShippedVoxlineCursor::advance(std::uint64_t points) {
  in_voxline_ += points;
  settle();
}

void ShippedVoxlineCursor::settle() {
  while (position_ < order_.streamlines.size()) {
    const std::uint64_t end = strm_[order_.streamlines[position_] + 1];
    while (voxline_ < end && in_voxline_ >= own()) {
      in_voxline_ -= own();
      ++voxline_;
    }
    if (voxline_ < end) return;
    if (++position_ < order_.streamlines.size()) voxline_ = strm_[order_.streamlines[position_]];
  }
}

}  // namespace vxl
