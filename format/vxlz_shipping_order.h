// The order in which a package ships its points (spec/vxlz-package-v2.md §5.1): streamline after streamline, each
// voxline's own points in turn; in level order (predictor 2) the streamlines of the coarsest level first, so that a
// prefix of the positions holds a level of detail whole. The packer encodes and the unpacker decodes the position
// chunks by it.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/vxl_layout.h"
#include "format/vxlz_layout.h"

namespace vxl {

struct ShippingOrder {
  std::vector<std::uint64_t> streamlines;  // streamline indices, in shipped order
  std::vector<std::uint64_t> first_point;  // streamlines.size() + 1: the shipped index of each one's first point
};

// `strm`: the streamline table (N + 1 first voxlines), `voxlines` the voxline table (own point counts),
// `depths`: each streamline's depth (spec §5.1: the order's key), or empty for streamline order.
ShippingOrder shipping_order(std::span<const std::uint64_t> strm, std::span<const VoxlineEntry> voxlines,
                             std::span<const std::uint8_t> depths);

// Each streamline's depth in the order `pack` names (PACK.predictor, PACK.level_count: `.vxl` spec §6.5's depth for
// its level order), the key shipping_order sorts by; empty for streamline order.
std::vector<std::uint8_t> shipped_depths(const PackSection& pack, std::uint64_t streamline_count);

// Walks the shipped points voxline by voxline, from any shipped point: where a chunk starts, which voxline holds
// the point, and how far into it.
class ShippedVoxlineCursor {
 public:
  ShippedVoxlineCursor(const ShippingOrder& order, std::span<const std::uint64_t> strm,
                       std::span<const VoxlineEntry> voxlines, std::uint64_t point);
  std::uint64_t voxline() const { return voxline_; }
  std::uint64_t point_in_voxline() const { return in_voxline_; }
  // Where the voxline's streamline is in the order (its index in ShippingOrder::streamlines).
  std::uint64_t shipped_position() const { return position_; }
  // The voxline's own points (count_flags' count).
  std::uint64_t own() const { return voxlines_[voxline_].count_flags & kVoxlineCountMask; }
  // Moves `points` points on (at most to the end of the voxline); past its end, to the next shipped voxline.
  void advance(std::uint64_t points);

 private:
  void settle();  // past the end of a voxline or a streamline: to the next shipped voxline with points left

  const ShippingOrder& order_;
  std::span<const std::uint64_t> strm_;
  std::span<const VoxlineEntry> voxlines_;
  std::uint64_t position_ = 0;  // in order_.streamlines
  std::uint64_t voxline_ = 0, in_voxline_ = 0;
};

}  // namespace vxl
