// The `segsort` mode's per-frame CPU work: every visible voxel's segments sorted by their own depth for the
// exact view, far to near, instead of drawn in a precomputed order. It is the best any stored order set could
// reach (the voxels are still sorted as `axis` sorts them), a reference for the orders, and slow: O(segments
// drawn · log) on the CPU every frame. No GL here (the renderer uploads what it writes).
//
//   SegmentSorter sorter(layout, files);
//   plan_frame(layout, view, PlanOrder::Block, plan);   // voxels back to front
//   sorter.sort(SegmentSortView{eye, forward, ortho}, plan);
//   // per span: sorter.span_order(c)[sorter.written(c)] -> the dataset texture buffer; draw plan.first/count
//
// A segment's depth is the distance from the eye to its midpoint (perspective) or the midpoint's projection
// on the view direction (orthographic). Each voxel's sorted segments are written, as span vertex indices (the
// dataset-order entries of scene_layout.h: segment (v, v + 1) of the span's words), at the voxel's segment
// range [seg_first, seg_first + segment_count) of its span's array, and plan.first/count are pointed at
// those ranges, so one glMultiDrawArrays draws the voxels back to front, each sorted.
#pragma once

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "format/vxl_file.h"
#include "viewer/render/frame_plan.h"
#include "viewer/render/scene_layout.h"

namespace vxl {

struct SegmentSortView {
  glm::dvec3 eye;
  glm::dvec3 forward;  // unit view direction
  bool orthographic = false;
};

// The depth key of the segment from p to q: larger is farther (|m - eye|^2 or (m - eye) · forward, m the
// midpoint).
double segment_depth(const SegmentSortView& view, const float* p, const float* q);

// One voxel's segments far to near. xyz: 3 floats per vertex of its block (prefix); starts: the block-local
// first vertex of each segment (segment (s, s + 1)). Writes base + start for every segment into out[0 ..
// starts.size()), farthest first; equal depths keep ascending starts (deterministic). keys: scratch.
void sort_segments_far_to_near(std::span<const float> xyz, std::span<const std::uint32_t> starts,
                               const SegmentSortView& view, std::uint32_t base,
                               std::vector<std::pair<double, std::uint32_t>>& keys, std::uint32_t* out);

class SegmentSorter {
 public:
  // The layout and the files (in the layout's order) must outlive the sorter.
  SegmentSorter(const SceneLayout& layout, std::vector<const VxlFile*> files);

  // Sorts the segments of every voxel `plan` draws (plan.voxels, in drawing order) for `view`, at the
  // layout's level of detail, on all hardware threads; writes them into the spans' arrays and replaces
  // plan.first/count by their dataset-order ranges (SceneLayout::dataset_id).
  void sort(const SegmentSortView& view, FramePlan& plan);

  // Span c's array: S entries (its padded segment count), span vertex indices.
  const std::vector<std::uint32_t>& span_order(std::uint32_t span) const { return per_span_[span]; }
  // The entries [first, end) of span c's array that the last sort() wrote (first == end: none).
  std::pair<std::uint64_t, std::uint64_t> written(std::uint32_t span) const { return written_[span]; }

 private:
  struct Scratch {
    std::vector<float> xyz;
    std::vector<std::uint32_t> starts;
    std::vector<std::pair<double, std::uint32_t>> keys;
  };
  const SceneLayout& layout_;
  std::vector<const VxlFile*> files_;
  std::vector<std::vector<std::uint32_t>> per_span_;
  std::vector<std::pair<std::uint64_t, std::uint64_t>> written_;
  std::vector<Scratch> scratch_;  // per thread
};

}  // namespace vxl
