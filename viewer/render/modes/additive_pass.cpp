// The `additive` mode: the lines' alpha-weighted colours summed in a target of their own and composited
// over the opaque picture of the same lines, so that density shows as brightness. Blends in no order:
// drawn whole by a frame's first piece.
#include <algorithm>

#include "viewer/render/line_shaders.h"
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/fullscreen_composite.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"

namespace vxl {
namespace {

void clear_target(GLuint target, int width, int height) {
  glBindFramebuffer(GL_FRAMEBUFFER, target);
  glViewport(0, 0, width, height);
  glClearColor(0, 0, 0, 0);
  glClearDepth(1.0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

class AdditivePass final : public ModePass {
 public:
  ~AdditivePass() override {
    if (composite_) glDeleteProgram(composite_);
    opaque_target_.destroy();
    additive_target_.destroy();
  }
  RenderMode mode() const override { return RenderMode::Additive; }
  void draw(PassHost& host, const FrameView& frame) override {
    if (!composite_) composite_ = gl::make_program(shaders::kFullscreenVertex, shaders::kAdditiveCompositeFragment);
    LinePass& lines = host.lines();
    const RenderSettings& s = frame.settings;
    opaque_target_.ensure(frame.width, frame.height, GL_RGBA8, 0, true);
    additive_target_.ensure(frame.width, frame.height, GL_RGBA16F, 0, false);
    clear_target(opaque_target_.fbo, frame.width, frame.height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    RenderSettings solid = s;
    solid.opacity = 1.0f;
    draw_planned_lines(host, frame, lines.over(), solid, render_mode_info(mode()).plan_order);
    glDisable(GL_DEPTH_TEST);
    glBindFramebuffer(GL_FRAMEBUFFER, additive_target_.fbo);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    host.bind_lines(lines.additive(), frame, s);
    lines.draw_plan(lines.additive(), host.frame_plan().first, host.frame_plan().count);
    host.clear_to_base(frame);
    over_blending();
    glUseProgram(composite_);
    glUniform1f(glGetUniformLocation(composite_, "u_opacity"), std::clamp(s.opacity, 0.001f, 1.0f));
    draw_fullscreen_composite(composite_, lines.vao(),
                              {{"u_opaque", opaque_target_.color[0]}, {"u_additive", additive_target_.color[0]}});
  }

 private:
  GLuint composite_ = 0;  // made on first use
  gl::RenderTarget opaque_target_, additive_target_;
};

}  // namespace

std::unique_ptr<ModePass> make_additive_pass() { return std::make_unique<AdditivePass>(); }

}  // namespace vxl
