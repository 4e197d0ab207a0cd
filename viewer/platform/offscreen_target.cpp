#include "viewer/platform/offscreen_target.h"

#include <epoxy/gl.h>

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <utility>

#include "format/base/error.h"

namespace vxl {

namespace {

std::string hex(GLenum v) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%04X", static_cast<unsigned>(v));
  return buf;
}

// Saves and restores the framebuffer bindings touched by construction, resize and resolve.
struct FramebufferBindingGuard {
  GLint draw = 0, read = 0, rb = 0, tex = 0;
  FramebufferBindingGuard() {
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &draw);
    glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &read);
    glGetIntegerv(GL_RENDERBUFFER_BINDING, &rb);
    glGetIntegerv(GL_TEXTURE_BINDING_2D, &tex);
  }
  ~FramebufferBindingGuard() {
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(draw));
    glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(read));
    glBindRenderbuffer(GL_RENDERBUFFER, static_cast<GLuint>(rb));
    glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(tex));
  }
  FramebufferBindingGuard(const FramebufferBindingGuard&) = delete;
  FramebufferBindingGuard& operator=(const FramebufferBindingGuard&) = delete;
};

// Why the bound framebuffer cannot be drawn to, or "" when it can.
std::string incomplete(GLenum target, const char* which) {
  const GLenum status = glCheckFramebufferStatus(target);
  if (status == GL_FRAMEBUFFER_COMPLETE) return "";
  return std::string(which) + " framebuffer incomplete, status " + hex(status);
}

// Whether the driver says, without allocating it, that it can hold the colour buffer of a w x h picture (a
// proxy texture: a software driver caps a buffer's bytes, llvmpipe at 1 GiB, which no limit query tells).
bool driver_holds(int w, int h) {
  glTexImage2D(GL_PROXY_TEXTURE_2D, 0, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
  GLint held = 0;
  glGetTexLevelParameteriv(GL_PROXY_TEXTURE_2D, 0, GL_TEXTURE_WIDTH, &held);
  return held != 0;
}

// Clears stale error flags so that a later glGetError() reports our own calls (bounded: a lost
// context may keep reporting errors).
void drain_gl_errors() {
  for (int i = 0; i < 32 && glGetError() != GL_NO_ERROR; ++i) {
  }
}

}  // namespace

OffscreenTarget::OffscreenTarget(int width, int height, int samples)
    : width_(width), height_(height), samples_(samples) {
  if (samples < 0) throw std::invalid_argument("OffscreenTarget: negative sample count");
  if (samples > 0) {
    GLint max_samples = 0;
    glGetIntegerv(GL_MAX_SAMPLES, &max_samples);
    if (samples > max_samples)
      throw std::runtime_error("OffscreenTarget: " + std::to_string(samples) +
                               " samples requested, GL_MAX_SAMPLES is " + std::to_string(max_samples));
  }
  allocate();
}

OffscreenTarget::~OffscreenTarget() { release(); }

OffscreenTarget::OffscreenTarget(OffscreenTarget&& o) noexcept
    : width_(o.width_),
      height_(o.height_),
      samples_(o.samples_),
      fbo_(std::exchange(o.fbo_, 0)),
      resolve_fbo_(std::exchange(o.resolve_fbo_, 0)),
      color_tex_(std::exchange(o.color_tex_, 0)),
      color_rb_(std::exchange(o.color_rb_, 0)),
      depth_rb_(std::exchange(o.depth_rb_, 0)) {}

OffscreenTarget& OffscreenTarget::operator=(OffscreenTarget&& o) noexcept {
  if (this != &o) {
    release();
    width_ = o.width_;
    height_ = o.height_;
    samples_ = o.samples_;
    fbo_ = std::exchange(o.fbo_, 0);
    resolve_fbo_ = std::exchange(o.resolve_fbo_, 0);
    color_tex_ = std::exchange(o.color_tex_, 0);
    color_rb_ = std::exchange(o.color_rb_, 0);
    depth_rb_ = std::exchange(o.depth_rb_, 0);
  }
  return *this;
}

void OffscreenTarget::allocate() {
  if (width_ <= 0 || height_ <= 0)
    throw std::invalid_argument("OffscreenTarget: size must be positive, got " + std::to_string(width_) + "x" +
                                std::to_string(height_));
  const std::string size = "image size " + std::to_string(width_) + "x" + std::to_string(height_);
  GLint max_rb = 0, max_tex = 0, max_viewport[2] = {0, 0};
  glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &max_rb);
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_tex);
  glGetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
  const int limit = std::min({max_rb, max_tex, max_viewport[0], max_viewport[1]});
  if (width_ > limit || height_ > limit)
    throw Error(ErrorKind::Unsupported, size, std::nullopt,
                "beyond the GL driver's limit of " + std::to_string(limit) +
                    " pixels a side (GL_MAX_TEXTURE_SIZE, GL_MAX_RENDERBUFFER_SIZE, GL_MAX_VIEWPORT_DIMS)");
  // Drivers also cap a buffer's bytes (llvmpipe refuses the 2 GiB float colour buffer of 16384x8192): asked
  // first without allocating, else found by allocating; either way the largest size of this shape that
  // allocates is found, to say what can be drawn.
  const bool held = driver_holds(width_, height_);
  const std::string why = held ? try_allocate() : "the driver holds no float colour buffer this large";
  if (why.empty()) return;
  const int width = width_, height = height_;
  std::string largest = "none";
  for (double scale = 0.9; scale * std::max(width, height) >= 1; scale *= 0.9) {
    width_ = std::max(1, static_cast<int>(width * scale));
    height_ = std::max(1, static_cast<int>(height * scale));
    // Where the driver refused the size without allocating, the smaller ones are asked the same way.
    if (driver_holds(width_, height_) && (!held || try_allocate().empty())) {
      largest = std::to_string(width_) + "x" + std::to_string(height_);
      if (held) release();
      break;
    }
  }
  width_ = width, height_ = height;
  throw Error(ErrorKind::Unsupported, size, std::nullopt,
              "the GL driver cannot allocate a framebuffer this large (" + why +
                  "); the largest of this shape it allocates is " + largest);
}

std::string OffscreenTarget::try_allocate() {
  drain_gl_errors();
  FramebufferBindingGuard guard;
  std::string why;
  glGenTextures(1, &color_tex_);
  glBindTexture(GL_TEXTURE_2D, color_tex_);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, width_, height_, 0, GL_RGBA, GL_FLOAT, nullptr);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);

  glGenRenderbuffers(1, &depth_rb_);
  glBindRenderbuffer(GL_RENDERBUFFER, depth_rb_);
  if (samples_ > 0)
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_DEPTH24_STENCIL8, width_, height_);
  else
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH24_STENCIL8, width_, height_);

  if (samples_ > 0) {
    glGenRenderbuffers(1, &color_rb_);
    glBindRenderbuffer(GL_RENDERBUFFER, color_rb_);
    glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples_, GL_RGBA32F, width_, height_);

    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color_rb_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    why = incomplete(GL_FRAMEBUFFER, "multisampled");

    glGenFramebuffers(1, &resolve_fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, resolve_fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color_tex_, 0);
    if (why.empty()) why = incomplete(GL_FRAMEBUFFER, "resolve");
  } else {
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, color_tex_, 0);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, depth_rb_);
    why = incomplete(GL_FRAMEBUFFER, "render");
    resolve_fbo_ = fbo_;
  }
  const GLenum err = glGetError();
  if (why.empty() && err != GL_NO_ERROR)
    why = "GL error " + hex(err) + " allocating " + std::to_string(width_) + "x" + std::to_string(height_) +
          " (samples " + std::to_string(samples_) + ")";
  if (!why.empty()) release();
  return why;
}

void OffscreenTarget::release() noexcept {
  if (resolve_fbo_ != 0 && resolve_fbo_ != fbo_) glDeleteFramebuffers(1, &resolve_fbo_);
  if (fbo_ != 0) glDeleteFramebuffers(1, &fbo_);
  if (color_rb_ != 0) glDeleteRenderbuffers(1, &color_rb_);
  if (depth_rb_ != 0) glDeleteRenderbuffers(1, &depth_rb_);
  if (color_tex_ != 0) glDeleteTextures(1, &color_tex_);
  fbo_ = resolve_fbo_ = color_rb_ = depth_rb_ = color_tex_ = 0;
}

void OffscreenTarget::resize(int width, int height) {
  if (width == width_ && height == height_ && fbo_ != 0) return;
  release();
  width_ = width;
  height_ = height;
  allocate();
}

void OffscreenTarget::bind() const {
  glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
  glViewport(0, 0, width_, height_);
}

void OffscreenTarget::resolve() const {
  if (samples_ == 0) return;
  FramebufferBindingGuard guard;
  GLboolean scissor = glIsEnabled(GL_SCISSOR_TEST);
  if (scissor) glDisable(GL_SCISSOR_TEST);  // the scissor test applies to blits
  glBindFramebuffer(GL_READ_FRAMEBUFFER, fbo_);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, resolve_fbo_);
  glBlitFramebuffer(0, 0, width_, height_, 0, 0, width_, height_, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  if (scissor) glEnable(GL_SCISSOR_TEST);
}

std::vector<std::uint8_t> OffscreenTarget::read_rgba() const {
  resolve();
  const std::size_t row = static_cast<std::size_t>(width_) * 4;
  std::vector<std::uint8_t> pixels(row * static_cast<std::size_t>(height_));

  FramebufferBindingGuard guard;
  GLint pack_buffer = 0, alignment = 4, row_length = 0, skip_rows = 0, skip_pixels = 0;
  glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &pack_buffer);
  glGetIntegerv(GL_PACK_ALIGNMENT, &alignment);
  glGetIntegerv(GL_PACK_ROW_LENGTH, &row_length);
  glGetIntegerv(GL_PACK_SKIP_ROWS, &skip_rows);
  glGetIntegerv(GL_PACK_SKIP_PIXELS, &skip_pixels);
  GLint read_buffer = GL_COLOR_ATTACHMENT0;

  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);  // else glReadPixels would write into the buffer object
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glPixelStorei(GL_PACK_SKIP_ROWS, 0);
  glPixelStorei(GL_PACK_SKIP_PIXELS, 0);
  glBindFramebuffer(GL_READ_FRAMEBUFFER, resolve_fbo_);
  drain_gl_errors();
  glGetIntegerv(GL_READ_BUFFER, &read_buffer);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, width_, height_, GL_RGBA, GL_UNSIGNED_BYTE, pixels.data());
  const GLenum err = glGetError();
  glReadBuffer(static_cast<GLenum>(read_buffer));

  glBindBuffer(GL_PIXEL_PACK_BUFFER, static_cast<GLuint>(pack_buffer));
  glPixelStorei(GL_PACK_ALIGNMENT, alignment);
  glPixelStorei(GL_PACK_ROW_LENGTH, row_length);
  glPixelStorei(GL_PACK_SKIP_ROWS, skip_rows);
  glPixelStorei(GL_PACK_SKIP_PIXELS, skip_pixels);
  if (err != GL_NO_ERROR) throw std::runtime_error("OffscreenTarget: glReadPixels failed with GL error " + hex(err));

  // GL rows run bottom-up; callers get top-down.
  std::vector<std::uint8_t> tmp(row);
  for (int y = 0; y < height_ / 2; ++y) {
    std::uint8_t* a = pixels.data() + static_cast<std::size_t>(y) * row;
    std::uint8_t* b = pixels.data() + static_cast<std::size_t>(height_ - 1 - y) * row;
    std::memcpy(tmp.data(), a, row);
    std::memcpy(a, b, row);
    std::memcpy(b, tmp.data(), row);
  }
  return pixels;
}

}  // namespace vxl
