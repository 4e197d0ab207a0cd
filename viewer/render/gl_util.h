// Small OpenGL helpers: shader programs, a fullscreen pass, texture-buffer objects. Need a current context.
#pragma once

#include <cstdint>
#include <string>

#include <epoxy/gl.h>

namespace vxl::gl {

// Compiles and links; throws std::runtime_error with the driver's log on failure.
GLuint make_program(const std::string& vertex_source, const std::string& fragment_source);
GLuint make_compute_program(const std::string& source);

// A buffer object with a buffer texture viewing it (internal format e.g. GL_R32F, GL_R32UI).
struct TextureBuffer {
  GLuint buffer = 0, texture = 0;
  void create(GLenum internal_format, const void* data, std::size_t bytes);
  // The same filled in place: create_mapped makes the buffer `bytes` long (at least 16) and returns its
  // memory mapped for writing, which any thread may fill; finish_mapped unmaps it and makes the texture.
  // Throws std::runtime_error when the driver cannot map or loses the contents.
  void* create_mapped(std::size_t bytes);
  void finish_mapped(GLenum internal_format);
  void destroy();
};

// RAII-free owner of a framebuffer with colour textures, for multipass modes.
struct RenderTarget {
  GLuint fbo = 0, color[2] = {0, 0}, depth = 0;
  int width = 0, height = 0;
  // Recreates when the size or formats change. color1_format 0 means a single colour attachment.
  void ensure(int w, int h, GLenum color0_format, GLenum color1_format, bool with_depth);
  void destroy();
};

std::string version_string();

}  // namespace vxl::gl
