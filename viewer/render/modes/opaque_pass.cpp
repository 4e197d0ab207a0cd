// The `opaque` mode: depth-tested lines, the nearest wins; drawn in pieces as runs of voxels in any order.
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"

namespace vxl {
namespace {

class OpaquePass final : public ModePass {
 public:
  RenderMode mode() const override { return RenderMode::Opaque; }
  void draw(PassHost& host, const FrameView& frame) override {
    host.clear_to_base(frame);
    opaque_blending();
    draw_planned_lines(host, frame, host.lines().over(), frame.settings, render_mode_info(mode()).plan_order);
    glDisable(GL_DEPTH_TEST);
  }
  PieceKind piece_kind() const override { return PieceKind::Voxels; }
  PlanOrder plan_order(const RenderSettings&, FramePlan&) const override { return render_mode_info(mode()).plan_order; }
  void piece_state() const override { opaque_blending(); }
};

}  // namespace

std::unique_ptr<ModePass> make_opaque_pass() { return std::make_unique<OpaquePass>(); }

}  // namespace vxl
