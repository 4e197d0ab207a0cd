#include "converter/selection/voxline_boxes.h"

#include <algorithm>

#include "format/vxl_positions.h"

namespace vxl {

VoxlineBoxes::VoxlineBoxes(const VxlFile& file, std::uint64_t budget_bytes)
    : file_(file),
      budget_(budget_bytes),
      lists_(file.voxels().size()),
      boxed_(new std::atomic<bool>[file.voxels().size()]),
      used_(new std::atomic<bool>[file.voxels().size()]),
      references_(file.voxels().size()) {
  for (std::size_t v = 0; v < lists_.size(); ++v) boxed_[v] = false, used_[v] = false;
}

std::optional<std::span<BoxedVoxline>> VoxlineBoxes::voxel(std::size_t voxel, const VoxelVoxlines& index) {
  used_[voxel] = true;
  if (boxed_[voxel]) return std::span<BoxedVoxline>(lists_[voxel]);
  const auto voxlines = static_cast<std::int64_t>(index.of_voxel(voxel).size());
  if (boxing_left_.fetch_sub(voxlines) <= 0) {  // a voxel larger than the whole allowance is boxed when it comes first
    boxing_left_ += voxlines;
    return std::nullopt;
  }
  const std::uint64_t need = index.of_voxel(voxel).size() * sizeof(BoxedVoxline);
  if (bytes_.fetch_add(need) + need > budget_) {
    bytes_ -= need;
    boxing_left_ += voxlines;
    return std::nullopt;
  }
  thread_local std::vector<std::uint8_t> ends;
  thread_local std::vector<PlacedVoxline> placed;
  try {
    place_voxel_voxlines(file_, index, voxel, ends, placed);
  } catch (...) {
    bytes_ -= need;
    throw;
  }
  const VoxelEntry& v = file_.voxels()[voxel];
  const std::uint32_t* words = file_.packed_vertices().data();
  std::vector<BoxedVoxline>& list = lists_[voxel];
  list.resize(placed.size());
  for (std::size_t k = 0; k < placed.size(); ++k) {
    const PlacedVoxline& p = placed[k];
    BoxedVoxline& b = list[k];
    b.streamline = p.streamline;
    b.first = static_cast<std::uint32_t>(p.first_vertex - v.vertex_first);
    b.own = p.own;
    b.flags = static_cast<std::uint8_t>((p.synthetic_first ? BoxedVoxline::kSyntheticFirst : 0) |
                                        (p.first_of_streamline ? BoxedVoxline::kFirstOfStreamline : 0) |
                                        (p.last_of_streamline ? BoxedVoxline::kLastOfStreamline : 0));
    std::uint32_t lo[3] = {kPackedSteps + 1, kPackedSteps + 1, kPackedSteps + 1}, hi[3] = {0, 0, 0};
    for (std::uint64_t i = p.first_vertex + (p.synthetic_first ? 1 : 0); i < p.first_vertex + p.own; ++i) {
      const std::uint32_t w = words[i];
      const std::uint32_t q[3] = {w & kPackedAxisMask, (w >> 10) & kPackedAxisMask, (w >> 20) & kPackedAxisMask};
      for (int c = 0; c < 3; ++c) lo[c] = std::min(lo[c], q[c]), hi[c] = std::max(hi[c], q[c]);
    }
    for (int c = 0; c < 3; ++c)
      b.lo[c] = static_cast<std::uint16_t>(lo[c]), b.hi[c] = static_cast<std::uint16_t>(hi[c]);
  }
  references_[voxel].known = false;
  boxed_[voxel] = true;
  return std::span<BoxedVoxline>(list);
}

void VoxlineBoxes::track_region(int region) {
  if (region == tracked_region_) return;
  tracked_region_ = region;
  for (VoxelReference& r : references_) r.known = false;
}

void VoxlineBoxes::selection_started() {
  boxing_left_ = selected_before_ ? kBoxedPerSelection : 0;
  selected_before_ = true;
}

void VoxlineBoxes::selection_done() {
  for (std::size_t v = 0; v < lists_.size(); ++v) {
    if (bytes_ > budget_ / 2 && boxed_[v] && !used_[v]) {
      bytes_ -= lists_[v].size() * sizeof(BoxedVoxline);
      std::vector<BoxedVoxline>().swap(lists_[v]);
      boxed_[v] = false;
    }
    used_[v] = false;
  }
}

}  // namespace vxl
