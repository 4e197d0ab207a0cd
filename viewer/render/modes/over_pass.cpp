// The `basic` and `axis` modes: the frame plan's voxels blended "over", back to front, in the block order
// (basic) or each voxel's stored order nearest the view direction (axis); drawn in pieces as runs of voxels.
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"

namespace vxl {
namespace {

class OverPass final : public ModePass {
 public:
  explicit OverPass(RenderMode mode) : mode_(mode), order_(render_mode_info(mode).plan_order) {}
  RenderMode mode() const override { return mode_; }
  void draw(PassHost& host, const FrameView& frame) override {
    host.clear_to_base(frame);
    over_blending();
    const PlanOrder order = plan_order(frame.settings, host.frame_plan());
    draw_planned_lines(host, frame, host.lines().over(), frame.settings, order);
  }
  PieceKind piece_kind() const override { return PieceKind::Voxels; }
  PlanOrder plan_order(const RenderSettings& settings, FramePlan& plan) const override {
    // Only the nearest-order pick keeps a voxel's order across frames (FramePlan::order_hysteresis).
    if (order_ == PlanOrder::Nearest) plan.order_hysteresis = settings.order_hysteresis;
    return order_;
  }
  void piece_state() const override {
    glDisable(GL_DEPTH_TEST);
    over_blending();
  }

 private:
  RenderMode mode_;
  PlanOrder order_;
};

}  // namespace

std::unique_ptr<ModePass> make_basic_pass() { return std::make_unique<OverPass>(RenderMode::Basic); }
std::unique_ptr<ModePass> make_axis_pass() { return std::make_unique<OverPass>(RenderMode::Axis); }

}  // namespace vxl
