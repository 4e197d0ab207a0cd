#include "viewer/render/modes/mode_pass.h"

#include <stdexcept>

namespace vxl {

PlanOrder ModePass::plan_order(const RenderSettings&, FramePlan&) const {
  throw std::logic_error(std::string("the ") + render_mode_name(mode()) + " mode is not drawn in runs of voxels");
}

void ModePass::begin(PassHost&, const FrameView&) {
  throw std::logic_error(std::string("the ") + render_mode_name(mode()) + " mode does not draw its own pieces");
}

bool ModePass::step(double) {
  throw std::logic_error(std::string("the ") + render_mode_name(mode()) + " mode does not draw its own pieces");
}

void draw_planned_lines(PassHost& host, const FrameView& frame, GLuint program, const RenderSettings& settings,
                        PlanOrder order) {
  FramePlan& plan = host.frame_plan();
  host.plan_and_count(frame, order, plan);
  host.bind_lines(program, frame, settings);
  host.lines().draw_plan(program, plan.first, plan.count);
}

}  // namespace vxl
