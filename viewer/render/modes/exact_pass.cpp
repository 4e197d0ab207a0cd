// The `exact` mode (exact_renderer.h): per-fragment sorted transparency, composited on the CPU; drawn in
// pieces as runs of voxels composited one after another.
#include "viewer/render/exact_renderer.h"
#include "viewer/render/modes/mode_pass.h"
#include "viewer/render/modes/mode_table.h"

namespace vxl {
namespace {

class ExactPass final : public ModePass {
 public:
  RenderMode mode() const override { return RenderMode::Exact; }
  void draw(PassHost& host, const FrameView& frame) override {
    ExactRenderer& exact = renderer(host);
    host.base_for_exact(frame);
    exact.draw(frame.camera, frame.settings, frame.width, frame.height, frame.fbo);
  }
  PieceKind piece_kind() const override { return PieceKind::Own; }
  void begin(PassHost& host, const FrameView& frame) override {
    ExactRenderer& exact = renderer(host);
    host.base_for_exact(frame);
    exact.begin(frame.camera, frame.settings, frame.width, frame.height, frame.fbo);
  }
  bool step(double max_ms) override { return exact_->step(max_ms); }
  double progress() const override { return exact_ ? exact_->progress() : 0.0; }

 private:
  // Made on first use: it needs OpenGL 4.3, and throws on a context without it.
  ExactRenderer& renderer(PassHost& host) {
    if (!exact_) exact_ = std::make_unique<ExactRenderer>(host);
    return *exact_;
  }
  std::unique_ptr<ExactRenderer> exact_;
};

}  // namespace

std::unique_ptr<ModePass> make_exact_pass() { return std::make_unique<ExactPass>(); }

}  // namespace vxl
