#pragma once
// Off-screen render target: a framebuffer object with an RGBA8 colour buffer and a
// DEPTH24_STENCIL8 depth/stencil renderbuffer. Needs only a current OpenGL 3.3+ core context
// (no EGL, no window): it can serve a HeadlessGlContext as well as a GLFW window's context.
//
// samples == 0: colour is a GL_TEXTURE_2D (color_texture()), rendered to directly.
// samples  > 0: colour and depth are multisampled renderbuffers; resolve() (called by read_rgba())
//               blits them into the single-sample colour texture.
//
// GL objects belong to the context current at construction; destroy or resize the target with
// that context (or one sharing with it) current.

#include <cstdint>
#include <vector>

namespace vxl {

class OffscreenTarget {
public:
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
    // Colour as tightly packed RGBA8, width*height*4 bytes, rows top-to-bottom (GL's bottom-up
    // order flipped). Resolves first; leaves framebuffer bindings and pack state as it found them.
    std::vector<std::uint8_t> read_rgba() const;

    unsigned framebuffer() const { return fbo_; }          // the one bind() binds
    unsigned color_texture() const { return color_tex_; }  // single-sample colour (after resolve())

private:
    int width_ = 0, height_ = 0, samples_ = 0;
    unsigned fbo_ = 0;          // render FBO
    unsigned resolve_fbo_ = 0;  // single-sample FBO around color_tex_ (== fbo_ when samples_ == 0)
    unsigned color_tex_ = 0;
    unsigned color_rb_ = 0;     // multisampled colour (samples_ > 0)
    unsigned depth_rb_ = 0;

    void allocate();
    void release() noexcept;
};

}  // namespace vxl
