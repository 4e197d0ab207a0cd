// The `wboit` mode: weighted blended order-independent transparency (McGuire & Bavoil): the lines'
// weighted colours summed in one target and their revealage multiplied in another, then composited over
// the base. Blends in no order: drawn whole by a frame's first piece.
#include "viewer/render/line_shaders.h"
#include "viewer/render/modes/blend_states.h"
#include "viewer/render/modes/fullscreen_composite.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"

namespace vxl {
namespace {

class WboitPass final : public ModePass {
 public:
  ~WboitPass() override {
    if (composite_) glDeleteProgram(composite_);
    target_.destroy();
  }
  RenderMode mode() const override { return RenderMode::Wboit; }
  void draw(PassHost& host, const FrameView& frame) override {
    if (!composite_) composite_ = gl::make_program(shaders::kFullscreenVertex, shaders::kWboitCompositeFragment);
    LinePass& lines = host.lines();
    target_.ensure(frame.width, frame.height, GL_RGBA16F, GL_RGBA16F, false);
    glBindFramebuffer(GL_FRAMEBUFFER, target_.fbo);
    glViewport(0, 0, frame.width, frame.height);
    const GLenum accum = GL_COLOR_ATTACHMENT0, reveal = GL_COLOR_ATTACHMENT1;
    glDrawBuffers(1, &accum);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    glEnable(GL_BLEND);
    glBlendFunc(GL_ONE, GL_ONE);
    draw_planned_lines(host, frame, lines.wboit_accum(), frame.settings, render_mode_info(mode()).plan_order);
    glDrawBuffers(1, &reveal);
    glClearColor(1, 1, 1, 1);
    glClear(GL_COLOR_BUFFER_BIT);
    glBlendFunc(GL_ZERO, GL_ONE_MINUS_SRC_COLOR);
    host.bind_lines(lines.wboit_reveal(), frame, frame.settings);
    lines.draw_plan(lines.wboit_reveal(), host.frame_plan().first, host.frame_plan().count);
    const GLenum both[2] = {accum, reveal};
    glDrawBuffers(2, both);
    host.clear_to_base(frame);
    over_blending();
    draw_fullscreen_composite(composite_, lines.vao(), {{"u_accum", target_.color[0]}, {"u_reveal", target_.color[1]}});
  }

 private:
  GLuint composite_ = 0;  // made on first use
  gl::RenderTarget target_;
};

}  // namespace

std::unique_ptr<ModePass> make_wboit_pass() { return std::make_unique<WboitPass>(); }

}  // namespace vxl
