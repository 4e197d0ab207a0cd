#include "viewer/render/gl_util.h"

#include <stdexcept>
#include <vector>

namespace vxl::gl {
namespace {

GLuint compile(GLenum type, const std::string& source) {
  GLuint s = glCreateShader(type);
  const char* src = source.c_str();
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<std::size_t>(len) + 1);
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error(std::string("shader compilation failed: ") + log.data());
  }
  return s;
}

GLuint link(std::initializer_list<GLuint> shaders) {
  GLuint p = glCreateProgram();
  for (GLuint s : shaders) glAttachShader(p, s);
  glLinkProgram(p);
  for (GLuint s : shaders) glDeleteShader(s);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &len);
    std::vector<char> log(static_cast<std::size_t>(len) + 1);
    glGetProgramInfoLog(p, len, nullptr, log.data());
    glDeleteProgram(p);
    throw std::runtime_error(std::string("program link failed: ") + log.data());
  }
  return p;
}

}  // namespace

GLuint make_program(const std::string& vs, const std::string& fs) {
  return link({compile(GL_VERTEX_SHADER, vs), compile(GL_FRAGMENT_SHADER, fs)});
}

GLuint make_compute_program(const std::string& cs) { return link({compile(GL_COMPUTE_SHADER, cs)}); }

void TextureBuffer::create(GLenum internal_format, const void* data, std::size_t bytes) {
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  // A zero-sized buffer texture is not portable: keep at least one texel.
  glBufferData(GL_TEXTURE_BUFFER, static_cast<GLsizeiptr>(bytes > 0 ? bytes : 16), bytes > 0 ? data : nullptr,
               GL_STATIC_DRAW);
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_BUFFER, texture);
  glTexBuffer(GL_TEXTURE_BUFFER, internal_format, buffer);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void* TextureBuffer::create_mapped(std::size_t bytes) {
  glGenBuffers(1, &buffer);
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  const auto size = static_cast<GLsizeiptr>(bytes > 16 ? bytes : 16);
  glBufferData(GL_TEXTURE_BUFFER, size, nullptr, GL_STATIC_DRAW);
  // Invalidated: the driver need not keep (or copy) what the buffer held.
  void* memory = glMapBufferRange(GL_TEXTURE_BUFFER, 0, size, GL_MAP_WRITE_BIT | GL_MAP_INVALIDATE_BUFFER_BIT);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
  if (memory == nullptr) {
    destroy();
    throw std::runtime_error("the driver could not map a buffer of " + std::to_string(size) + " bytes for writing");
  }
  return memory;
}

void TextureBuffer::finish_mapped(GLenum internal_format) {
  glBindBuffer(GL_TEXTURE_BUFFER, buffer);
  const GLboolean kept = glUnmapBuffer(GL_TEXTURE_BUFFER);
  if (kept == GL_FALSE) {
    glBindBuffer(GL_TEXTURE_BUFFER, 0);
    destroy();
    throw std::runtime_error("the driver lost a buffer's contents while it was being filled");
  }
  glGenTextures(1, &texture);
  glBindTexture(GL_TEXTURE_BUFFER, texture);
  glTexBuffer(GL_TEXTURE_BUFFER, internal_format, buffer);
  glBindTexture(GL_TEXTURE_BUFFER, 0);
  glBindBuffer(GL_TEXTURE_BUFFER, 0);
}

void TextureBuffer::destroy() {
  if (texture) glDeleteTextures(1, &texture);
  if (buffer) glDeleteBuffers(1, &buffer);
  texture = buffer = 0;
}

void RenderTarget::ensure(int w, int h, GLenum f0, GLenum f1, bool with_depth) {
  if (fbo && w == width && h == height) return;
  destroy();
  width = w;
  height = h;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  GLenum formats[2] = {f0, f1};
  GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  int n = f1 ? 2 : 1;
  for (int i = 0; i < n; ++i) {
    glGenTextures(1, &color[i]);
    glBindTexture(GL_TEXTURE_2D, color[i]);
    glTexImage2D(GL_TEXTURE_2D, 0, static_cast<GLint>(formats[i]), w, h, 0, GL_RGBA, GL_FLOAT, nullptr);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glFramebufferTexture2D(GL_FRAMEBUFFER, buffers[i], GL_TEXTURE_2D, color[i], 0);
  }
  glDrawBuffers(n, buffers);
  if (with_depth) {
    glGenRenderbuffers(1, &depth);
    glBindRenderbuffer(GL_RENDERBUFFER, depth);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, w, h);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
  }
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw std::runtime_error("incomplete framebuffer for a multipass transparency mode");
}

void RenderTarget::destroy() {
  if (fbo) glDeleteFramebuffers(1, &fbo);
  for (GLuint& c : color)
    if (c) glDeleteTextures(1, &c), c = 0;
  if (depth) glDeleteRenderbuffers(1, &depth);
  fbo = depth = 0;
  width = height = 0;
}

std::string version_string() {
  const char* v = reinterpret_cast<const char*>(glGetString(GL_VERSION));
  const char* r = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string(v ? v : "?") + " / " + (r ? r : "?");
}

}  // namespace vxl::gl
