#include "viewer/render/segment_sort.h"

#include <algorithm>
#include <limits>
#include <string>

#include "format/base/error.h"
#include "format/base/parallel.h"

namespace vxl {

double segment_depth(const SegmentSortView& view, const float* p, const float* q) {
  // In double, relative to the eye: scenes far from the origin keep their precision.
  const glm::dvec3 m(0.5 * (double(p[0]) + double(q[0])) - view.eye.x, 0.5 * (double(p[1]) + double(q[1])) - view.eye.y,
                     0.5 * (double(p[2]) + double(q[2])) - view.eye.z);
  return view.orthographic ? glm::dot(m, view.forward) : glm::dot(m, m);
}

void sort_segments_far_to_near(std::span<const float> xyz, std::span<const std::uint32_t> starts,
                               const SegmentSortView& view, std::uint32_t base,
                               std::vector<std::pair<double, std::uint32_t>>& keys, std::uint32_t* out) {
  keys.clear();
  keys.reserve(starts.size());
  for (const std::uint32_t s : starts) keys.push_back({-segment_depth(view, &xyz[3 * s], &xyz[3 * s + 3]), s});
  std::sort(keys.begin(), keys.end());  // farthest first; ties by start
  for (std::size_t j = 0; j < keys.size(); ++j) out[j] = base + keys[j].second;
}

SegmentSorter::SegmentSorter(const SceneLayout& layout, std::vector<const VxlFile*> files)
    : layout_(layout), files_(std::move(files)) {
  for (const TextureSpan& c : layout_.texture_spans()) per_span_.emplace_back(c.segments, 0u);
  written_.assign(per_span_.size(), {0, 0});
  scratch_.resize(resolve_threads(0));
}

void SegmentSorter::sort(const SegmentSortView& view, FramePlan& plan) {
  const auto& voxels = layout_.voxels();
  plan.first.resize(plan.voxels.size());
  plan.count.resize(plan.voxels.size());
  parallel_for(plan.voxels.size(), static_cast<unsigned>(scratch_.size()), [&](std::uint64_t k, unsigned t) {
    Scratch& s = scratch_[t];
    const std::uint32_t i = plan.voxels[k];
    const VoxelDrawInfo& d = voxels[i];
    const std::uint32_t fi = layout_.file_of(i), li = layout_.local_voxel(i);
    const VxlFile& file = *files_[fi];
    // The layout's level: its vertices are a prefix of the block, its order 0 lists its segments' first
    // vertices (.vxl spec §5.12); order entries were checked by the upload (gpu_scene.cpp), checked again
    // here for a sorter used on its own.
    const OrderView starts = file.order(li, 0, layout_.files()[fi].level);
    s.starts.resize(starts.count);
    for (std::uint32_t n = 0; n < starts.count; ++n) {
      s.starts[n] = starts[n];
      if (s.starts[n] + 1ull >= d.vertex_count)
        throw Error(ErrorKind::Input, file.path(), std::nullopt,
                    "order entry out of range in voxel " + std::to_string(li) + " (run `voxlines verify`)");
    }
    s.xyz.resize(3 * std::uint64_t(d.vertex_count));
    file.read_vertices(li, file.voxels()[li].vertex_first, d.vertex_count, s.xyz.data());
    sort_segments_far_to_near(s.xyz, s.starts, view, static_cast<std::uint32_t>(d.vertex_first), s.keys,
                              per_span_[d.span].data() + d.seg_first);
    plan.first[k] = layout_.dataset_id(d.span, d.seg_first);
    plan.count[k] = static_cast<std::int32_t>(2 * std::uint64_t(starts.count));
  });
  // What changed, per span: the upload sends only that range.
  written_.assign(per_span_.size(), {std::numeric_limits<std::uint64_t>::max(), 0});
  for (const std::uint32_t i : plan.voxels) {
    const VoxelDrawInfo& d = voxels[i];
    auto& [first, end] = written_[d.span];
    first = std::min(first, d.seg_first);
    end = std::max(end, d.seg_first + d.segment_count);
  }
  for (auto& [first, end] : written_)
    if (first >= end) first = end = 0;
}

}  // namespace vxl
