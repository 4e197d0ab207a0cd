// The `exact` mode: per-fragment sorted transparency, the reference every other mode is scored against.
//
// Pass 1 stores every line fragment (colour, depth) in per-pixel linked lists (a head image, a node
// buffer, an atomic counter). Pass 2, a compute shader, composites each pixel's fragments back to front.
// Lists of any length are resolved exactly: fragments are taken in batches of the farthest remaining
// ones (a bounded heap per batch), so no fragment is dropped. When the node buffer would overflow, the
// image is rendered in horizontal bands. A compute resolve is used because a fragment-shader resolve gave
// wrong pixels on llvmpipe 22.3 (BRIEF §3, pitfall 4). Needs OpenGL 4.3.
#pragma once

#include <cstdint>

#include "camera.h"
#include "gl_util.h"
#include "render_settings.h"

namespace vxl {

class Renderer;

class ExactRenderer {
 public:
  // node_capacity 0: as many 16-byte nodes as fit in min(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, 256 MiB).
  explicit ExactRenderer(Renderer& lines, std::uint64_t node_capacity = 0);
  ~ExactRenderer();
  void draw(const Camera& camera, const RenderSettings& settings, int width, int height, GLuint fbo);
  int bands_used() const { return bands_used_; }  // of the last frame
  std::uint64_t fragments() const { return fragments_; }

 private:
  Renderer& lines_;
  std::uint64_t capacity_ = 0;
  GLuint list_program_ = 0, clear_program_ = 0, resolve_program_ = 0, blit_program_ = 0;
  GLuint nodes_ = 0, counter_ = 0, heads_ = 0, result_ = 0;
  int width_ = 0, height_ = 0;
  int bands_used_ = 0;
  std::uint64_t fragments_ = 0;
};

}  // namespace vxl
