// The `segsort` mode: voxels sorted as axis sorts them, each voxel's segments sorted on the CPU for this
// view (segment_sort.h), uploaded into the dataset buffers and drawn from there. Its CPU sort is the frame's
// cost: drawn whole by a frame's first piece.
#include <chrono>
#include <utility>
#include <vector>

#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"
#include "viewer/render/renderer.h"
#include "viewer/render/segment_sort.h"

namespace vxl {
namespace {

class SegsortPass final : public ModePass {
 public:
  RenderMode mode() const override { return RenderMode::Segsort; }
  void draw(PassHost& host, const FrameView& frame) override {
    host.clear_to_base(frame);
    over_blending();
    // The dataset buffers take the view order first, so that the budget counts them when the spans are made
    // resident. Then the voxels back to front as axis sorts them (Block and Nearest share the sort), then
    // each one's segments for this view; the plan's ranges then point into the dataset buffers.
    GpuScene& scene = host.scene();
    scene.prepare_view_order();
    FramePlan& plan = host.frame_plan();
    host.plan_and_count(frame, render_mode_info(RenderMode::Segsort).plan_order, plan);
    auto t0 = std::chrono::steady_clock::now();
    if (!sorter_) sorter_ = std::make_unique<SegmentSorter>(scene.layout(), host.scene_files());
    const Camera& camera = frame.camera;
    sorter_->sort(SegmentSortView{camera.eye(), camera.forward(), camera.orthographic}, plan);
    host.frame_stats().plan_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::vector<const std::vector<std::uint32_t>*> arrays;
    std::vector<std::pair<std::uint64_t, std::uint64_t>> ranges;
    for (std::uint32_t c = 0; c < scene.layout().texture_spans().size(); ++c) {
      arrays.push_back(&sorter_->span_order(c));
      ranges.push_back(sorter_->written(c));
    }
    scene.upload_view_order(arrays, ranges);
    const GLuint program = host.lines().over();
    host.bind_lines(program, frame, frame.settings);
    host.lines().draw_plan(program, plan.first, plan.count);
  }

 private:
  std::unique_ptr<SegmentSorter> sorter_;  // made on first use
};

}  // namespace

std::unique_ptr<ModePass> make_segsort_pass() { return std::make_unique<SegsortPass>(); }

}  // namespace vxl
