#pragma once
// Off-screen render target: a framebuffer object with an RGBA32F colour buffer and a
// DEPTH24_STENCIL8 depth/stencil renderbuffer.
//
// Why float colour: transparent lines are blended one layer over another thousands of times. In an
// 8-bit buffer every blend rounds to 1/255, so at opacity 0.01 a pixel stops brightening once one layer
// adds less than half a level (a white stack stalls near 205 of 255). Half floats still fell short
// (300 layers at 0.01: 236 instead of 242.5 on llvmpipe); 32-bit floats match the CPU compositing, and
// the image is rounded to 8 bits once, on read-back. Needs only a current OpenGL 3.3+ core context
// (no EGL, no window): it can serve a HeadlessGlContext as well as a GLFW window's context.
//
// samples == 0: colour is a GL_TEXTURE_2D (color_texture()), rendered to directly.
// samples  > 0: colour and depth are multisampled renderbuffers; resolve() (called by read_rgba())
//               blits them into the single-sample colour texture.
//
// GL objects belong to the context current at construction; destroy or resize the target with
// that context (or one sharing with it) current.

#include <cstdint>
#include <string>
#include <vector>

namespace vxl {

class OffscreenTarget {
 public:
  // Throws vxl::Error (Unsupported) when the driver cannot hold a framebuffer of this size: beyond its
  // per-side limits (the message gives them), or beyond what it allocates (the message gives the largest
  // size of this shape it does).
  OffscreenTarget(int width, int height, int samples = 0);
  ~OffscreenTarget();
  OffscreenTarget(const OffscreenTarget&) = delete;
  OffscreenTarget& operator=(const OffscreenTarget&) = delete;
  OffscreenTarget(OffscreenTarget&& other) noexcept;
  OffscreenTarget& operator=(OffscreenTarget&& other) noexcept;

  // Binds the render framebuffer (GL_FRAMEBUFFER: draw and read) and sets the viewport to the
  // full target.
  void bind() const;
  // Reallocates all buffers (contents undefined afterwards). Keeps the sample count.
  void resize(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  int samples() const { return samples_; }

  // Multisampled: blit colour into the single-sample texture. No-op otherwise.
  // Restores the framebuffer bindings it changes.
  void resolve() const;
  // Colour converted to tightly packed RGBA8 (clamped, rounded once), width*height*4 bytes, rows top-to-bottom (GL's
  // bottom-up order flipped). Resolves first; leaves framebuffer bindings and pack state as it found them.
  std::vector<std::uint8_t> read_rgba() const;

  unsigned framebuffer() const { return fbo_; }          // the one bind() binds
  unsigned color_texture() const { return color_tex_; }  // single-sample colour (after resolve())

 private:
  int width_ = 0, height_ = 0, samples_ = 0;
  unsigned fbo_ = 0;          // render FBO
  unsigned resolve_fbo_ = 0;  // single-sample FBO around color_tex_ (== fbo_ when samples_ == 0)
  unsigned color_tex_ = 0;
  unsigned color_rb_ = 0;  // multisampled colour (samples_ > 0)
  unsigned depth_rb_ = 0;

  void allocate();
  std::string try_allocate();  // "" when every buffer was made, else why not (and nothing is held)
  void release() noexcept;
};

}  // namespace vxl
