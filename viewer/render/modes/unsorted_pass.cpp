// The `unsorted` mode: the streamlines in the file's order, blended "over" without sorting (the baseline
// every sorted mode improves on); drawn whole by a frame's first piece.
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"
#include "viewer/render/renderer.h"

namespace vxl {
namespace {

class UnsortedPass final : public ModePass {
 public:
  RenderMode mode() const override { return RenderMode::Unsorted; }
  void draw(PassHost& host, const FrameView& frame) override {
    host.clear_to_base(frame);
    over_blending();
    FramePlan dataset;  // runs of the streamline order, one span each
    dataset.first = host.scene().dataset_first();
    dataset.count = host.scene().dataset_count();
    host.keep_resident(dataset);
    FrameStats& stats = host.frame_stats();
    stats.plan_ms = 0;
    stats.voxels_drawn = stats.segments_drawn = 0;
    for (const VxlFile* f : host.scene_files()) stats.voxels_drawn += f->meta().voxel_count;
    for (std::int32_t ids : dataset.count) stats.segments_drawn += static_cast<std::uint64_t>(ids / 2);  // the level's
    const GLuint program = host.lines().over();
    host.bind_lines(program, frame, frame.settings);
    host.lines().draw_plan(program, dataset.first, dataset.count);
  }
};

}  // namespace

std::unique_ptr<ModePass> make_unsorted_pass() { return std::make_unique<UnsortedPass>(); }

}  // namespace vxl
